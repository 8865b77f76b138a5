"""Shared s51 (uCsim 8051 simulator) harness: build an SDCC program, run it, read its output.

Used by the TLC2543 driver tests/benchmark, the firmware and the fixed-point
engineers. Typical use::

    from toolchain import s51
    ihx = s51.build(["csrc/tests/s51_foo.c"], build_dir / "foo",
                    lib_sources=["csrc/src/tlc2543.c"])
    res = s51.run(ihx)             # raises S51Error if it did not stop cleanly
    assert res.exit_code == 0
    print(res.output)              # text the program wrote
    res.cycles["scan"]             # from s51_report_cycles("scan")

The C side (``toolchain/s51_sif.h`` / ``s51_sif.c``, linked in automatically):

* ``s51_putc/s51_puts/s51_putu/s51_puthex`` write text to the simulator
  interface output file (uCsim simif command ``'w'`` on SFR 0xFF),
* ``S51_CYCLES_BEGIN(); ...; S51_CYCLES_END(); s51_report_cycles("x");`` times a
  region in 8051 machine cycles with Timer 0 (the instruction that stops the
  timer is subtracted, so an empty region reads 0; 16-bit, max 65534),
* ``s51_exit(code)`` prints ``EXIT <code>`` and writes simif command ``'s'``
  (stop), which makes ``s51 -G`` exit. This is the deterministic stop.

How s51 is run: ``s51 -t C51 -R 1 -I if=sfr[0xff],out=<file> -S in=<file>,out=<file>
-G <ihx>`` under a wall-clock timeout. ``-G`` ("go, quit on stop") is used rather
than a ``-C`` command file with ``run``: uCsim executes ``-C`` commands *before*
it loads the image, so ``run`` would start an empty code memory. ``-C`` files
can still be passed (``commands=``) for inspection (e.g. ``state``) — they then
run before the program. s51 always exits with status 0, so success is judged by
the program's own ``EXIT <code>`` line: no such line (runaway program,
simulator error) raises :class:`S51Error`; a wall-clock timeout raises
:class:`S51Timeout`. The UART (serial 0) is connected to files too: pass
``uart_input`` bytes, read ``S51Result.uart`` bytes.

The target definition (compiler, flags: small model, 128 B IRAM, no XRAM, 4 KB
code) comes from ``toolchain/mcs51.toml``. Only the library sources you list
are linked (the whole library does not fit an AT89S51).
"""

from __future__ import annotations

import re
import subprocess
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from . import targets

HERE = Path(__file__).resolve().parent
SIF_SOURCE = HERE / "s51_sif.c"
SIF_HEADER = HERE / "s51_sif.h"
#: Address of the uCsim simulator interface (an unused SFR of the 8051).
SIF_ARG = "if=sfr[0xff]"

_EXIT_RE = re.compile(r"^EXIT (\d+)$", re.MULTILINE)
_CYC_RE = re.compile(r"^CYCLES (\S+) (\d+|overflow)$", re.MULTILINE)


class S51Error(RuntimeError):
    """The simulated program did not finish through ``s51_exit`` (or s51 failed)."""


class S51BuildError(S51Error):
    """SDCC rejected a source (any warning is an error); ``stderr`` holds its messages."""

    def __init__(self, message: str, stderr: str) -> None:
        super().__init__(message)
        self.stderr = stderr


class S51Timeout(S51Error, TimeoutError):
    """s51 did not exit within the wall-clock timeout (program never stopped)."""


@dataclass
class S51Result:
    """What one s51 run produced."""

    output: str  #: text written through the simulator interface (s51_putc...)
    exit_code: int  #: the code passed to s51_exit()
    cycles: dict[str, int] = field(default_factory=dict)  #: label -> machine cycles
    uart: bytes = b""  #: bytes the program sent on UART 0
    console: str = ""  #: raw s51 console text (banner, warnings, command output)

    @property
    def lines(self) -> list[str]:
        return self.output.splitlines()


def target() -> targets.Target:
    """The mcs51 target; raises targets.ToolchainMissing if sdcc/s51 are absent."""
    t = targets.load("mcs51")
    t.require()
    return t


def available() -> bool:
    """True when sdcc and s51 are both installed."""
    return not targets.load("mcs51").missing_tools()


