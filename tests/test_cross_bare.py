"""Every C test program of the library (csrc/tests/test_*.c) on the emulated
ARMv4T core: built for `armv4t-bare` (arm-none-eabi-gcc -mcpu=arm920t, newlib
semihosting, soft float), run by `qemu-arm -cpu ti925t`, double and float.

The ti925t model executes only ARMv4T: a single ARMv5 instruction anywhere in
the program (library, newlib, test code) would stop it with SIGILL, so a pass
is also proof that the library runs on an ARM920T. Each program must end with
its "N passed, 0 failed" line.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import ROOT, require_target

pytestmark = pytest.mark.system  # builds and runs ARMv4T bare-metal targets under qemu

C_TESTS = sorted((ROOT / "csrc" / "tests").glob("test_*.c"))
# test_integrator's long runs (10^6 updates) take ~30 s per build on the emulated core: run it
# in float only (the soft-float build the ARM920T cares about); the double integrator is
# covered on this core by the test vectors (tests/test_vectors.py). Keeps this file ~1 min.
CASES = [(src, prec) for src in C_TESTS for prec in ("f64", "f32")
         if not (src.stem == "test_integrator" and prec == "f64")]


@pytest.mark.qemu
@pytest.mark.parametrize(("src", "precision"), CASES, ids=[f"{s.stem}-{p}" for s, p in CASES])
def test_c_program_on_armv4t_core(src: Path, precision: str, build_root: Path) -> None:
    t = require_target("armv4t-bare")
    exe = t.build_program([src], build_root / "armv4t-bare" / precision / src.stem,
                          defines=["ATT_REAL_F32"] if precision == "f32" else [],
                          include_dirs=[ROOT / "csrc" / "host", ROOT / "csrc" / "tests"],
                          lib_sources=sorted((ROOT / "csrc" / "src").glob("*.c"))
                          + sorted((ROOT / "csrc" / "host").glob("*.c")))
    proc = t.run([exe], timeout=600, check=False)
    out = proc.stdout.decode(errors="replace")
    err = proc.stderr.decode(errors="replace")
    assert proc.returncode == 0, \
        f"{src.name} on qemu-arm -cpu ti925t failed ({proc.returncode}):\n{out[-3000:]}\n{err}"
    lines = out.strip().splitlines()
    assert lines and lines[-1].endswith(" 0 failed"), out[-3000:]
