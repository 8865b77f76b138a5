"""The ``attitude`` command.

Subcommands live in modules of this package; each module defines
``register(subparsers)`` that adds its parsers and sets ``func`` (a
callable taking the parsed ``argparse.Namespace`` and returning an exit
code). Add the module to ``_MODULES`` to add its subcommands.

What every subcommand guarantees (docs/cli.md): a user mistake or an OS
error is one line on stderr and an exit status of the table below, never a
traceback; a closed stdout (``attitude link-rx ... | head -1``) ends the
command quietly, as Unix tools do; numeric options go through one
validator (:mod:`attitude_c.cli.options`); result files are written
complete or not at all (:mod:`attitude_c._io`).
"""

from __future__ import annotations

import argparse
import errno
import os
import re
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

from . import ahrs, allan, calibrate, demo, link, simulate, sweep, view


class _VersionAction(argparse.Action):
    """``--version``: print the version (resolved only when asked for)."""

    def __init__(self, option_strings: Sequence[str], dest: str = argparse.SUPPRESS,
                 default: str = argparse.SUPPRESS, help: str = "show the version and exit") -> None:
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: object, option_string: str | None = None) -> None:
        import attitude_c

        parser.exit(message=f"{parser.prog} {attitude_c.__version__}\n")

#: Exit statuses shared by every subcommand (docs/cli.md; commands add their own
#: from 3 up: link-tx 3 and 4, view 3).
EXIT_OK = 0
EXIT_OS = 1  # an OS error: a file, directory, device or port cannot be opened, read or written
EXIT_USAGE = 2  # a bad option, option value or input line
EXIT_INTERRUPTED = 130  # SIGINT (128 + 2)
EXIT_PIPE = 141  # stdout closed by its reader (128 + SIGPIPE), ended quietly


class _Parser(argparse.ArgumentParser):
    """argparse with one-line usage errors ("PROG: error: MESSAGE (see PROG --help)")."""

    def error(self, message: str) -> NoReturn:
        m = re.match(r"argument ([^:]+): (-[\w-]+): ", message)
        if m and m.group(2) in m.group(1).split("/"):  # the validators name the option too
            message = f"argument {m.group(1)}: " + message[m.end():]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def fail(prog: str, message: str, code: int) -> int:
    """Report a failure as its one line "PROG: error: MESSAGE" on stderr; return
    ``code``, the exit status (``return fail(prog, ..., EXIT_USAGE)``)."""
    print(f"{prog}: error: {message}", file=sys.stderr)
    return code


def os_error_line(exc: OSError) -> str:
    """One line for an OS error: what failed (the file when known) and why."""
    why = exc.strerror or str(exc) or type(exc).__name__
    if exc.filename is not None:
        return f"{os.fsdecode(exc.filename)}: {why}"
    return why


def _quiet_stdout(stream: Any) -> None:
    """stdout cannot be written (reader gone, disk full): point its descriptor
    at /dev/null so that the flush at exit finds somewhere to go (Python
    docs, "Note on SIGPIPE") instead of printing a second error."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, stream.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):  # stdout without a descriptor (tests): nothing to flush
        pass


# The subcommand modules, in the order their commands are listed.
_MODULES = (simulate, sweep, link, demo, view, ahrs, allan, calibrate)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="attitude",
        description="libattitude: strapdown attitude measurement tools "
        "(simulation, serial link, analysis).",
    )
    parser.add_argument("--version", action=_VersionAction)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for mod in _MODULES:
        mod.register(sub)
    return parser


class _WatchedStdout:
    """sys.stdout while a command runs: remembers the OSError of a failed
    write, so that main() tells a closed or full stdout from other errors."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream
        self.failed: OSError | None = None

    def write(self, text: str) -> int:
        try:
            return int(self._stream.write(text))
        except OSError as exc:
            self.failed = exc
            raise

    def flush(self) -> None:
        try:
            self._stream.flush()
        except OSError as exc:
            self.failed = exc
            raise

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    func = getattr(args, "func", None)
    if func is None:
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    prog = f"attitude {args.command}"
    real_stdout = sys.stdout
    watched = _WatchedStdout(real_stdout)
    sys.stdout = watched  # type: ignore[assignment]
    try:
        rc = int(func(args) or 0)
        sys.stdout.flush()  # here, not at exit: a failing flush is reported like any write
        return rc
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except OSError as exc:
        on_stdout = exc is watched.failed or isinstance(exc, BrokenPipeError) and exc.filename is None
        if on_stdout and exc.errno == errno.EPIPE:
            _quiet_stdout(real_stdout)  # the reader is gone (| head): end quietly, as Unix tools do
            return EXIT_PIPE
        where = " (writing standard output)" if on_stdout else ""
        print(f"{prog}: error: {os_error_line(exc)}{where}", file=sys.stderr)
        if on_stdout:
            _quiet_stdout(real_stdout)
        return EXIT_OS
    finally:
        sys.stdout = real_stdout
