"""The library exports its public API only (issue 31, item 5).

libattitude.so is built with -fvisibility=hidden by every build path (invoke
cross-build, make, CMake), and the public headers open their declarations
with ATT_API_BEGIN (attitude/common.h): a symbol is exported only when a
public header declares it. Internals shared between sources are named
``att__MODULE_NAME`` (docs/conventions.md, "Names"), so an internal that
leaks is recognisable by name. The Python extensions embed the library with
ATT_NO_EXPORT and export their PyInit function only."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest
from conftest import ROOT, require_target, require_tools

from toolchain.tasks.cross import cross_build_target

pytestmark = pytest.mark.system  # builds the library, runs nm

PUBLIC_HEADERS = [*sorted((ROOT / "csrc" / "include" / "attitude").glob("*.h")),
                  *sorted((ROOT / "csrc" / "platform").glob("*/include/attitude/*.h"))]
INTERNAL = re.compile(r"att__\w+")


def _public_names() -> set[str]:
    """Every identifier the public headers declare, comments removed."""
    text = "\n".join(h.read_text() for h in PUBLIC_HEADERS)
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.DOTALL)
    return set(re.findall(r"\b[A-Za-z_]\w*\b", text))


def _symbols(nm: str, path: Path, *flags: str) -> set[str]:
    """The defined global symbols nm lists (name only)."""
    out = subprocess.run([nm, "--defined-only", "-g", *flags, str(path)], capture_output=True, text=True,
                         check=True).stdout
    return {f[2] for f in (ln.split() for ln in out.splitlines()) if len(f) == 3 and f[1] in "TDBR"}


def _build(path: str, tmp_path: Path) -> Path:
    """libattitude.so (host) from one build path; returns the build folder."""
    if path == "invoke":
        require_target("host")
        cross_build_target("host", out=tmp_path / "invoke")
        return tmp_path / "invoke"
    require_tools("make", "cmake", apt="make cmake")
    if path == "make":
        cmd = ["make", "-j2", "APP=0", f"BUILDDIR={tmp_path / 'make'}"]
        subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=True)
        return tmp_path / "make"
    bdir = tmp_path / "cmake"
    subprocess.run(["cmake", "-S", str(ROOT), "-B", str(bdir), "-DATT_BUILD_APP=OFF"], capture_output=True,
                   text=True, check=True)
    subprocess.run(["cmake", "--build", str(bdir), "-j2"], capture_output=True, text=True, check=True)
    return bdir


@pytest.mark.parametrize("path", ["invoke", "make", "cmake"])
def test_shared_library_exports_the_public_headers_only(path: str, tmp_path: Path) -> None:
    """Every symbol libattitude.so exports is declared in a public header, none
    is an internal (att__*); the hidden ones exist (the static library has
    them) and follow the internal naming style."""
    out = _build(path, tmp_path)
    exported = _symbols("nm", out / "libattitude.so", "-D")
    assert exported, "libattitude.so exports nothing"
    assert sorted(exported - _public_names()) == [], "exported but in no public header"
    assert sorted(filter(INTERNAL.fullmatch, exported)) == []
    hidden = _symbols("nm", out / "libattitude.a") - exported
    assert "att__wden_select" in hidden and "att__fx_apply" in hidden  # the internals are there
    assert sorted(s for s in hidden if not INTERNAL.fullmatch(s)) == [], "internal names: att__MODULE_NAME"


def test_python_extensions_export_only_their_init() -> None:
    """The CFFI modules (the library embedded, ATT_NO_EXPORT) export PyInit_* only."""
    require_tools("nm", apt="binutils")
    mods = sorted((ROOT / "attitude_c").glob("_att_*.so"))
    assert mods, "no attitude_c/_att_*.so: python3 setup.py build_ext --inplace"
    for mod in mods:
        assert _symbols("nm", mod, "-D") == {f"PyInit_{mod.name.split('.')[0]}"}, mod.name
