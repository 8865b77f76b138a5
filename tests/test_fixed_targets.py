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

import pytest
from conftest import ROOT, require_target

from toolchain.fixed_harness import KERNEL_SIZES, KERNEL_UPDATES, KERNELS, replay, s51_kernel_run

pytestmark = pytest.mark.system  # builds the fixed-point code for every target

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


@pytest.mark.parametrize("method", list(KERNELS))
def test_kernel_on_8051_matches_host(method: str, build_root: Path) -> None:
    require_target("mcs51")
    # AT89S51 configuration of toolchain/mcs51.toml (small model, 128 B IRAM, no
    # XRAM, 4 KB code) on s51's C51 core: it links and runs, bit-identical
    res, sym = s51_kernel_run(build_root / "s51fx", method)
    assert res.exit_code == 0
    got = [ln for ln in res.lines if not ln.startswith(("CYC", "EXIT"))]
    assert got == replay(KERNEL_UPDATES[method], method)
    cyc = dict(re.findall(r"^CYC (\w+) (\d+)$", res.output, re.MULTILINE))
    assert set(cyc) == {"small", "big"}
    area = {m.group(1): int(m.group(2), 16)
            for m in re.finditer(r"^\s+\w+\s+(\w+)\s+size\s+([0-9A-Fa-f]+)", sym.read_text(),
                                 re.MULTILINE)}
    code, ram = KERNEL_SIZES[KERNELS[method][0]]
    assert area["CSEG"] + area["CONST"] <= code, area
    assert area["DSEG"] + area.get("OSEG", 0) <= ram, area
