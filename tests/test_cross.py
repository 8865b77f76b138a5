"""Cross builds: invoke cross-build, the ARMv4T instruction check and the qemu
instruction counter (make and CMake: tests/test_consumer.py, test_buildfiles.py)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest
from conftest import ROOT, require_target, require_tools

from toolchain import armv4t_check
from toolchain.tasks.cross import cross_build_target

pytestmark = pytest.mark.system  # cross-builds the library and attitude-rx, runs them under qemu

# A small user program: what a mini2440 application does with the library (the
# consumer project's, tests/consumer/main.c).
EXAMPLE_C = (ROOT / "tests" / "consumer" / "main.c").read_text()
# q = [cos(0.015), 0, 0, sin(0.015)] to 6 decimals (the same in float and double)
Q_TEXT = "q=0.999888 0.014999"

SNIPPET_C = r"""
unsigned lead(unsigned a) { return (unsigned)__builtin_clz(a); }
"""


def _cc(t, src: Path, obj: Path, *flags: str) -> Path:
    subprocess.run([t.cc, "-O2", "-marm", "-mfloat-abi=soft", *flags, "-c", str(src), "-o", str(obj)],
                   check=True, capture_output=True)
    return obj


# -- the ARMv4T check -------------------------------------------------------

def test_armv4t_check_rejects_armv5te_object(tmp_path: Path) -> None:
    """An object built for ARMv5TE (clz) is caught; the v4T build of the same code is clean."""
    t = require_target("armv4t")
    src = tmp_path / "snippet.c"
    src.write_text(SNIPPET_C)
    bad = _cc(t, src, tmp_path / "v5te.o", "-march=armv5te")
    vs = armv4t_check.check_objects([bad], objdump=t.objdump)
    mnems = {v.insn.split()[0] for v in vs}
    assert "clz" in mnems, vs
    assert any("v5TE" in v.reason for v in vs if v.insn.startswith("Tag_CPU_arch")), vs
    good = _cc(t, src, tmp_path / "v4t.o", "-march=armv4t", "-mtune=arm920t")
    assert armv4t_check.check_objects([good], objdump=t.objdump) == []


def test_armv4t_check_rejects_interworking_and_vfp(tmp_path: Path) -> None:
    """Returns that load pc (no interworking on v4T), blx and VFP code are caught."""
    t = require_target("armv4t")
    asm = tmp_path / "bad.s"
    asm.write_text(
        ".arm\n.text\n.global f\nf:\n push {r4, lr}\n pop {r4, pc}\n"
        ".global g\ng:\n mov pc, lr\n.global h\nh:\n ldr pc, [sp], #4\n"
        ".global j\nj:\n ldr pc, [pc, r0, lsl #2]\n bx lr\n")
    obj = tmp_path / "bad.o"
    subprocess.run([t.cc, "-march=armv4t", "-c", str(asm), "-o", str(obj)], check=True,
                   capture_output=True)
    vs = armv4t_check.check_objects([obj], objdump=t.objdump)
    funcs = sorted(v.function for v in vs)
    assert funcs == ["f", "g", "h"], vs  # j's jump table stays in ARM state: accepted
    vfp = tmp_path / "vfp.c"
    vfp.write_text("double mac(double a, double b, double c) { return a * b + c; }\n"
                   "int (*fp)(void); int call(void) { return fp() + 1; }\n")
    obj2 = _cc(t, vfp, tmp_path / "vfp.o", "-march=armv5te", "-mfpu=vfp", "-mfloat-abi=softfp")
    reasons = " ".join(v.reason for v in armv4t_check.check_objects([obj2], objdump=t.objdump))
    assert "FPU" in reasons and "BLX" in reasons


SHARED_C = r"""
#include <math.h>
double norm(double x, double y) { return sqrt(x * x + y * y) / (x + 1.0); }
unsigned part(unsigned a, unsigned b) { return a / b; }
"""


def test_armv4t_shared_object_needs_the_armv4t_libgcc(tmp_path: Path) -> None:
    """A shared object of ARMv4T code linked the armel compiler's default way
    pulls its ARMv5TE runtime (soft-float/division helpers with clz and
    pc-loading returns, crti.o) and fails the check; linked as the armv4t
    target says (toolchain/armv4t.toml: the ARMv4T libgcc.a of
    arm-none-eabi-gcc, -nostdlib, then -lm -lc) it passes, its PLT stubs
    included."""
    t = require_target("armv4t")
    src = tmp_path / "shared.c"
    src.write_text(SHARED_C)
    obj = _cc(t, src, tmp_path / "shared.o", "-march=armv4t", "-fPIC")
    default = tmp_path / "default.so"
    subprocess.run([t.cc, *t.target_cflags, "-shared", str(obj), "-o", str(default), "-lm"], check=True,
                   capture_output=True)
    vs = armv4t_check.check_objects([default], objdump=t.objdump)
    assert any(v.insn.startswith("clz") for v in vs) and any("v5TE" in v.reason for v in vs), vs
    v4t = tmp_path / "v4t.so"
    subprocess.run([t.cc, *t.target_cflags, "-shared", str(obj), "-o", str(v4t), *t.shared_ldflags,
                    *t.shared_link_libs()], check=True, capture_output=True)
    plt = subprocess.run([t.objdump, "-d", str(v4t)], check=True, capture_output=True, text=True).stdout
    assert "<sqrt@plt>:" in plt  # a PLT stub is there, and accepted
    assert armv4t_check.check_objects([v4t], objdump=t.objdump) == []


def test_armv4t_check_accepts_only_the_linkers_plt_stubs() -> None:
    """Only GNU ld's PLT pc loads, and only inside .plt / NAME@plt, are accepted."""
    text = ("00000400 <.plt>:\n 400:\tstr\tlr, [sp, #-4]!\n 404:\tldr\tlr, [pc, #4]\n"
            " 408:\tadd\tlr, pc, lr\n 40c:\tldr\tpc, [lr, #8]!\n 410:\t.word\t0x00010bf0\n"
            "00000414 <sqrt@plt>:\n 414:\tadd\tip, pc, #0, 12\n 418:\tadd\tip, ip, #16, 20\n"
            " 41c:\tldr\tpc, [ip, #3052]!\n 420:\tpop\t{r4, pc}\n"
            "00000424 <f>:\n 424:\tldr\tpc, [ip, #8]!\n 428:\tbx\tlr\n")
    vs = armv4t_check.check_disassembly(text, "x.so")
    assert [(v.function, v.address) for v in vs] == [("sqrt@plt", "0x420"), ("f", "0x424")], vs


