"""Cross builds: `invoke cross-build --target NAME` (settings in toolchain/NAME.toml).

Produces in ``build/NAME/``:

* ``libattitude.a`` (``libattitude.lib`` for SDCC targets) from the target's
  library sources (all of ``csrc/src`` except on mcs51, which builds only
  the 8051 parts) plus, on Linux targets, the platform code of
  ``csrc/platform/linux`` (the AD7927 spidev HAL);
* ``libattitude.so`` (+ ``.so.0`` and the versioned file) on Linux targets;
* ``attitude-rx`` (statically linked) on Linux targets;
* ``include/attitude/*.h`` and ``attitude.pc`` (relocatable: paths relative
  to the .pc file, so ``PKG_CONFIG_PATH=build/NAME pkg-config --cflags
  --libs attitude`` works wherever the tree is);
* on ``armv4t``/``armv4t-bare``: the ARMv4T instruction check of every
  object and of the linked ``libattitude.so`` (toolchain/armv4t_check.py);
  the build fails on a violation.

The build is done from Python (not by calling make) so that every
target, including SDCC, uses exactly the flags of its TOML file;
``make TARGET=NAME`` and cmake/NAME-toolchain.cmake use the same ones
(generated from the TOML files by toolchain/buildfiles.py).
"""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path

from invoke import task

from attitude_c._build import version as _version
from toolchain import targets as T
from toolchain.buildfiles import shared_ldflags

ROOT = T.ROOT
APP_DIR = ROOT / "csrc" / "app"
#: N of the soname libattitude.so.N (csrc/include/attitude/version.h).
SOVERSION = str(_version.read()["SO"])


def version() -> str:
    """MAJOR.MINOR.PATCH from csrc/include/attitude/version.h, the one source."""
    return _version.version()


