"""Aiding-sensor time alignment on BROAD: the magnetometer's lag, estimated and compensated.

BROAD: D. Laidig, M. Caruso, A. Cereatti, T. Seel, "BROAD — A Benchmark for Robust
Inertial Orientation Estimation", Data 6(7), 2021, doi:10.3390/data6070072
(CC BY 4.0); metric and loading as ``bench/broad.py`` (whose functions this module
reuses).

1. Per trial, the reference-free estimate of the magnetometer's lag behind the gyro
   (``attitude_c.aiding_delay``: the filter's own attitude with the defaults, fit
   over the movement phases, 2 s high-pass), and the same after one iteration (the
   filter re-run with ``mag_delay`` = that trial's first estimate).
2. ``mag_delay`` = the median of the undisturbed trials' estimates (no reference
   used), scored with BROAD's metric against the defaults (``mag_delay`` = 0).
3. A scan of ``acc_delay`` (0, 2.5, 5, 7.5 ms) on top of it, scored WITH the
   reference: a diagnostic of how much BROAD's accelerometer lags, not a tuned
   default (the estimator does not work for an accelerometer: docs/ahrs.md).

The defaults of the filter stay 0: these lags are properties of BROAD's IMU.

    python -m bench.broad_timing [--quick] [--data DIR]
    invoke bench --only broad_timing        # docs/bench/broad_timing.md
"""

from __future__ import annotations

import statistics
import sys
import time
from typing import Any

import numpy as np

from bench.broad import group_means, run_ours, score

TITLE = "Aiding-sensor time alignment on BROAD (magnetometer lag estimate, acc/mag delay compensation)"

#: the accelerometer lags scanned on top of the estimated magnetometer lag (s)
ACC_SCAN = (0.0, 0.0025, 0.005, 0.0075)


def _undisturbed(t: Any) -> bool:
    return "undisturbed" in t.groups or "_undisturbed_" in t.name


def estimates(trials: list[Any], **settings: Any) -> list[float]:
    """Per trial the magnetometer lag (s) from the filter's attitude with ``settings``."""
    from attitude_c.timing import aiding_delay

    return [aiding_delay(t.gyr, t.mag, run_ours(t, **settings), t.rate, mask=np.asarray(t.movement, bool))
            for t in trials]


def run(quick: bool = False, data: str | None = None) -> str:
    from attitude_c import broad

    paths = broad.find_trials(data or None)
    trials = [broad.load_trial(p) for p in paths]
    if quick:  # smoke test: a third of the trials
        trials = trials[::3]
    d1 = estimates(trials)
    d2 = [estimates([t], mag_delay=float(np.clip(d, -0.05, 0.05)))[0] for t, d in zip(trials, d1)]
    und = [d for t, d in zip(trials, d1) if _undisturbed(t)]
    dm = round(statistics.median(und), 4)
    configs: list[tuple[str, dict[str, Any]]] = [("defaults (acc_delay = mag_delay = 0)", {}),
                                                   (f"mag_delay = {dm:g} (estimated, no reference)",
                                                    {"mag_delay": dm})]
    configs += [(f"mag_delay = {dm:g}, acc_delay = {a * 1e3:g} ms (scan, scored with the reference)",
                 {"mag_delay": dm, "acc_delay": a}) for a in ACC_SCAN if a > 0]
    figs = [score(trials, [run_ours(t, **kw) for t in trials]) for _, kw in configs]
    i5 = next(i for i, (_, kw) in enumerate(configs) if kw.get("acc_delay") == 0.005)
    intro = (f"BROAD: {broad.CITATION}. {len(trials)} trials; metric of the BROAD paper (`attitude_c.broad`), "
             "degrees, mean of per-trial RMS over movement phases; settings otherwise the frozen defaults. "
             "Estimates: `attitude_c.aiding_delay(gyr, mag, q, rate, mask=movement)` with q the filter's own "
             "attitude (no reference used); they are relative to the filter's attitude (docs/ahrs.md, "
             "\"Sensor timing\").\n")
    head = ("**Magnetometer lag per trial** (ms; 1st: from the defaults' attitude; 2nd: the filter re-run with "
            "`mag_delay` = the 1st) and the trial's total error (°) with the defaults, with `mag_delay` = the "
            "median below, and with that plus `acc_delay` = 5 ms:\n")
    out = [intro, head,
           "| trial | 1st estimate | 2nd (iterated) | total, defaults | total, mag_delay | total, + acc_delay 5 ms |",
           "|---|---|---|---|---|---|"]
    for i, (t, a, b) in enumerate(zip(trials, d1, d2)):
        out.append(f"| {t.name} | {a * 1e3:.2f} | {b * 1e3:.2f} | {figs[0][i].total:.3f} | {figs[1][i].total:.3f} | "
                   f"{figs[i5][i].total:.3f} |")
    out.append(f"\nUndisturbed trials ({len(und)}): {min(und) * 1e3:.2f}…{max(und) * 1e3:.2f} ms, median "
               f"**{dm * 1e3:.1f} ms** → `mag_delay = {dm:g}` below.\n")
    out += [("**BROAD figures** (mean of per-trial RMS, °; the acc_delay rows are a diagnostic scan scored "
             "WITH the reference, not a tuned default):\n"),
            "| settings | total | heading | inclination | disturbed (total) | undisturbed (total) |",
            "|---|---|---|---|---|---|"]
    for (label, _), fg in zip(configs, figs):
        gm = group_means(trials, fg)
        m = gm["all"]
        out.append(f"| {label} | {m['total']:.3f} | {m['heading']:.3f} | {m['inclination']:.3f} | "
                   f"{gm.get('disturbed', {}).get('total', float('nan')):.3f} | "
                   f"{gm.get('undisturbed', {}).get('total', float('nan')):.3f} |")
    kw: dict[str, Any] = {"mag_delay": dm, "acc_delay": 0.005}
    f64 = figs[i5]
    f32 = score(trials, [run_ours(t, "f32", **kw) for t in trials])
    dmax = max(abs(a.total - b.total) for a, b in zip(f64, f32))
    out.append(f"\nFloat build with mag_delay = {dm:g}, acc_delay = 5 ms: largest per-trial difference of the "
               f"total RMS to double {dmax:.4f}°.")
    return "\n".join(out)


if __name__ == "__main__":  # pragma: no cover
    data = sys.argv[sys.argv.index("--data") + 1] if "--data" in sys.argv else None
    t0 = time.time()
    print(run(quick="--quick" in sys.argv, data=data))
    print(f"\n({time.time() - t0:.0f} s)", file=sys.stderr)
