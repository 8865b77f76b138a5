"""The ``attitude`` command.

Subcommands live in modules of this package; each module defines
``register(subparsers)`` that adds its parsers and sets ``func`` (a
callable taking the parsed ``argparse.Namespace`` and returning an exit
code). Add the module to ``_MODULES`` to add its subcommands.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from . import ahrs, demo, link, simulate, view


class _VersionAction(argparse.Action):
    """``--version``: print the version (resolved only when asked for)."""

    def __init__(self, option_strings: Sequence[str], dest: str = argparse.SUPPRESS,
                 default: str = argparse.SUPPRESS, help: str = "show the version and exit") -> None:
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: object, option_string: str | None = None) -> None:
        import attitude_c

        parser.exit(message=f"{parser.prog} {attitude_c.__version__}\n")

# The subcommand modules, in the order their commands are listed.
_MODULES = (simulate, link, demo, view, ahrs)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="attitude",
        description="libattitude: strapdown attitude measurement tools "
        "(simulation, serial link, analysis).",
    )
    parser.add_argument("--version", action=_VersionAction)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for mod in _MODULES:
        mod.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    func = getattr(args, "func", None)
    if func is None:
        parser.print_help(sys.stderr)
        return 2
    try:
        return int(func(args) or 0)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