def test_armv4t_check_cli_exit_status(tmp_path: Path) -> None:
    t = require_target("armv4t")
    src = tmp_path / "snippet.c"
    src.write_text(SNIPPET_C)
    bad = _cc(t, src, tmp_path / "v5te.o", "-march=armv5te")
    assert armv4t_check.main(["--objdump", t.objdump, str(bad)]) == 1
    good = _cc(t, src, tmp_path / "v4t.o", "-march=armv4t")
    assert armv4t_check.main(["--objdump", t.objdump, str(good)]) == 0


# -- invoke cross-build -----------------------------------------------------

def _example_against(t, out: Path, tmp_path: Path) -> Path:
    """Compile the example with the flags pkg-config gives for build/NAME/attitude.pc."""
    require_tools("pkg-config", apt="pkg-config")
    env = dict(os.environ, PKG_CONFIG_PATH=str(out), PKG_CONFIG_LIBDIR=str(out))
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "--static", "attitude"], env=env,
                           check=True, capture_output=True, text=True).stdout.split()
    src = tmp_path / "example.c"
    src.write_text(EXAMPLE_C)
    exe = tmp_path / "example"
    rpath = [] if "-static" in t.ldflags else [f"-Wl,-rpath,{out}"]  # dynamic: find our .so
    subprocess.run([t.cc, *t.cflags, str(src), "-o", str(exe), *flags, *t.ldflags, *rpath],
                   check=True, capture_output=True)
    return exe


