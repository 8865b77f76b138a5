"""Self-test of the shared s51 harness (toolchain/s51.py).

Checks the deterministic stop (EXIT line), text output through the simulator
interface, exact machine-cycle counts of known instruction sequences, the
UART files, and that a runaway program ends in S51Timeout instead of a hang.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import ROOT, require_target

from toolchain import s51

pytestmark = pytest.mark.system  # runs s51

HERE = ROOT / "tests" / "s51"


@pytest.fixture(scope="module")
def selftest(build_root: Path) -> s51.S51Result:
    require_target("mcs51")
    ihx = s51.build([HERE / "harness_selftest.c"], build_root / "s51" / "selftest")
    return s51.run(ihx, uart_input=b"abc xyz\n", timeout=30)


def test_output_and_exit(selftest: s51.S51Result) -> None:
    assert selftest.exit_code == 3
    assert selftest.lines[0] == "hello 8051"
    assert selftest.lines[1] == "4000000000 BEEF"


def test_cycle_counts_are_exact(selftest: s51.S51Result) -> None:
    # 8051 datasheet timings: NOP = 1 machine cycle, MOV Rn,#d = 1, DJNZ = 2;
    # 100 x (NOP + DJNZ) + MOV = 301.
    assert selftest.cycles == {"empty": 0, "ten_nops": 10, "nop_djnz100": 301}


def test_uart_in_and_out(selftest: s51.S51Result) -> None:
    assert selftest.uart == b"ABC XYZ\n"


def test_runaway_program_times_out(build_root: Path) -> None:
    require_target("mcs51")
    ihx = s51.build([HERE / "harness_runaway.c"], build_root / "s51" / "runaway")
    with pytest.raises(s51.S51Timeout, match="spinning"):
        s51.run(ihx, timeout=1.0)


def test_warning_fails_the_build(build_root: Path, tmp_path: Path) -> None:
    require_target("mcs51")
    bad = tmp_path / "bad.c"
    bad.write_text("void main(void) { int x; x = 1; return; x = 2; }\n")
    with pytest.raises(s51.S51BuildError) as info:
        s51.build([bad], build_root / "s51" / "bad")
    assert "unreachable" in info.value.stderr

