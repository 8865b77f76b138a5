"""One source of target flags: toolchain/*.toml. The Makefile presets
(toolchain/targets.mk) and the CMake toolchain files (cmake/*-toolchain.cmake)
are generated from it, and invoke, `make TARGET=NAME` and CMake compile the
library with exactly the TOML's target flags."""

from __future__ import annotations

import json
import os
import shlex
import subprocess
from pathlib import Path

import pytest
from conftest import ROOT, require_target, require_tools

from toolchain import buildfiles
from toolchain import targets as T

pytestmark = pytest.mark.system  # configures and builds with make and CMake

# Flags each build system adds on its own (the language level and warnings),
# besides include paths and defines: not target flags.
OWN_FLAGS = {"-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "--std-c99", "--Werror"}
GCC_TARGETS = [n for n in T.names() if T.load(n).kind == "gcc"]


def _clean_env() -> dict[str, str]:
    """No compiler or flag settings from the caller's environment."""
    drop = {"CC", "AR", "CFLAGS", "CPPFLAGS", "LDFLAGS", "CROSS_COMPILE", "TARGET_CFLAGS", "MAKEFLAGS"}
    return {k: v for k, v in os.environ.items() if k not in drop and not k.startswith("ATT_CC_")}


def _target_flags(cmd: list[str]) -> list[str]:
    """The flags of a compile command that are neither the build system's own
    (OWN_FLAGS), nor -I/-D, nor the source, the object and -c/-o."""
    out, skip = [], False
    for tok in cmd[1:]:
        if skip:
            skip = False
            continue
        if tok == "-o":
            skip = True
            continue
        if tok in OWN_FLAGS or tok == "-c" or tok.startswith(("-I", "-D")) or tok.endswith(".c"):
            continue
        out.append(tok)
    return out


def _defines(cmd: list[str]) -> list[str]:
    return sorted(t for t in cmd if t.startswith("-D"))


def test_generated_build_files_are_current() -> None:
    """targets.mk and the CMake toolchain files say what the TOML files say
    (regenerate with `python -m toolchain.buildfiles` after editing a TOML)."""
    assert buildfiles.stale() == []
    assert buildfiles.main(["--check"]) == 0
    for name in GCC_TARGETS:
        assert (ROOT / "cmake" / f"{name}-toolchain.cmake").exists()


def _invoke_cmd(t: T.Target, src: Path) -> list[str]:
    defines = ["ATT_REAL_F32"] if t.kind == "sdcc" else []  # as invoke cross-build does
    return t.compile_cmd(src, "common.o", defines=defines)


def _make_cmd(name: str, src_rel: str, tmp_path: Path) -> list[str]:
    out = subprocess.run(["make", "-n", f"TARGET={name}", f"BUILDDIR={tmp_path / 'mk'}"], cwd=ROOT,
                         env=_clean_env(), capture_output=True, text=True, check=True).stdout
    line = next(ln for ln in out.splitlines() if f"-c {src_rel} " in ln and "-fPIC" not in ln)
    return shlex.split(line)


def _cmake_cmd(name: str, src: Path, tmp_path: Path) -> list[str]:
    bdir = tmp_path / "cmake"
    subprocess.run(["cmake", "-S", str(ROOT), "-B", str(bdir), "-DCMAKE_EXPORT_COMPILE_COMMANDS=ON",
                    f"-DCMAKE_TOOLCHAIN_FILE={ROOT / 'cmake' / f'{name}-toolchain.cmake'}",
                    "-DATT_BUILD_SHARED=OFF", "-DATT_BUILD_APP=OFF"],
                   env=_clean_env(), capture_output=True, text=True, check=True)
    entries = json.loads((bdir / "compile_commands.json").read_text())
    entry = next(e for e in entries if Path(e["file"]) == src)
    return shlex.split(entry["command"])


@pytest.mark.parametrize("name", GCC_TARGETS + ["mcs51"])
def test_every_build_path_compiles_with_the_toml_flags(name: str, tmp_path: Path) -> None:
    """The compile command of csrc/src/common.c from invoke, `make TARGET=NAME`
    and (gcc-kind targets) CMake with cmake/NAME-toolchain.cmake: the same
    compiler, the same defines and exactly the TOML's target flags."""
    t = require_target(name)
    require_tools("make", "cmake", apt="make cmake")
    src = ROOT / "csrc" / "src" / "common.c"  # built for every target, mcs51 included
    cmds = {"invoke": _invoke_cmd(t, src), "make": _make_cmd(name, "csrc/src/common.c", tmp_path)}
    if t.kind == "gcc":
        cmds["cmake"] = _cmake_cmd(name, src, tmp_path)
    for path, cmd in cmds.items():
        assert Path(cmd[0]).name == t.cc, (path, cmd)
        assert _target_flags(cmd) == t.target_cflags, (path, cmd)
        assert _defines(cmd) == _defines(cmds["invoke"]), (path, cmd)


def test_every_build_path_links_the_shared_library_alike(tmp_path: Path) -> None:
    """armv4t's libattitude.so: invoke, `make TARGET=armv4t` and CMake with
    cmake/armv4t-toolchain.cmake link it with the TOML's shared_ldflags and end
    the link line with the same libraries (the ARMv4T libgcc.a, -lm, -lc)."""
    from toolchain.tasks.cross import shared_link_cmd

    t = require_target("armv4t")
    require_tools("make", "cmake", apt="make cmake")
    tail = t.shared_link_libs()
    assert Path(tail[0]).name == "libgcc.a" and tail[1:] == ["-lm", "-lc"]
    mk = subprocess.run(["make", "-n", "TARGET=armv4t", f"BUILDDIR={tmp_path / 'mk'}"], cwd=ROOT,
                        env=_clean_env(), capture_output=True, text=True, check=True).stdout
    bdir = tmp_path / "cmake"
    subprocess.run(["cmake", "-S", str(ROOT), "-B", str(bdir), "-DATT_BUILD_APP=OFF",
                    f"-DCMAKE_TOOLCHAIN_FILE={ROOT / 'cmake' / 'armv4t-toolchain.cmake'}"],
                   env=_clean_env(), capture_output=True, text=True, check=True)
    cmds = {
        "invoke": shared_link_cmd(t, [Path("common.o")], Path("libattitude.so.0")),
        "make": shlex.split(next(ln for ln in mk.splitlines() if " -shared " in ln)),
        "cmake": shlex.split((bdir / "CMakeFiles/attitude_shared.dir/link.txt").read_text()),
    }
    for path, cmd in cmds.items():
        assert Path(cmd[0]).name == t.cc, (path, cmd)
        assert cmd[-len(tail):] == tail, (path, cmd)
        assert all(f in cmd for f in t.shared_ldflags) and "-static" not in cmd, (path, cmd)