def _run(cmd: Sequence[str], verbose: bool) -> None:
    if verbose:
        print(" ".join(map(str, cmd)), flush=True)
    proc = subprocess.run(list(map(str, cmd)), capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise BuildError(f"command failed ({proc.returncode}): {' '.join(map(str, cmd))}\n"
                         f"{proc.stdout}{proc.stderr}")


#: The shared library's objects: every symbol hidden but the public headers'
#: declarations (ATT_API_BEGIN/END, attitude/common.h), as make and CMake do.
HIDDEN = ["-fvisibility=hidden"]


class BuildError(RuntimeError):
    pass


def _compile_all(t: T.Target, srcs: Sequence[Path], objdir: Path, extra: Sequence[str],
                 defines: Sequence[str], verbose: bool) -> list[Path]:
    objdir.mkdir(parents=True, exist_ok=True)
    objs = []
    suffix = ".rel" if t.kind == "sdcc" else ".o"
    for s in srcs:
        o = objdir / (s.stem + suffix)
        incs = [*t.platform_include_dirs(), *([APP_DIR] if s.parent == APP_DIR else [])]
        _run(t.compile_cmd(s, o, defines=defines, extra_cflags=extra, include_dirs=incs), verbose)
        objs.append(o)
    return objs


def pc_text(t: T.Target, defines: Sequence[str], libs: Sequence[str]) -> str:
    cflags = " ".join(f"-D{d}" for d in defines)
    return (
        "prefix=${pcfiledir}\n"
        "libdir=${prefix}\n"
        "includedir=${prefix}/include\n\n"
        "Name: attitude\n"
        f"Description: libattitude strapdown attitude library ({t.name} build)\n"
        f"Version: {version()}\n"
        f"Cflags: -I${{includedir}}{(' ' + cflags) if cflags else ''}\n"
        "Libs: -L${libdir} -lattitude\n"
        f"Libs.private: {' '.join(libs)}\n"
    )


def shared_link_cmd(t: T.Target, objs: Sequence[Path], real: Path) -> list[str]:
    """The link of libattitude.so: the target's flags, its program link flags
    without the program-only ones, its ``shared_ldflags``, then the libraries
    (armv4t: the ARMv4T libgcc.a, -lm, -lc; toolchain/armv4t.toml)."""
    return [t.cc, *t.cflags, "-shared", f"-Wl,-soname,libattitude.so.{SOVERSION}", *map(str, objs),
            "-o", str(real), *shared_ldflags(t), *t.shared_ldflags, *t.shared_link_libs()]


def app_optional_found(t: T.Target, workdir: Path, verbose: bool = False) -> list[T.AppOptional]:
    """The optional dependencies whose probe (a program including the header and calling the
    symbol) compiles and links for target ``t`` with the app's link flags: built in."""
    workdir.mkdir(parents=True, exist_ok=True)
    found = []
    for o in T.app_optional():
        src = workdir / f"{o.name}.c"
        src.write_text(o.probe_source())
        cmd = [t.cc, *t.target_cflags, str(src), "-o", str(workdir / o.name), *t.ldflags, *t.app_libs,
               *o.libs, *t.libs]
        ok = subprocess.run(cmd, capture_output=True, check=False).returncode == 0
        if verbose:
            print(f"probe {o.name}: {' '.join(cmd)}: {'ok' if ok else 'failed'}", flush=True)
        if ok:
            found.append(o)
    return found


def cross_build_target(name: str, *, precision: str = "f64", out: Path | None = None,
                       verbose: bool = False) -> dict[str, Path]:
    """Build target ``name`` into ``out`` (default build/NAME); returns the products."""
    t = T.load(name)
    t.require()
    if precision not in ("f64", "f32"):
        raise ValueError(f"precision must be 'f64' or 'f32', not {precision!r}")
    # SDCC has no double (it would silently be float): always the float build.
    defines = ["ATT_REAL_F32"] if precision == "f32" or t.kind == "sdcc" else []
    out = Path(out) if out else t.build_dir()
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    srcs = t.library_sources()
    if not srcs:
        raise BuildError(f"target {name}: no library sources match {t.lib_source_globs}")
    srcs = [*srcs, *t.platform_sources()]
    products: dict[str, Path] = {}

    objs = _compile_all(t, srcs, out / "obj", [], defines, verbose)
    if t.kind == "sdcc":
        lib = out / "libattitude.lib"
        _run([t.ar, "rcs", lib, *objs], verbose)
    else:
        lib = out / "libattitude.a"
        _run([t.ar, "rcs", lib, *objs], verbose)
    products["static"] = lib

    if t.shared and t.kind == "gcc":
        pobjs = _compile_all(t, srcs, out / "obj-pic", [*t.pic_flags, *HIDDEN], defines, verbose)
        real = out / f"libattitude.so.{version()}"
        _run(shared_link_cmd(t, pobjs, real), verbose)
        for link in (f"libattitude.so.{SOVERSION}", "libattitude.so"):
            (out / link).symlink_to(real.name)
        products["shared"] = out / "libattitude.so"

    app_objs: list[Path] = []
    if t.app:
        app_srcs = sorted(APP_DIR.glob("*.c"))
        if app_srcs:
            found = app_optional_found(t, out / "probe", verbose)
            app_defines = [*defines, *(o.define for o in found)]
            app_objs = _compile_all(t, app_srcs, out / "obj-app", [], app_defines, verbose)
            exe = out / "attitude-rx"
            _run([t.cc, *t.cflags, *app_objs, lib, "-o", exe, *t.ldflags, *t.app_libs,
                  *(f for o in found for f in o.libs), *t.libs], verbose)
            products["app"] = exe
            products.update({f"app_{o.name}": exe for o in found})

    inc = out / "include" / "attitude"
    inc.mkdir(parents=True)
    for d in (T.INCLUDE, *t.platform_include_dirs()):
        for h in sorted((d / "attitude").glob("*.h")):
            shutil.copy2(h, inc / h.name)
    products["include"] = inc
    pc = out / "attitude.pc"
    pc.write_text(pc_text(t, defines, t.libs))
    products["pc"] = pc

    if "armv4t" in t.checks:
        from toolchain.armv4t_check import check_objects

        shared = [products["shared"].resolve()] if "shared" in products else []
        vs = check_objects([lib, *shared, *app_objs], objdump=t.objdump or t.tool("objdump"))
        if vs:
            raise BuildError(f"target {name}: {len(vs)} instruction(s) the ARM920T cannot execute:\n"
                             + "\n".join(map(str, vs)))
        products["armv4t_check"] = lib
    return products


@task(help={
    "target": "target name (toolchain/NAME.toml): armv4t, armv4t-bare, armv7hf, aarch64, host, mcs51",
    "precision": "f64 (att_real = double, default) or f32 (float)",
    "out": "output directory (default build/TARGET)",
    "verbose": "print every command",
})
def cross_build(c, target="armv4t", precision="f64", out="", verbose=False):
    """Build libattitude (+ .so, attitude-rx, headers, attitude.pc) for a target into build/TARGET."""
    try:
        products = cross_build_target(target, precision=precision, out=Path(out) if out else None,
                                      verbose=verbose)
    except (T.ToolchainMissing, BuildError, ValueError) as exc:
        raise SystemExit(f"cross-build: {exc}")
    for kind, p in products.items():
        rel = os.path.relpath(p, ROOT)
        if kind.startswith("app_"):
            continue
        if kind == "armv4t_check":
            print("  ARMv4T check: every object and libattitude.so are ARMv4T clean")
        else:
            print(f"  {kind:8s} {rel}")
    if "app" in products:
        for o in T.app_optional():
            print(f"  attitude-rx {o.name} support: " + ("built in" if f"app_{o.name}" in products else
                  f"not built (no <{o.header}> / {' '.join(o.libs)} for {target}: apt-get install {o.apt})"))
