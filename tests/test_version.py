"""One version: csrc/include/attitude/version.h is its only source, and the
Python package (at run time and in its distribution metadata), the compiled
libraries (f64 and f32), CMake, the Makefile and `invoke cross-build` all
give the same MAJOR.MINOR.PATCH and soname."""

from __future__ import annotations

import os
import re
import subprocess
from importlib import metadata
from pathlib import Path

import pytest
from conftest import ROOT, require_tools

import attitude_c
from attitude_c._build import version as V
from attitude_c._lib import ffi_lib

HEADER = ROOT / "csrc" / "include" / "attitude" / "version.h"


def _want() -> tuple[str, int]:
    parts = V.read(HEADER)
    return f"{parts['MAJOR']}.{parts['MINOR']}.{parts['PATCH']}", parts["SO"]


def _env() -> dict[str, str]:
    drop = {"CC", "AR", "CFLAGS", "CPPFLAGS", "LDFLAGS", "CROSS_COMPILE", "MAKEFLAGS"}
    return {k: v for k, v in os.environ.items() if k not in drop}


def test_header_is_the_only_place_the_version_is_written() -> None:
    want, _ = _want()
    assert re.fullmatch(r"\d+\.\d+\.\d+", want)
    assert V.version() == want  # the default header path is the checkout's
    literal = re.compile(rf"(?<![\d.]){re.escape(want)}(?![\d.])")
    for f in ("pyproject.toml", "setup.py", "CMakeLists.txt", "Makefile", "attitude_c/__init__.py",
              "toolchain/tasks/cross.py"):
        assert not literal.search((ROOT / f).read_text()), f"{f} spells out the version {want}"
    assert 'dynamic = ["version"]' in (ROOT / "pyproject.toml").read_text()
    assert '#include "attitude/version.h"' in (ROOT / "csrc/include/attitude/attitude.h").read_text()


def test_python_and_the_compiled_libraries_agree() -> None:
    """attitude_c.__version__ comes from the compiled library's enums; the
    installed distribution's metadata from setup.py reading the header (a
    mismatch here means a stale build: pip install -e .)."""
    want, so = _want()
    assert attitude_c.__version__ == want
    for precision in ("f64", "f32"):
        lib = ffi_lib(precision)[1]
        assert (lib.ATT_VERSION_MAJOR, lib.ATT_VERSION_MINOR, lib.ATT_VERSION_PATCH, lib.ATT_VERSION_SO) \
            == (*map(int, want.split(".")), so), precision
    assert metadata.version("attitude-c") == want


@pytest.mark.system
def test_invoke_make_and_cmake_agree(tmp_path: Path) -> None:
    """The shared library's file name and soname and the attitude.pc Version
    from every build path."""
    require_tools("make", "cmake", apt="make cmake")
    from toolchain.tasks import cross

    want, so = _want()
    assert (cross.version(), cross.SOVERSION) == (want, str(so))
    assert f"-Wl,-soname,libattitude.so.{so}" in cross.shared_link_cmd(cross.T.load("host"), [], Path("x.so"))
    make = ["make", "-C", str(ROOT), f"BUILDDIR={tmp_path / 'mk'}"]
    assert subprocess.run([*make, "-s", "version"], env=_env(), capture_output=True, text=True,
                          check=True).stdout.strip() == want
    plan = subprocess.run([*make, "-n"], env=_env(), capture_output=True, text=True, check=True).stdout
    assert f"-Wl,-soname,libattitude.so.{so} " in plan and f"libattitude.so.{want}" in plan
    assert f"'Version: {want}'" in plan
    bdir = tmp_path / "cmake"
    subprocess.run(["cmake", "-S", str(ROOT), "-B", str(bdir), "-DATT_BUILD_APP=OFF"], env=_env(),
                   capture_output=True, text=True, check=True)
    assert f"CMAKE_PROJECT_VERSION:STATIC={want}\n" in (bdir / "CMakeCache.txt").read_text()
    link = (bdir / "CMakeFiles/attitude_shared.dir/link.txt").read_text()
    assert f"-Wl,-soname,libattitude.so.{so} " in link and f"-o libattitude.so.{want} " in link
    assert f"Version: {want}\n" in (bdir / "attitude.pc.in").read_text()
