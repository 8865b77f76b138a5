"""ARMv4T cost of attitude-rx's filter path: instructions per sample on the
emulated ARM920T core (exact counts, toolchain/qemu_count.py) of the library
calls attitude-rx makes for one sample of an aided stream (records decoded and
numbered, codes converted, att_ahrs_update, the line's angles, bias and flags;
and the JSON line formatted), and the share of a 400 MHz ARM920T at 200
samples/s and at the aided board's sampling plan (toolchain.firmware.AIDED)."""

from __future__ import annotations

import math
import os
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from bench.armv4t import CLOCK_HZ, CPI
from toolchain import targets as T
from toolchain.firmware import AIDED
from toolchain.qemu_count import count_instructions

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "bench" / "rx_filter_armv4t.c"
TITLE = "ARMv4T cost of attitude-rx's filter path (instructions per sample, share of a 400 MHz ARM920T)"
RATE = 200.0  #: samples/s of the harness's stream (rx_filter_armv4t.c) and of the first share column
TABLE = 1024  #: samples per turn of the harness's field table
#: The gyro-only sample's cost comes from a run with aiding in every GYRO_EVERY-th sample:
#: GYRO_EVERY x its mean - the full sample's, over GYRO_EVERY - 1
GYRO_EVERY = 2
#: One counted run (a few hundred million logged instructions) may take this long on a loaded machine
QEMU_TIMEOUT_S = 3600.0
#: The builds measured: attitude-rx's (double) and the float one (ATT_REAL_F32)
PRECISIONS = ("f64", "f32")


def _counts(quick: bool, tmp: Path) -> dict[tuple[str, str, int], float]:
    """(precision, mode, every) -> instructions per sample."""
    from attitude_c.ahrs_filter import default_settings

    t = T.load("armv4t-bare")
    # both runs end past the reported inclination's running-mean start (tilt_tau at 200 Hz), their
    # difference one turn of the field table (the quick run: an eighth of a turn)
    n1 = math.ceil(default_settings()["tilt_tau"] * RATE) + 100
    n2 = n1 + (TABLE // 8 if quick else TABLE)
    exe = {p: t.build_program([SRC], tmp / f"rx_filter_{p}", defines=["ATT_REAL_F32"] if p == "f32" else [])
           for p in PRECISIONS}
    keys = [(p, *m) for p in PRECISIONS
            for m in sorted({("path", 1), ("path", GYRO_EVERY), ("path", AIDED.acc_every), ("line", 1)})]
    runs = [(k, n) for k in keys for n in (n1, n2)]

    def count(run: tuple[tuple[str, str, int], int]) -> int:
        (prec, mode, every), n = run
        return count_instructions(exe[prec], _args(mode, every, n), timeout=QEMU_TIMEOUT_S)

    with ThreadPoolExecutor(max_workers=min(2, os.cpu_count() or 1)) as pool:  # independent runs, exact counts
        got = dict(zip(runs, pool.map(count, runs)))
    return {k: (got[(k, n2)] - got[(k, n1)]) / (n2 - n1) for k in keys}


def _args(mode: str, every: int, n: int) -> list[str]:
    """rx_filter_armv4t's arguments for n samples."""
    return [mode, str(every), str(n)]


def _us(instr: float) -> float:
    return instr * CPI / CLOCK_HZ * 1e6


def _share(instr: float, rate: float) -> float:
    return 100.0 * instr * CPI * rate / CLOCK_HZ


def run(quick: bool) -> str:
    if AIDED.acc_every != AIDED.mag_every:
        raise ValueError("the harness sends accelerometer and magnetometer together: the plan's decimations differ")
    every, g = AIDED.acc_every, GYRO_EVERY
    plan_rate = 1.0 / AIDED.period_s
    plan_txt = f"gyros {plan_rate:.0f}/s, " + ("acc + mag in each" if every == 1 else f"acc + mag every {every}")
    with tempfile.TemporaryDirectory() as d:
        c = _counts(quick, Path(d))
    rows = []
    for prec in PRECISIONS:
        full, line = c[(prec, "path", 1)], c[(prec, "line", 1)]
        gyro_only = (g * c[(prec, "path", g)] - full) / (g - 1)
        rows.append((prec, full, gyro_only, c[(prec, "path", every)], line - full))
    out = [
        ("Instructions per sample on the emulated ARMv4T core (`qemu-arm -cpu ti925t`, exact counts with "
        "`-singlestep -d nochain,exec`, `toolchain/qemu_count.py`; difference of two runs of "
        f"`bench/rx_filter_armv4t.c` past the filter's start, {TABLE // 8 if quick else TABLE} samples apart; "
        "soft-float newlib libm, `-O2`). The path is what attitude-rx's attitude thread does per sample of an "
        "aided stream (`csrc/app/attitude_rx.c`): the sample's records decoded and numbered "
        "(`att_block_seq_decode`), converted (`att_sensor_convert`, accelerometer and magnetometer with a "
        "correction matrix and bias), one `att_ahrs_update` (default settings; NULL aiding when the sample has "
        "none), the line's Euler angles, heading, bias and flags. The JSON line (snprintf of its 23 numbers "
        "with 17 digits, newlib; the board's glibc differs) is counted apart. Time at 400 MHz assumes "
        f"{CPI} cycles per instruction (docs/bench/armv4t.md)."),
        "",
        (f"| build | gyro + acc + mag | gyro only (filter prediction) | the plan ({plan_txt}), mean "
        "| + the JSON line | µs @400 MHz (full / + line) |"),
        "|---|---|---|---|---|---|",
    ]
    for prec, full, gyro_only, plan, line in rows:
        out.append(f"| {prec} | {full:,.0f} | {gyro_only:,.0f} | {plan:,.0f} | +{line:,.0f} "
                   f"| {_us(full):.1f} / {_us(full + line):.1f} |")
    out += [
        "",
        (f"(gyro only: derived from a run with aiding in one sample of {g}: {g} × its mean − the full sample, "
        f"over {g - 1}.)"),
        "",
        "Share of a 400 MHz ARM920T:",
        "",
        (f"| build | {RATE:.0f} samples/s, acc + mag in each | + JSON lines | the aided board's plan: "
        f"{plan_txt} (toolchain.firmware.AIDED) | + JSON lines |"),
        "|---|---|---|---|---|",
    ]
    for prec, full, _, plan, line in rows:
        out.append(f"| {prec} | {_share(full, RATE):.2f} % | {_share(full + line, RATE):.2f} % "
                   f"| {_share(plan, plan_rate):.2f} % | {_share(plan + line, plan_rate):.2f} % |")
    return "\n".join(out) + "\n"
