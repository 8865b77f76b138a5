"""Run the library's own C test programs (csrc/tests/test_*.c) on the host.

Each program is built with the whole library under AddressSanitizer and
UndefinedBehaviorSanitizer, once with gcc and once with clang, with
-std=c99 -Wall -Wextra -Wpedantic -Werror, and must print its
"N passed, 0 failed" line. Every program runs against the double and the
float build of the library (-DATT_REAL_F32). The library (csrc/src and the
host twins in csrc/host) is compiled once per target and precision in each
test worker, into a static archive the programs link against: the same
flags as compiling it with each program, at a fraction of the time.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from conftest import ROOT, require_target

pytestmark = pytest.mark.system  # builds and runs the C test programs (sanitizers, every compiler)

C_TESTS = sorted((ROOT / "csrc" / "tests").glob("test_*.c"))
INCLUDE_DIRS = [ROOT / "csrc" / "host", ROOT / "csrc" / "tests"]
_ARCHIVES: dict[tuple[str, str], Path] = {}


def _library(t, precision: str, defines: list[str], build_root: Path) -> Path:
    """libattitude (+ the host twins) for target t, compiled once per worker."""
    key = (t.name, precision)
    if key not in _ARCHIVES:
        d = build_root / t.name / precision / "_lib"
        d.mkdir(parents=True, exist_ok=True)
        srcs = sorted((ROOT / "csrc" / "src").glob("*.c")) + sorted((ROOT / "csrc" / "host").glob("*.c"))
        incs = [f"-I{x}" for x in (ROOT / "csrc" / "include", *INCLUDE_DIRS)]
        cmd = [t.cc, *t.cflags, *incs, *[f"-D{x}" for x in defines], "-c", *map(str, srcs)]
        proc = subprocess.run(cmd, cwd=d, capture_output=True, text=True, check=False)
        assert proc.returncode == 0, f"library build failed ({t.name}, {precision}):\n{proc.stderr}"
        lib = d / "libattitude_test.a"
        subprocess.run([t.ar, "rcs", str(lib), *sorted(map(str, d.glob("*.o")))], check=True)
        _ARCHIVES[key] = lib
    return _ARCHIVES[key]


@pytest.mark.parametrize("target", ["host-asan", "host-clang"])
@pytest.mark.parametrize("precision", ["f64", "f32"])
@pytest.mark.parametrize("src", C_TESTS, ids=[p.stem for p in C_TESTS])
def test_c_program(src: Path, target: str, precision: str, build_root: Path) -> None:
    t = require_target(target)
    defines = ["ATT_REAL_F32"] if precision == "f32" else []
    lib = _library(t, precision, defines, build_root)
    exe = t.build_program([src, lib], build_root / target / precision / src.stem,
                          defines=defines, include_dirs=INCLUDE_DIRS, with_lib=False)
    proc = t.run([exe], timeout=300, check=False)
    out = proc.stdout.decode(errors="replace")
    err = proc.stderr.decode(errors="replace")
    assert proc.returncode == 0, f"{src.name} failed:\n{out}\n{err}"
    last = out.strip().splitlines()[-1]
    assert last.endswith(" 0 failed"), out
