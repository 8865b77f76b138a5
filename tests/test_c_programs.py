"""Run the library's own C test programs (csrc/tests/test_*.c) on the host.

Each program is built with the whole library under AddressSanitizer and
UndefinedBehaviorSanitizer, once with gcc and once with clang, with
-std=c99 -Wall -Wextra -Wpedantic -Werror, and must print its
"N passed, 0 failed" line. Programs whose name ends in ``_f32`` are also
the float build of the library (-DATT_REAL_F32).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import ROOT, require_target

C_TESTS = sorted((ROOT / "csrc" / "tests").glob("test_*.c"))


@pytest.mark.parametrize("target", ["host-asan", "host-clang"])
@pytest.mark.parametrize("precision", ["f64", "f32"])
@pytest.mark.parametrize("src", C_TESTS, ids=[p.stem for p in C_TESTS])
def test_c_program(src: Path, target: str, precision: str, build_root: Path) -> None:
    t = require_target(target)
    defines = ["ATT_REAL_F32"] if precision == "f32" else []
    exe = t.build_program([src], build_root / target / precision / src.stem,
                          defines=defines, include_dirs=[ROOT / "csrc" / "host", ROOT / "csrc" / "tests"],
                          lib_sources=sorted((ROOT / "csrc" / "src").glob("*.c"))
                          + sorted((ROOT / "csrc" / "host").glob("*.c")))
    proc = t.run([exe], timeout=300, check=False)
    out = proc.stdout.decode(errors="replace")
    err = proc.stderr.decode(errors="replace")
    assert proc.returncode == 0, f"{src.name} failed:\n{out}\n{err}"
    last = out.strip().splitlines()[-1]
    assert last.endswith(" 0 failed"), out
