"""The Makefile presets and the CMake toolchain files, generated from the
target definitions (toolchain/*.toml): one source of target flags.

    python -m toolchain.buildfiles            # rewrite the generated files
    python -m toolchain.buildfiles --check    # exit 1 if one is out of date

Generated (and committed, so that make and CMake need no Python):

* ``toolchain/targets.mk``: one block of ``ATT_TARGET_*_<name>`` variables per
  target, read by ``make TARGET=<name>``;
* ``cmake/app-optional.cmake``: attitude-rx's optional dependencies
  (``toolchain/app/optional.toml``), probed by ``CMakeLists.txt`` (the Makefile
  reads them from ``targets.mk``);
* ``cmake/<name>-toolchain.cmake`` for every gcc-kind target (CMake has no
  SDCC preset); the cross ones include ``cmake/cross-common.cmake``, what
  they share (the ``CROSS_COMPILE`` prefix, the tools under it, the find modes).

What goes where: the TOML ``cflags`` (the target: architecture, ABI,
optimization, instrumentation) go unchanged into every path; the TOML
``strict_cflags`` (-std, warnings, -Werror) stay with the project's own
builds: make and CMake add their own ``-std=c99 -Wall -Wextra -Wpedantic``.
The TOML ``ldflags`` link programs (``-static``, ``--specs=...``; in CMake
``-static`` links only ``attitude-rx``, so that a user's program can link
``attitude::attitude_shared``); the shared library gets them without those
program-only flags, plus the TOML
``shared_ldflags``, the libgcc.a that ``shared_libgcc`` prints and
``shared_libs`` (armv4t: an ARMv4T runtime instead of the compiler's own).
``tests/test_buildfiles.py`` checks that these files are current and that
invoke, make and CMake compile with the same target flags.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from toolchain import targets as T

ROOT = T.ROOT
MAKE_FRAGMENT = ROOT / "toolchain" / "targets.mk"
CMAKE_DIR = ROOT / "cmake"
CROSS_COMMON = CMAKE_DIR / "cross-common.cmake"

#: Link flags only a program takes (not a shared library).
PROGRAM_ONLY_LDFLAGS = ("-static", "--specs=")
#: Of those, the ones only attitude-rx takes in CMake (a user's program may link the .so).
APP_ONLY_LDFLAGS = ("-static",)


def _generated_note(source: str, regen: str = "python -m toolchain.buildfiles") -> str:
    return f"# GENERATED from {source} by `{regen}`: do not edit.\n"


def split_tool(t: T.Target) -> tuple[str, str, str]:
    """``(prefix, compiler, archiver)`` with ``cc = prefix + compiler``, so a
    user can swap the prefix (``CROSS_COMPILE=arm-linux-``) and keep the rest."""
    cc, ar = t.cc, t.ar
    for tool in ("gcc", "clang"):
        if cc.endswith(tool):
            prefix = cc[: -len(tool)]
            if ar.startswith(prefix) and prefix:
                return prefix, tool, ar[len(prefix):]
            return prefix, tool, ar
    return "", cc, ar


def shared_ldflags(t: T.Target) -> list[str]:
    return [f for f in t.ldflags if not f.startswith(PROGRAM_ONLY_LDFLAGS)]


def _header_comment(t: T.Target) -> list[str]:
    """The TOML file's leading comment lines."""
    out = []
    for line in (T.TOOLCHAIN_DIR / f"{t.name}.toml").read_text().splitlines():
        if not line.startswith("#"):
            break
        out.append(line)
    return out


def _load_plain(name: str) -> T.Target:
    """The TOML as written (no ATT_CC_* environment override)."""
    import os

    key = f"ATT_CC_{name.upper().replace('-', '_')}"
    saved = os.environ.pop(key, None)
    try:
        return T.load(name)
    finally:
        if saved is not None:
            os.environ[key] = saved