@pytest.mark.qemu
def test_cross_build_armv4t(tmp_path: Path) -> None:
    """invoke cross-build --target armv4t: every product, ARMv4T-clean, usable through pkg-config."""
    t = require_target("armv4t")
    out = tmp_path / "armv4t"
    products = cross_build_target("armv4t", out=out)
    for name in ("libattitude.a", "libattitude.so", "attitude.pc", "include/attitude/attitude.h"):
        assert (out / name).exists(), name
    assert "armv4t_check" in products  # the build ran the check (and would have failed on a violation)
    if any((ROOT / "csrc" / "app").glob("*.c")):
        assert (out / "attitude-rx").exists()
    exe = _example_against(t, out, tmp_path)
    # the .so too: linked against the ARMv4T libgcc, not the armel compiler's (toolchain/armv4t.toml)
    assert armv4t_check.check_objects([out / "libattitude.a", (out / "libattitude.so").resolve()],
                                      objdump=t.objdump) == []
    res = t.run([exe], timeout=60)
    assert res.stdout.decode().strip() == f"att_real=8 ok=ok {Q_TEXT}"


@pytest.mark.parametrize("name", ["host", "armv4t-bare", "armv7hf", "aarch64", "mcs51"])
def test_cross_build_other_targets(name: str, tmp_path: Path) -> None:
    t = require_target(name)
    out = tmp_path / name
    products = cross_build_target(name, out=out)
    assert products["static"].stat().st_size > 0
    assert (products["pc"]).read_text().startswith("prefix=${pcfiledir}")
    if t.os == "linux":
        assert (out / "libattitude.so").exists()
    if name == "host":
        exe = _example_against(t, out, tmp_path)
        assert subprocess.run([exe], capture_output=True, text=True, check=True).stdout.strip() \
            == f"att_real=8 ok=ok {Q_TEXT}"


def test_cross_build_f32_pc_carries_define(tmp_path: Path) -> None:
    """The float build's attitude.pc passes -DATT_REAL_F32 (att_real is part of the ABI)."""
    t = require_target("host")
    out = tmp_path / "f32"
    cross_build_target("host", precision="f32", out=out)
    assert "-DATT_REAL_F32" in (out / "attitude.pc").read_text()
    exe = _example_against(t, out, tmp_path)
    assert subprocess.run([exe], capture_output=True, text=True, check=True).stdout.strip() \
        == f"att_real=4 ok=ok {Q_TEXT}"


# -- plain Makefile and CMake: tests/test_consumer.py (installs, consumer project) and
# tests/test_buildfiles.py (the same target flags on every path).


# -- qemu instruction counter ----------------------------------------------

@pytest.mark.qemu
def test_qemu_count_exact_loop(tmp_path: Path) -> None:
    """count_instructions is exact: a 2-instruction loop run k times costs 2k more."""
    from toolchain.qemu_count import count_instructions, per_iteration

    t = require_target("armv4t-bare")
    src = tmp_path / "loop.c"
    src.write_text(
        "#include <stdlib.h>\n"
        "int main(int argc, char **argv) {\n"
        "  unsigned n = argc > 1 ? (unsigned)atoi(argv[1]) : 0;\n"
        "  if (n) __asm__ volatile(\"1: subs %0, %0, #1\\n bne 1b\" : \"+r\"(n) :: \"cc\");\n"
        "  return 0;\n}\n")
    exe = t.build_program([src], tmp_path / "loop", with_lib=False)
    # same-length arguments so that atoi() costs the same in both runs
    a = count_instructions(exe, ["0001"])
    b = count_instructions(exe, ["1001"])
    assert b - a == 2000  # exactly subs + bne per extra iteration
    assert per_iteration(exe, lambda k: [f"{k:04d}"], 1, 501) == 2.0


@pytest.mark.parametrize("cc", ["gcc", "clang"])
def test_app_and_runner_are_warning_free(cc: str) -> None:
    """csrc/app and csrc/vectors: -std=c99 -Wall -Wextra -Wpedantic -Werror, f64 and f32."""
    require_tools(cc, apt=cc)
    srcs = [str(p) for p in sorted((ROOT / "csrc" / "app").glob("*.c"))
            + sorted((ROOT / "csrc" / "vectors").glob("*.c"))]
    for d in ([], ["-DATT_REAL_F32"], ["-DBENCH_AHRS_TEKF"]):  # bench_ahrs.c's second filter too
        subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-fsyntax-only",
                        f"-I{ROOT / 'csrc' / 'include'}", f"-I{ROOT / 'csrc' / 'app'}", *d, *srcs],
                       check=True, capture_output=True)