def build(sources: Sequence[Path | str], out: Path | str, *,
          lib_sources: Iterable[Path | str] = (), defines: Sequence[str] = (),
          include_dirs: Sequence[Path | str] = (), extra_cflags: Sequence[str] = (),
          with_sif: bool = True) -> Path:
    """Compile ``sources`` (main file first) + ``lib_sources`` with SDCC into an .ihx.

    Flags are those of toolchain/mcs51.toml (``--Werror``: any warning fails the
    build with :class:`S51BuildError`, whose message and ``stderr`` hold SDCC's
    messages). ``with_sif`` links the s51_sif helpers and puts
    toolchain/ on the include path. Returns the path of the .ihx image.
    """
    t = target()
    srcs = [Path(s) for s in sources] + [Path(s) for s in lib_sources]
    if with_sif:
        srcs.append(SIF_SOURCE)
    incs = [*include_dirs, HERE] if with_sif else list(include_dirs)
    try:
        return t.build_program(srcs, out, defines=defines, extra_cflags=extra_cflags,
                               include_dirs=incs, with_lib=False)
    except subprocess.CalledProcessError as exc:
        err = (exc.stderr or "") + (exc.stdout or "")
        raise S51BuildError(f"SDCC failed: {' '.join(map(str, exc.cmd))}\n{err}", err) from None


def run(ihx: Path | str, *, timeout: float = 30.0, uart_input: bytes = b"",
        commands: Sequence[str] = (), check: bool = True, cpu: str | None = None) -> S51Result:
    """Run ``ihx`` in s51 (C51 core) until it calls ``s51_exit``.

    ``timeout`` is wall-clock seconds (s51 simulates several million machine
    cycles per second). ``commands`` are uCsim console commands executed
    before the program starts. ``cpu`` overrides the simulated core type (``-t``,
    default C51 from mcs51.toml; "8052" has 256 bytes of internal RAM). With
    ``check`` (default) a missing ``EXIT`` line
    raises :class:`S51Error`; without it ``exit_code`` is -1 in that case.
    """
    t = target()
    with tempfile.TemporaryDirectory(prefix="s51_") as tmp:
        d = Path(tmp)
        sif_out, uart_in, uart_out = d / "sif.out", d / "uart.in", d / "uart.out"
        uart_in.write_bytes(uart_input)
        run_cmd = list(t.run_cmd)
        if cpu is not None:  # e.g. "8052": 256 bytes of internal RAM (AT89S52)
            run_cmd[run_cmd.index("-t") + 1] = cpu
        cmd = [*run_cmd, "-R", "1", "-I", f"{SIF_ARG},out={sif_out}",
               "-S", f"in={uart_in},out={uart_out}", "-G"]
        if commands:
            cfile = d / "cmds"
            cfile.write_text("\n".join(commands) + "\n")
            cmd += ["-C", str(cfile)]
        cmd.append(str(ihx))
        # stdin stays an open, silent pipe: on end-of-file of its console
        # (e.g. stdin=/dev/null) s51 -G quits at its next console poll, which
        # would cut the program short at a random point.
        con_path = d / "console.txt"
        with open(con_path, "wb") as con:
            proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=con,
                                    stderr=subprocess.STDOUT)
            try:
                rc = proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
                partial = sif_out.read_text(errors="replace") if sif_out.exists() else ""
                raise S51Timeout(f"s51 still running after {timeout} s on {ihx} "
                                 f"(program never called s51_exit?); output so far:\n"
                                 f"{partial}") from None
            finally:
                assert proc.stdin is not None
                proc.stdin.close()
        output = sif_out.read_text(errors="replace") if sif_out.exists() else ""
        uart = uart_out.read_bytes() if uart_out.exists() else b""
        console = con_path.read_text(errors="replace")
    m = _EXIT_RE.search(output)
    if m is None:
        if check:
            raise S51Error(f"{ihx}: program stopped without s51_exit (s51 rc {rc});\n"
                           f"output:\n{output}\nconsole:\n{console}")
        code = -1
    else:
        code = int(m.group(1))
    cycles: dict[str, int] = {}
    for label, val in _CYC_RE.findall(output):
        if val == "overflow":
            raise S51Error(f"{ihx}: cycle region {label!r} overflowed the 16-bit timer")
        cycles[label] = int(val)
    return S51Result(output=output, exit_code=code, cycles=cycles, uart=uart, console=console)


def build_and_run(sources: Sequence[Path | str], out: Path | str, *,
                  lib_sources: Iterable[Path | str] = (), defines: Sequence[str] = (),
                  include_dirs: Sequence[Path | str] = (), timeout: float = 30.0,
                  uart_input: bytes = b"") -> S51Result:
    """:func:`build` then :func:`run`."""
    ihx = build(sources, out, lib_sources=lib_sources, defines=defines,
                include_dirs=include_dirs)
    return run(ihx, timeout=timeout, uart_input=uart_input)
