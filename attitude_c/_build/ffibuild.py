"""CFFI out-of-line API-mode builders for libattitude.

Two extension modules are built from the *same* C sources:

* ``attitude_c._att_f64`` — ``att_real`` is ``double``;
* ``attitude_c._att_f32`` — ``att_real`` is ``float`` (``-DATT_REAL_F32``).

The declarations fed to ``cdef()`` are the real public headers: the
umbrella ``csrc/cffi/bindings.h`` is run through the C preprocessor with
``ATT_CDEF`` defined (which keeps system headers and inline helpers out),
so the headers are the single source of truth. Files ``csrc/cffi/*.cdef``
are appended verbatim: they hold what only Python needs, such as the
``extern "Python"`` callbacks of the pin-level device models.

Used by ``setup.py`` through ``cffi_modules`` and by ``invoke build``.
"""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
from pathlib import Path

from cffi import FFI

ROOT = Path(__file__).resolve().parents[2]
CSRC = ROOT / "csrc"
INCLUDE = CSRC / "include"
CFFI_DIR = CSRC / "cffi"

# Library sources (portable C99) and host-only sources (device models...).
SOURCE_DIRS = (CSRC / "src", CSRC / "host")

# -fvisibility=hidden with ATT_NO_EXPORT (attitude/common.h): the extension
# exports its PyInit function only, none of the library it embeds.
COMPILE_ARGS = ["-std=c99", "-O3", "-fno-strict-aliasing", "-fvisibility=hidden"]


def _rel(p: Path) -> str:
    # setuptools wants paths relative to the setup.py directory
    return os.path.relpath(p, Path.cwd())


def sources() -> list[str]:
    out: list[str] = []
    for d in SOURCE_DIRS:
        out.extend(_rel(p) for p in sorted(d.glob("*.c")))
    return out


def preprocess_cdef(defines: list[str]) -> str:
    cc = os.environ.get("CC", "cc")
    cmd = shlex.split(cc) + [
        "-E", "-P", "-std=c99", "-DATT_CDEF", *defines,
        "-I", str(INCLUDE), "-I", str(CSRC / "host"), str(CFFI_DIR / "bindings.h"),
    ]
    try:
        text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    except FileNotFoundError as exc:  # pragma: no cover - depends on machine
        sys.exit(f"attitude_c build: C compiler {cc!r} not found ({exc}); install gcc")
    except subprocess.CalledProcessError as exc:  # pragma: no cover
        sys.exit(f"attitude_c build: preprocessing the headers failed:\n{exc.stderr}")
    extra = "".join(p.read_text() for p in sorted(CFFI_DIR.glob("*.cdef")))
    return text + "\n" + extra


def make_ffi(precision: str) -> FFI:
    defines = ["-DATT_REAL_F32"] if precision == "f32" else []
    ffi = FFI()
    ffi.cdef(preprocess_cdef(defines))
    ffi.set_source(
        f"attitude_c._att_{precision}",
        '#include "bindings.h"\n',
        sources=sources(),
        include_dirs=[_rel(INCLUDE), _rel(CSRC / "host"), _rel(CFFI_DIR)],
        define_macros=[("ATT_NO_EXPORT", "1"), *([("ATT_REAL_F32", "1")] if precision == "f32" else [])],
        extra_compile_args=COMPILE_ARGS,
    )
    return ffi


ffi_f64 = make_ffi("f64")
ffi_f32 = make_ffi("f32")


if __name__ == "__main__":  # in-place build for development
    for f in (ffi_f64, ffi_f32):
        f.compile(tmpdir=str(ROOT), verbose=True)
