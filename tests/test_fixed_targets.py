"""The fixed-point module on its targets: no float anywhere, the same bits
everywhere.

* ARMv4T objects (bare metal and Linux toolchains) reference no soft-float
  helper and contain only ARMv4T instructions;
* tests/fixed_vectors.c prints hashes of everything the module computes on
  a fixed input set: the host build (64-bit product), the host build of the
  8051 code (16-bit-halves product, compact kernel), ARMv4T bare metal and
  ARMv4T Linux (both under qemu-arm, the bare one on the ti925t ARMv4T core)
  must print exactly the same lines;
* every fixed*.c compiles warning-free with SDCC for the 8051;
* the rv3 and reuse-form update kernels run in s51 and match the host bit
  for bit.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path
from typing import Any

import pytest
from conftest import ROOT, require_target

SRC = ROOT / "csrc" / "src"
FIXED_SOURCES = sorted(SRC.glob("fixed*.c"))
# the vectors program uses the fixed-point module only
LIB_SOURCES = [*FIXED_SOURCES, SRC / "common.c"]
VECTORS = ROOT / "tests" / "fixed_vectors.c"

# soft-float helpers of libgcc / the ARM EABI run-time
SOFT_FLOAT = re.compile(r"__aeabi_[fd]\w*|__\w*(sf|df)\w*[0-9]\b|__(add|sub|mul|div)[sd]f3|"
                        r"__float\w+|__fix\w+|__extendsfdf2|__truncdfsf2")


@pytest.fixture(scope="module")
def host_vectors(build_root: Path) -> str:
    t = require_target("host")
    exe = t.build_program([VECTORS], build_root / "fxv" / "host", lib_sources=LIB_SOURCES)
    return t.run([exe]).stdout.decode()


@pytest.mark.parametrize("target", ["armv4t-bare", "armv4t"])
def test_no_soft_float_and_armv4t_only(target: str, build_root: Path) -> None:
    t = require_target(target)
    out = build_root / "fxobj" / target
    out.mkdir(parents=True, exist_ok=True)
    objs = []
    for src in FIXED_SOURCES:
        obj = out / (src.stem + ".o")
        subprocess.run(t.compile_cmd(src, obj), check=True, capture_output=True)
        objs.append(obj)
    nm = t.objdump.replace("objdump", "nm") if t.objdump else "nm"
    undefined = subprocess.run([nm, "-u", *map(str, objs)], check=True, capture_output=True,
                               text=True).stdout
    names = set(re.findall(r"^\s+U (\S+)$", undefined, re.MULTILINE))
    bad = sorted(n for n in names if SOFT_FLOAT.fullmatch(n))
    assert not bad, f"soft-float helpers referenced by the fixed-point objects: {bad}"
    # nothing from libm/libgcc either: only the module's own functions and the
    # block copies the compiler emits for struct assignments
    assert names <= {n for n in names if n.startswith("att_")} | {"memcpy", "memset"}, names
    from toolchain.armv4t_check import check_objects

    violations = check_objects(objs, objdump=t.objdump or "arm-linux-gnueabi-objdump")
    assert not violations, "\n".join(map(str, violations))


def test_halves_and_compact_builds_match_host(host_vectors: str, build_root: Path) -> None:
    t = require_target("host")
    for name, defs in [("halves", ["ATT_FX_FORCE_HALVES"]),
                       ("compact", ["ATT_FX_FORCE_HALVES", "ATT_FX_COMPACT"])]:
        exe = t.build_program([VECTORS], build_root / "fxv" / name, lib_sources=LIB_SOURCES,
                              defines=defs)
        assert t.run([exe]).stdout.decode() == host_vectors, name
    names = [ln.split()[0] for ln in host_vectors.splitlines()]
    assert names == ["rv3_kernel", "reuse_kernel_4", "reuse_kernel_6",
                     *(f"integ_{m}" for m in (0, 1, 2, 3, 4, 6)), "primitives", "adc"]


@pytest.mark.parametrize("target", ["armv4t-bare", "armv4t"])
def test_arm_vectors_match_host(target: str, host_vectors: str, build_root: Path) -> None:
    t = require_target(target)
    exe = t.build_program([VECTORS], build_root / "fxv" / target, lib_sources=LIB_SOURCES)
    assert t.run([exe], timeout=120).stdout.decode() == host_vectors


def test_sdcc_compiles_every_fixed_source(build_root: Path) -> None:
    t = require_target("mcs51")
    out = build_root / "fxsdcc"
    out.mkdir(parents=True, exist_ok=True)
    for src in FIXED_SOURCES:
        # ATT_REAL_F32: SDCC has no double (att_real is unused by this module)
        cmd = t.compile_cmd(src, out / (src.stem + ".rel"), defines=["ATT_REAL_F32"])
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        assert proc.returncode == 0 and "warning" not in proc.stderr.lower(), (src.name, proc.stderr)


def rv3_increments(n: int) -> list[list[int]]:
    """n × 9 increments (Q2.30) from a 32-bit LCG: even updates small
    ([-2^19, 2^19) ≈ ±4.9e-4 rad, series degree 1), odd ones large
    ([-2^28, 2^28) = ±0.25 rad, degree up to 4)."""
    x = 12345
    out = []
    for k in range(n):
        d = []
        for _ in range(9):
            x = (x * 1664525 + 1013904223) & 0xFFFFFFFF
            d.append((x >> 3) - 268435456 if k & 1 else (x >> 12) - 524288)
        out.append(d)
    return out


#: the 8051 kernels: method → (define leaving it alone in fixed_rv.c, its call)
KERNELS = {
    "rv3": ("ATT_FX_RV3_ONLY", "att_fx_update_rv3(q, d)"),
    "rv3-reuse": ("ATT_FX_REUSE_ONLY", "att_fx_update_reuse(q, d, ATT_FX_RV3_REUSE)"),
    "rv3-reuse-poly": ("ATT_FX_REUSE_ONLY", "att_fx_update_reuse(q, d, ATT_FX_RV3_REUSE_POLY)"),
}
#: what docs/fixed-point.md promises for fixed_rv.rel on the AT89S51: code
#: (CSEG + CONST) and static RAM (DSEG + OSEG) bytes when written (rv3 2,560
#: and 64, reuse 2,635 and 65), with room for compiler noise only
KERNEL_SIZES = {"ATT_FX_RV3_ONLY": (2600, 64), "ATT_FX_REUSE_ONLY": (2680, 65)}
#: updates run per kernel: the last n of rv3_increments(6), so the two timed
#: ones (small, big) are the same rows for every kernel; the reuse test
#: program holds only 4 rows (its kernel is larger: 4 KB of flash)
KERNEL_UPDATES = {"rv3": 6, "rv3-reuse": 4, "rv3-reuse-poly": 4}


def kernel_rows(n: int) -> list[list[int]]:
    return rv3_increments(6)[6 - n:]


def write_kernel_header(directory: Path, n: int, method: str = "rv3") -> Path:
    """fixed_kernel_inc.h for tests/s51/fixed_kernel.c: the increments in 8051
    code memory (one row of three increments per update) and the kernel call."""
    directory.mkdir(parents=True, exist_ok=True)
    rows = ",\n".join("    {" + ", ".join(f"{v}L" for v in d) + "}" for d in kernel_rows(n))
    path = directory / "fixed_kernel_inc.h"
    path.write_text(f"#define NUPD {n}\n#define FX_UPDATE(q, d) {KERNELS[method][1]}\n"
                    f"static __code const att_q30 fx_inc[NUPD][9] = {{\n{rows}\n}};\n")
    return directory


def _replay(n: int, method: str) -> list[str]:
    """The updates of tests/s51/fixed_kernel.c (same increments), through the host build."""
    from attitude_c._lib import ffi_lib

    ffi, lib = ffi_lib("f64")
    q = ffi.new("int32_t[4]", [1 << 30, 0, 0, 0])
    lines = []
    for d in kernel_rows(n):
        dd = ffi.new("int32_t[9]", d)
        if method == "rv3":
            st = lib.att_fx_update_rv3(q, dd)
        else:
            st = lib.att_fx_update_reuse(q, dd, getattr(lib, "ATT_FX_" + method.upper().replace("-", "_")))
        assert st == 0
        lines.append(" ".join("%08X" % (v & 0xFFFFFFFF) for v in q))
    return lines


def s51_kernel_run(out: Path, method: str) -> tuple[Any, Path]:
    """Build tests/s51/fixed_kernel.c for ``method`` with the AT89S51 flags
    and run it in s51; returns the result and the build's .sym of fixed_rv."""
    from toolchain import s51

    only, _ = KERNELS[method]
    n = KERNEL_UPDATES[method]
    name = method.replace("-", "_")
    ihx = s51.build([ROOT / "tests" / "s51" / "fixed_kernel.c"], out / name,
                    lib_sources=[SRC / "fixed_rv.c"], defines=["ATT_REAL_F32", only],
                    include_dirs=[write_kernel_header(out / f"inc_{name}", n, method)])
    return s51.run(ihx, timeout=120), out / f"{name}.objs" / "fixed_rv.sym"


@pytest.mark.parametrize("method", list(KERNELS))
def test_kernel_on_8051_matches_host(method: str, build_root: Path) -> None:
    require_target("mcs51")
    # AT89S51 configuration of toolchain/mcs51.toml (small model, 128 B IRAM, no
    # XRAM, 4 KB code) on s51's C51 core: it links and runs, bit-identical
    res, sym = s51_kernel_run(build_root / "s51fx", method)
    assert res.exit_code == 0
    got = [ln for ln in res.lines if not ln.startswith(("CYC", "EXIT"))]
    assert got == _replay(KERNEL_UPDATES[method], method)
    cyc = dict(re.findall(r"^CYC (\w+) (\d+)$", res.output, re.MULTILINE))
    assert set(cyc) == {"small", "big"}
    area = {m.group(1): int(m.group(2), 16)
            for m in re.finditer(r"^\s+\w+\s+(\w+)\s+size\s+([0-9A-Fa-f]+)", sym.read_text(),
                                 re.MULTILINE)}
    code, ram = KERNEL_SIZES[KERNELS[method][0]]
    assert area["CSEG"] + area["CONST"] <= code, area
    assert area["DSEG"] + area.get("OSEG", 0) <= ram, area
