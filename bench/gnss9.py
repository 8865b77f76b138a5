"""ARMv4T cost of GNSS aiding: the MEMS AHRS paper's nine-state filter
(csrc/include/attitude/ahrs_gnss9.h) — instructions per IMU sample, per GNSS velocity update and
per magnetic heading update — and att_ahrs's velocity aiding (ahrs.h, att_ahrs_update_vel) — per
IMU sample without and with aiding, per GNSS update — on the emulated ARM920T core (exact counts,
toolchain/qemu_count.py), double and float."""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path

from bench.armv4t import CLOCK_HZ, CPI
from toolchain import targets as T
from toolchain.qemu_count import per_iteration

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "bench" / "gnss9_armv4t.c"
AHRS_SRC = ROOT / "bench" / "ahrs_gnss_armv4t.c"
TITLE = ("ARMv4T cost of GNSS aiding: the nine-state filter and att_ahrs's velocity aiding "
         "(instructions per IMU sample and per update)")
EVERY = 5  #: the harness's aiding period and the default kf_period (gnss9_armv4t.c)


def _args(mode: str, n: int) -> list[str]:
    return [mode, str(n)]


def counts(precision: str, tmp: Path, n1: int = 100, n2: int = 200) -> dict[str, float]:
    """mode -> instructions per IMU sample (means over whole prediction periods)."""
    t = T.load("armv4t-bare")
    exe = t.build_program([SRC], tmp / f"gnss9_{precision}", defines=["ATT_REAL_F32"] if precision == "f32" else [])
    return {m: per_iteration(exe, functools.partial(_args, m), n1, n2) for m in ("imu", "gnss", "heading")}


def ahrs_counts(precision: str, tmp: Path, n1: int = 100, n2: int = 200) -> dict[str, float]:
    """att_ahrs: instructions per IMU sample unaided, per aided sample and per GNSS update."""
    t = T.load("armv4t-bare")
    exe = t.build_program([AHRS_SRC], tmp / f"ahrs_gnss_{precision}",
                          defines=["ATT_REAL_F32"] if precision == "f32" else [])
    m = {mode: per_iteration(exe, functools.partial(_args, mode), n1, n2) for mode in ("imu", "gnss10", "gnss20")}
    return {"imu": m["imu"], "aided": 2 * m["gnss20"] - m["gnss10"], "update": 20 * (m["gnss10"] - m["gnss20"])}


def _ahrs_table(precisions: tuple[str, ...], tmp: Path) -> list[str]:
    out = [
        "",
        ("att_ahrs with a magnetometer (`bench/ahrs_gnss_armv4t.c`: a level turn at 0.2 rad/s, 10 m/s, "
         "100 samples/s; default settings but `gnss_window` 0, so every velocity is an update; the "
         "velocity valid 50 ms before the clock). With m10 and m20 the per-sample means with a "
         "velocity after every 10th and every 20th sample: per GNSS update 20 (m10 − m20) (the "
         "checks, the history's interpolation, two or three scalar updates with a general row, the "
         "injection, the re-basing of the history); per aided sample 2 m20 − m10 (no accelerometer "
         "update; the integral and the history). Without any velocity the filter does what it did "
         "before the aiding existed (docs/ahrs.md, \"GNSS velocity aiding\")."),
        "",
        "| build | per IMU sample, no GNSS | per IMU sample, aided | per GNSS update | µs @400 MHz (sample / aided / update) |",
        "|---|---|---|---|---|",
    ]
    for prec in precisions:
        c = ahrs_counts(prec, tmp)
        out.append(f"| {prec} | {c['imu']:,.0f} | {c['aided']:,.0f} | {c['update']:,.0f} "
                   f"| {_us(c['imu']):.1f} / {_us(c['aided']):.1f} / {_us(c['update']):.1f} |")
    return out


def _us(instr: float) -> float:
    return instr * CPI / CLOCK_HZ * 1e6


def run(quick: bool) -> str:
    precisions = ("f32",) if quick else ("f32", "f64")
    out = [
        ("Instructions on the emulated ARMv4T core (`qemu-arm -cpu ti925t`, exact counts, "
        "`toolchain/qemu_count.py`; difference of two runs of `bench/gnss9_armv4t.c`, 100 IMU samples apart; "
        "soft-float newlib libm, `-O2`; default settings, kf_period 5). Per IMU sample: the strapdown step and "
        f"a fifth of a Kalman prediction (9×9), as a mean. Per update: {EVERY} × (the per-sample mean with an "
        "update every 5th sample − without), the update and the feedback. Time at 400 MHz assumes "
        f"{CPI} cycles per instruction (docs/bench/armv4t.md)."),
        "",
        ("| build | per IMU sample (mean) | per GNSS velocity update | per magnetic heading update "
        "| µs @400 MHz (sample / GNSS / heading) |"),
        "|---|---|---|---|---|",
    ]
    with tempfile.TemporaryDirectory() as d:
        for prec in precisions:
            c = counts(prec, Path(d))
            imu, gnss, hd = c["imu"], EVERY * (c["gnss"] - c["imu"]), EVERY * (c["heading"] - c["imu"])
            out.append(f"| {prec} | {imu:,.0f} | {gnss:,.0f} | {hd:,.0f} "
                       f"| {_us(imu):.1f} / {_us(gnss):.1f} / {_us(hd):.1f} |")
        out += _ahrs_table(precisions, Path(d))
    return "\n".join(out) + "\n"
