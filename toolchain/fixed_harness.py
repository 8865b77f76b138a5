"""Fixed-point harness shared by the tests (tests/test_fixed.py,
tests/test_fixed_targets.py) and the benchmark (bench/fixed.py): the 8051
update kernels built and run in s51, their increments and their host
replay, and the long-run motions the fixed-point core is judged on, with
the quaternion-angle error and the rounding-noise limit of docs/fixed-point.md.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from attitude_c import fixedpoint as fx

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "csrc" / "src"
#: one LSB of Q2.30 (rad for increments, unit for quaternions)
LSB = 2.0**-30


# -- the 8051 update kernels ----------------------------------------------------------

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


def replay(n: int, method: str) -> list[str]:
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
    from . import s51

    only, _ = KERNELS[method]
    n = KERNEL_UPDATES[method]
    name = method.replace("-", "_")
    ihx = s51.build([ROOT / "tests" / "s51" / "fixed_kernel.c"], out / name,
                    lib_sources=[SRC / "fixed_rv.c"], defines=["ATT_REAL_F32", only],
                    include_dirs=[write_kernel_header(out / f"inc_{name}", n, method)])
    return s51.run(ihx, timeout=120), out / f"{name}.objs" / "fixed_rv.sym"


# -- long runs against float64 fed the same increments --------------------------------

def angle_error(qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
    """Rotation angle between attitudes qa and qb (rad), 2·|vec(qa* ⊗ qb)|."""
    w1, v1 = qa[..., 0], qa[..., 1:]
    w2, v2 = qb[..., 0], qb[..., 1:]
    v = w1[..., None] * v2 - w2[..., None] * v1 - np.cross(v1, v2)
    return 2 * np.linalg.norm(v, axis=-1)


def quantize(x: np.ndarray) -> np.ndarray:
    """The values the fixed-point side really sees (rounded to Q2.30)."""
    return fx.from_q30(fx.to_q30(x))


def paper_sinusoid(n: int, rate: float = 100.0) -> np.ndarray:
    """Increments of the paper's sec. 4 test: attitude angles varying as sines
    (yaw 0.5 sin(0.2πt), pitch 0.3 sin(0.3πt), roll 0.4 sin(0.25πt)); body
    rate of the z-x-y sequence at mid-interval times the period."""
    dt = 1.0 / rate
    t = (np.arange(n) + 0.5) * dt
    A = np.array([0.5, 0.3, 0.4])
    W = np.array([0.2, 0.3, 0.25]) * np.pi
    ang = A * np.sin(np.outer(t, W))
    dang = A * W * np.cos(np.outer(t, W))
    th, ga = ang[:, 1], ang[:, 2]
    dpsi, dth, dga = dang[:, 0], dang[:, 1], dang[:, 2]
    # C = Rz(ψ) Rx(θ) Ry(γ): ω_b = Ry(γ)^T [ (dθ, 0, 0) + Rx(θ)^T (0, 0, dψ) ] + (0, dγ, 0)
    wx = dth * np.cos(ga) - dpsi * np.cos(th) * np.sin(ga)
    wy = dga + dpsi * np.sin(th)
    wz = dth * np.sin(ga) + dpsi * np.cos(th) * np.cos(ga)
    return np.stack([wx, wy, wz], 1) * dt


def coning(n: int, rate: float = 1000.0, half_angle: float = 0.05, freq: float = 2.0) -> np.ndarray:
    """Exact increments of classical coning (Ignagni 1990): ω = [−aΩ sinΩt, aΩ cosΩt, ...] form
    integrated in closed form; a = 2 sin(α/2) Ω sin(α/2)... (increments only need to be realistic:
    both sides get the same ones)."""
    dt = 1.0 / rate
    Om = 2 * np.pi * freq
    a = half_angle
    t0 = np.arange(n) * dt
    t1 = t0 + dt
    c = 2 * np.sin(a / 2)
    ix = c * (np.cos(Om * t1) - np.cos(Om * t0))
    iy = c * (np.sin(Om * t1) - np.sin(Om * t0))
    iz = -2 * np.sin(a / 2) ** 2 * Om * dt * np.ones(n)
    return np.stack([ix, iy, iz], 1)


def random_motion(n: int, rate: float = 1000.0, seed: int = 8) -> np.ndarray:
    """Smooth random body rate with ≈ 1 rad/s rms per axis, sampled at 1 kHz."""
    rng = np.random.default_rng(seed)
    k = 64
    w = np.cumsum(rng.normal(size=(n // k + 2, 3)), axis=0)
    w = (w - w.mean(0)) / w.std(0)
    tt = np.arange(n) / k
    wi = np.stack([np.interp(tt, np.arange(w.shape[0]), w[:, i]) for i in range(3)], 1)
    return wi / rate


def noise_limit(n_updates: int) -> float:
    """Rounding-noise limit of the Q2.30 quaternion (docs/fixed-point.md): per
    update the 4 components are rounded (uniform, var LSB²/12); the 3 of them
    orthogonal to Q turn the attitude by 2δ: angle variance 4·3/12 = 1 LSB²
    per update, rms angle after N updates = LSB·√N."""
    return LSB * float(np.sqrt(n_updates))


MOTIONS = {"paper-sinusoid": paper_sinusoid, "coning": coning, "random-1rad/s": random_motion}