def make_fragment() -> str:
    lines = [_generated_note("toolchain/*.toml").rstrip("\n"),
             "# Target presets of the Makefile: make TARGET=<name> (see the Makefile's header).", ""]
    names = T.names()
    lines.append(f"ATT_TARGETS := {' '.join(names)}")
    for name in names:
        t = _load_plain(name)
        prefix, cc, ar = split_tool(t)
        lines += ["", *_header_comment(t)]
        v = {
            "KIND": t.kind,
            "OS": t.os,
            "CROSS_COMPILE": prefix,
            "CC": cc,
            "AR": ar,
            "CFLAGS": " ".join(t.target_cflags),
            "LDFLAGS": " ".join(shared_ldflags(t)),
            "LIBS": " ".join(t.libs),
            "STATIC_APP": "1" if "-static" in t.ldflags else "0",
            "SHARED": "1" if t.shared and t.kind == "gcc" else "0",
            "APP": "1" if t.app else "0",
            "APP_LIBS": " ".join(t.app_libs),
            "SOURCES": " ".join(t.lib_source_globs),
            "SHARED_LDFLAGS": " ".join(t.shared_ldflags),
            "SHARED_LIBGCC": " ".join(t.shared_libgcc),
            "SHARED_LIBS": " ".join(t.shared_libs),
        }
        lines += [f"ATT_TARGET_{k}_{name} := {val}".rstrip() for k, val in v.items()]
    opts = T.app_optional()
    lines += ["", "# attitude-rx's optional dependencies (toolchain/app/optional.toml), probed by the Makefile.",
              f"ATT_APP_OPTIONAL := {' '.join(o.name for o in opts)}"]
    for o in opts:
        lines += [f"ATT_APP_OPTIONAL_DEFINE_{o.name} := {o.define}", f"ATT_APP_OPTIONAL_HEADER_{o.name} := {o.header}",
                  f"ATT_APP_OPTIONAL_SYMBOL_{o.name} := {o.symbol}",
                  f"ATT_APP_OPTIONAL_LIBS_{o.name} := {' '.join(o.libs)}"]
    return "\n".join(lines) + "\n"


def cmake_app_optional() -> str:
    """cmake/app-optional.cmake: attitude-rx's optional dependencies for CMakeLists.txt."""
    opts = T.app_optional()
    lines = [_generated_note("toolchain/app/optional.toml").rstrip("\n"),
             "# attitude-rx's optional dependencies: CMakeLists.txt probes each (header, symbol, libraries).",
             f"set(ATT_APP_OPTIONAL {' '.join(o.name for o in opts)})"]
    for o in opts:
        lines += [f"set(ATT_APP_OPTIONAL_{o.name}_DEFINE {o.define})", f"set(ATT_APP_OPTIONAL_{o.name}_HEADER {o.header})",
                  f"set(ATT_APP_OPTIONAL_{o.name}_SYMBOL {o.symbol})",
                  f"set(ATT_APP_OPTIONAL_{o.name}_LIBS {';'.join(o.libs)})"]
    return "\n".join(lines) + "\n"


def _processor(t: T.Target) -> str | None:
    if t.cc.startswith("aarch64"):
        return "aarch64"
    if t.cc.startswith("arm"):
        return "arm"
    return None


def cross_common() -> str:
    """cmake/cross-common.cmake: the part every cross toolchain file shares."""
    return "\n".join([
        _generated_note("toolchain/buildfiles.py").rstrip("\n"),
        "# Included by every cross toolchain file (cmake/<name>-toolchain.cmake), which sets",
        "# ATT_CROSS_COMPILE_DEFAULT first: the compiler prefix CROSS_COMPILE (-DCROSS_COMPILE=<prefix>,",
        "# else the environment's CROSS_COMPILE, else that default), the tools under it, and",
        "# find_* looking in the sysroot only (programs: on the build machine).",
        "",
        "if(NOT DEFINED CROSS_COMPILE)",
        "  if(DEFINED ENV{CROSS_COMPILE})",
        '    set(CROSS_COMPILE "$ENV{CROSS_COMPILE}")',
        "  else()",
        '    set(CROSS_COMPILE "${ATT_CROSS_COMPILE_DEFAULT}")',
        "  endif()",
        "endif()",
        'set(CROSS_COMPILE "${CROSS_COMPILE}" CACHE STRING "cross compiler prefix")',
        "set(CMAKE_C_COMPILER ${CROSS_COMPILE}gcc)",
        'set(CMAKE_AR ${CROSS_COMPILE}ar CACHE FILEPATH "archiver")',
        'set(CMAKE_RANLIB ${CROSS_COMPILE}ranlib CACHE FILEPATH "ranlib")',
        "",
        "set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)",
        "set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)",
        "set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)",
        "set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)",
    ]) + "\n"


