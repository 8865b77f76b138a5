"""The C library as a user's project meets it: installed by CMake or make into
a staged root (`DESTDIR=... --prefix /usr`), then a separate consumer
project (tests/consumer/, outside the library's tree) built against the
installed copy through pkg-config and through CMake's find_package, on the
host and for armv4t (run under qemu-arm). The installed armv4t library,
libattitude.a and libattitude.so, passes the ARMv4T instruction check
whichever way it was built (invoke: tests/test_cross.py::test_cross_build_armv4t).

What the armv4t checks cover: toolchain/armv4t_check.py reads every
instruction of the installed libattitude.a and libattitude.so (our code, the
ARMv4T libgcc helpers linked into the .so, its PLT stubs). A consumer linked
against the .so runs under qemu-arm with the Debian armel loader, libc and
libm (`-L` their sysroot): that proves the .so loads, resolves and computes
right; it runs on qemu's default CPU, not the ARMv4T model (ti925t), because
that loader and libc are ARMv5TE (SIGILL in the loader there): on the board
they are the board's own, not ours. The statically linked consumers run the
library's code alike.

Each build starts from a copy of the tracked sources (no stale objects)."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest
from conftest import ROOT, clean_copy, require_target, require_tools

from attitude_c._build import version as attitude_version
from toolchain import armv4t_check

pytestmark = pytest.mark.system  # builds consumer projects against installed packages

CONSUMER = ROOT / "tests" / "consumer"
# q = [cos(0.015), 0, 0, sin(0.015)] to 6 decimals (the same in float and double)
Q_TEXT = "q=0.999888 0.014999"


def _env(**kw: str) -> dict[str, str]:
    drop = {"CC", "AR", "CFLAGS", "CPPFLAGS", "LDFLAGS", "CROSS_COMPILE", "TARGET_CFLAGS", "MAKEFLAGS",
            "PKG_CONFIG_PATH", "PKG_CONFIG_LIBDIR", "PKG_CONFIG_SYSROOT_DIR", "CMAKE_PREFIX_PATH", "DESTDIR"}
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env.update(kw)
    return env


def _run(cmd: list, cwd: Path | None = None, env: dict[str, str] | None = None) -> str:
    proc = subprocess.run([str(c) for c in cmd], cwd=cwd, env=env or _env(), capture_output=True, text=True,
                          check=False, timeout=600)
    assert proc.returncode == 0, f"{' '.join(map(str, cmd))}\n{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}"
    return proc.stdout


def _sources(tmp_path: Path) -> Path:
    return clean_copy(tmp_path / "src", "Makefile", "CMakeLists.txt", "cmake", "csrc", "toolchain/targets.mk")


def _cmake_install(tmp_path: Path, toolchain: str, *options: str) -> Path:
    """Configure, build and `DESTDIR=root cmake --install --prefix /usr`; returns root."""
    require_tools("cmake", "make", apt="cmake make")
    src, bdir, root = _sources(tmp_path), tmp_path / "build", tmp_path / "root"
    _run(["cmake", "-S", src, "-B", bdir, f"-DCMAKE_TOOLCHAIN_FILE={src / 'cmake' / toolchain}", *options])
    _run(["cmake", "--build", bdir, "-j2"])
    _run(["cmake", "--install", bdir, "--prefix", "/usr"], env=_env(DESTDIR=str(root)))
    return root


def _pkg_config_consumer(tmp_path: Path, root: Path, cc: str, target_cflags: list[str],
                         ldflags: list[str]) -> Path:
    """tests/consumer/Makefile: the program through pkg-config against the staged root."""
    require_tools("pkg-config", "make", apt="pkg-config make")
    work = tmp_path / "consumer-pc"
    shutil.copytree(CONSUMER, work)
    _run(["make", f"CC={cc}", f"TARGET_CFLAGS={' '.join(target_cflags)}", f"LDFLAGS={' '.join(ldflags)}"],
         cwd=work, env=_env(PKG_CONFIG_SYSROOT_DIR=str(root), PKG_CONFIG_LIBDIR=str(root / "usr/lib/pkgconfig")))
    return work / "consumer"


def _cmake_consumer(tmp_path: Path, root: Path, *options: str) -> tuple[Path, str]:
    """tests/consumer/CMakeLists.txt: find_package(attitude) against the staged root."""
    bdir = tmp_path / "consumer-cmake"
    out = _run(["cmake", "-S", CONSUMER, "-B", bdir, *options])
    _run(["cmake", "--build", bdir])
    return bdir / "consumer", out


def _armel_prefix(t) -> Path:
    """The armel sysroot holding the dynamic loader (for qemu-arm -L)."""
    out = subprocess.run([t.cc, "-print-file-name=ld-linux.so.3"], capture_output=True, text=True,
                         check=True).stdout.strip()
    loader = Path(out)
    assert loader.is_absolute() and loader.exists(), f"{t.cc} knows no ld-linux.so.3 ({out!r})"
    return loader.resolve().parent.parent


def _check_armv4t_install(t, root: Path, tmp_path: Path) -> None:
    """The installed libattitude.a and libattitude.so are ARMv4T clean; the
    .so needs only libm and libc; a consumer linked against it (pkg-config,
    no -static) runs under qemu-arm with the armel loader (module docstring)."""
    lib = root / "usr/lib"
    so = (lib / "libattitude.so").resolve()
    assert armv4t_check.check_objects([lib / "libattitude.a", so], objdump=t.objdump) == []
    dyn = _run([t.tool("readelf"), "-dW", so])
    assert sorted(ln.split("[")[1].rstrip("]") for ln in dyn.splitlines() if "(NEEDED)" in ln) \
        == ["libc.so.6", "libm.so.6"], dyn
    exe = _pkg_config_consumer(tmp_path / "dyn", root, t.cc, t.target_cflags, [f"-Wl,-rpath,{lib}"])
    assert "libattitude.so.0" in _run([t.tool("readelf"), "-dW", exe])
    res = t.run([exe], timeout=60, extra_run_args=["-L", str(_armel_prefix(t))])
    assert res.stdout.decode().strip() == f"att_real=8 ok=ok {Q_TEXT}"


def _check_pc(root: Path, f32: bool) -> None:
    pc = (root / "usr/lib/pkgconfig/attitude.pc").read_text()
    assert pc.startswith("prefix=/usr\n"), pc  # the install prefix, not the configure-time /usr/local
    assert ("-DATT_REAL_F32" in pc) == f32, pc


def test_cmake_host_float_build_package_and_pkg_config(tmp_path: Path) -> None:
    """Host, float build: attitude.pc for /usr; find_package gives
    attitude::attitude with ATT_REAL_F32 (the consumer sees att_real = float);
    the version file refuses another minor version."""
    t = require_target("host")
    root = _cmake_install(tmp_path, "host-toolchain.cmake", "-DATT_PRECISION=f32", "-DATT_BUILD_APP=OFF")
    _check_pc(root, f32=True)
    for f in ("attitudeConfig.cmake", "attitudeConfigVersion.cmake", "attitudeTargets.cmake"):
        assert (root / "usr/lib/cmake/attitude" / f).exists(), f
    exe, log = _cmake_consumer(tmp_path, root, f"-DCMAKE_PREFIX_PATH={root / 'usr'}")
    v = attitude_version.read()
    want = f"{v['MAJOR']}.{v['MINOR']}.{v['PATCH']}"
    assert f"libattitude {want}, precision f32" in log
    assert _run([exe]).strip() == f"att_real=4 ok=ok {Q_TEXT}"
    exe = _pkg_config_consumer(tmp_path, root, t.cc, t.target_cflags, [])
    out = _run([exe], env=_env(LD_LIBRARY_PATH=str(root / "usr/lib")))  # -lattitude: the .so here
    assert out.strip() == f"att_real=4 ok=ok {Q_TEXT}"
    proc = subprocess.run(["cmake", "-S", str(CONSUMER), "-B", str(tmp_path / "v"), f"-DATT_WANT_VERSION={v['MAJOR']}.{v['MINOR'] + 1}",
                           f"-DCMAKE_PREFIX_PATH={root / 'usr'}"], env=_env(), capture_output=True, text=True,
                          check=False)
    assert proc.returncode != 0 and want in proc.stderr


@pytest.mark.qemu
def test_cmake_armv4t_package_find_package_and_pkg_config(tmp_path: Path) -> None:
    """armv4t with cmake/armv4t-toolchain.cmake: the installed libattitude.a
    and libattitude.so are ARMv4T clean, attitude-rx is linked statically; the
    consumer, cross-built through find_package (with the same toolchain file)
    against attitude::attitude and attitude::attitude_shared (issue 27: the file
    linked every program -static, so the .so could not be linked), and through
    pkg-config, static and against the .so, runs under qemu-arm."""
    t = require_target("armv4t")
    root = _cmake_install(tmp_path, "armv4t-toolchain.cmake")
    _check_pc(root, f32=False)
    assert "no dynamic section" in _run([t.tool("readelf"), "-d", root / "usr/bin/attitude-rx"])
    _check_armv4t_install(t, root, tmp_path)
    loader = ["-L", str(_armel_prefix(t))]  # the consumer links libc dynamically (module docstring)
    for target, lib in (("attitude::attitude", None), ("attitude::attitude_shared", "libattitude.so.0")):
        exe, _ = _cmake_consumer(tmp_path / target.replace(":", "_"), root,
                                 f"-DCMAKE_TOOLCHAIN_FILE={ROOT / 'cmake/armv4t-toolchain.cmake'}",
                                 f"-DCMAKE_FIND_ROOT_PATH={root}", "-DCMAKE_PREFIX_PATH=/usr",
                                 f"-DATT_CONSUMER_LINK={target}")
        needed = _run([t.tool("readelf"), "-dW", exe])
        assert (lib in needed) if lib else ("libattitude" not in needed), needed
        res = t.run([exe], timeout=60, extra_run_args=loader)
        assert res.stdout.decode().strip() == f"att_real=8 ok=ok {Q_TEXT}", target
    exe = _pkg_config_consumer(tmp_path, root, t.cc, t.target_cflags, t.ldflags)
    assert t.run([exe], timeout=60).stdout.decode().strip() == f"att_real=8 ok=ok {Q_TEXT}"


@pytest.mark.qemu
def test_make_armv4t_preset_install_and_pkg_config(tmp_path: Path) -> None:
    """The README's line: `make TARGET=armv4t PREFIX=/usr DESTDIR=... install`
    from a clean tree; the installed libraries (.a and .so) are ARMv4T clean
    and a consumer built through pkg-config, static and against the .so, runs
    under qemu-arm."""
    t = require_target("armv4t")
    require_tools("make", apt="make")
    assert "make TARGET=armv4t PREFIX=/usr DESTDIR=" in (ROOT / "README.md").read_text()
    src, root = _sources(tmp_path), tmp_path / "root"
    _run(["make", "-j2", "TARGET=armv4t", "PREFIX=/usr", f"DESTDIR={root}", "install"], cwd=src)
    lib = root / "usr/lib"
    for name in ("libattitude.a", "libattitude.so", "libattitude.so.0"):
        assert (lib / name).exists(), name
    assert (root / "usr/include/attitude/attitude.h").exists() and (root / "usr/bin/attitude-rx").exists()
    _check_pc(root, f32=False)
    _check_armv4t_install(t, root, tmp_path)
    exe = _pkg_config_consumer(tmp_path, root, t.cc, t.target_cflags, t.ldflags)
    assert t.run([exe], timeout=60).stdout.decode().strip() == f"att_real=8 ok=ok {Q_TEXT}"


def _machine(obj: Path) -> int:
    """ELF e_machine of an object file (40 ARM; 62 x86-64, 183 AArch64)."""
    data = obj.read_bytes()[:20]
    assert data[:4] == b"\x7fELF"
    return int.from_bytes(data[18:20], "little")


@pytest.mark.qemu
def test_make_flags_stamp_rebuilds_on_new_flags_or_compiler(tmp_path: Path) -> None:
    """One BUILDDIR, changing flags and compilers: objects are rebuilt exactly
    when the compiler or a flag changed (a stamp of both), never left from
    the previous configuration."""
    require_target("armv4t")
    require_tools("make", "gcc", apt="make gcc")
    src, bdir = _sources(tmp_path), tmp_path / "b"
    base = ["make", "-j2", f"BUILDDIR={bdir}", "SHARED=0", "APP=0"]

    def build(*args: str) -> int:
        out = _run([*base, *args], cwd=src)
        return sum(" -c csrc/src/" in ln for ln in out.splitlines())

    n_src = len(list((src / "csrc/src").glob("*.c")))
    assert build() == n_src
    assert build() == 0  # nothing changed: nothing compiled
    assert build("CFLAGS=-O1") == n_src  # new flags
    assert build("CFLAGS=-O1") == 0
    assert build("TARGET=armv4t") == n_src  # another compiler, same directory
    assert _machine(bdir / "obj/quat.o") == 40
    assert build() == n_src  # plain host make afterwards: no ARM object left behind
    assert _machine(bdir / "obj/quat.o") != 40