def cmake_toolchain(t: T.Target) -> str:
    prefix, cc, ar = split_tool(t)
    cross = bool(prefix) or t.os == "none"
    q = " ".join
    out = [_generated_note(f"toolchain/{t.name}.toml").rstrip("\n"), *_header_comment(t), "#",
           f"#   cmake -S . -B build/cmake-{t.name} -DCMAKE_TOOLCHAIN_FILE=cmake/{t.name}-toolchain.cmake",
           "#"]
    if prefix:
        out += [f"# The compiler prefix defaults to {prefix}; for another toolchain for the same core",
                "# (e.g. a vendor's arm-linux-) pass -DCROSS_COMPILE=<prefix> (or set CROSS_COMPILE in",
                "# the environment) and, if it has its own sysroot, -DCMAKE_SYSROOT=/path/to/sysroot."]
    out.append("")
    if cross:
        if (cc, ar) != ("gcc", "ar"):
            raise ValueError(f"toolchain/{t.name}.toml: {t.cc} / {t.ar}: cmake/cross-common.cmake "
                             "knows only <prefix>gcc and <prefix>ar")
        out.append(f"set(CMAKE_SYSTEM_NAME {'Linux' if t.os == 'linux' else 'Generic'})")
        proc = _processor(t)
        if proc:
            out.append(f"set(CMAKE_SYSTEM_PROCESSOR {proc})")
        out += [f'set(ATT_CROSS_COMPILE_DEFAULT "{prefix}")',
                'include("${CMAKE_CURRENT_LIST_DIR}/cross-common.cmake")  # the tools, the find modes']
    else:
        out.append(f"set(CMAKE_C_COMPILER {cc})")
    app = [f for f in t.ldflags if f in APP_ONLY_LDFLAGS]
    out += ["", "# The target's flags (toolchain/<name>.toml cflags); programs link with its ldflags"
            + (f" but {q(app)}," if app else "."),
            *(["# which only attitude-rx takes (below): a program that uses this file may link",
               "# attitude::attitude_shared."] if app else []),
            f'set(CMAKE_C_FLAGS_INIT "{q(t.target_cflags)}")',
            f'set(CMAKE_EXE_LINKER_FLAGS_INIT "{q(f for f in t.ldflags if f not in app)}")',
            f'set(CMAKE_SHARED_LINKER_FLAGS_INIT "{q(shared_ldflags(t))}")']
    if app:
        out += ["",
                "# attitude-rx links statically (the Makefile's STATIC_APP): read by the library's",
                "# CMakeLists.txt for that one program.",
                f'set(ATT_APP_LINK_OPTIONS "{";".join(app)}")']
    if t.shared_ldflags or t.shared_libgcc or t.shared_libs != t.libs:
        out += ["",
                "# How libattitude.so is linked (toolchain/<name>.toml shared_*): read by the",
                "# library's CMakeLists.txt for that one target, not applied to other targets.",
                f'set(ATT_SHARED_LINK_OPTIONS "{";".join(t.shared_ldflags)}")',
                f'set(ATT_SHARED_LIBGCC_CMD "{";".join(t.shared_libgcc)}")',
                f'set(ATT_SHARED_LIBS "{";".join(t.shared_libs)}")']
    opts = []
    if not t.shared:
        opts.append('set(ATT_BUILD_SHARED OFF CACHE BOOL "build libattitude.so as well as libattitude.a")')
    if not t.app:
        opts.append('set(ATT_BUILD_APP OFF CACHE BOOL "build the attitude-rx receiver app")')
    if opts:
        out += ["", "# What this target builds (toolchain/<name>.toml shared/app).", *opts]
    if t.os == "none":
        out += ["", "# No OS: the compiler checks build a static library, not a program.",
                "set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)"]
    if cross and t.run_cmd:
        out += ["", "# Run cross-built programs (try_run, ctest) under the target's emulator.",
                f'set(CMAKE_CROSSCOMPILING_EMULATOR {";".join(t.run_cmd)})']
    return "\n".join(out) + "\n"


def outputs() -> dict[Path, str]:
    files = {MAKE_FRAGMENT: make_fragment(), CROSS_COMMON: cross_common(),
             CMAKE_DIR / "app-optional.cmake": cmake_app_optional()}
    for name in T.names():
        t = _load_plain(name)
        if t.kind == "gcc":
            files[CMAKE_DIR / f"{name}-toolchain.cmake"] = cmake_toolchain(t)
    return files


def stale() -> list[Path]:
    """Generated files whose content differs from what the TOML files give."""
    return [p for p, text in outputs().items() if not p.exists() or p.read_text() != text]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m toolchain.buildfiles", description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="only report out-of-date files (exit 1 if any)")
    args = ap.parse_args(argv)
    if args.check:
        bad = stale()
        for p in bad:
            print(f"out of date: {p.relative_to(ROOT)} (run: python -m toolchain.buildfiles)", file=sys.stderr)
        return 1 if bad else 0
    for p, text in outputs().items():
        if not p.exists() or p.read_text() != text:
            p.write_text(text)
            print(f"wrote {p.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
