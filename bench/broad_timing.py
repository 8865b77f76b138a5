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
4. The output's lag behind the optical reference (no filter can observe it: it is
   between the IMU and the cameras), per trial for this filter (defaults) and VQF:
   the lag d that best explains the horizontal part of the error rotation
   e = q_est ⊗ q_ref⁻¹ as −d·ω_n (ω_n the rate in the navigation frame, from the
   reference attitude; least squares over the movement phases), and the BROAD
   inclination before and after the estimate is turned by exp(d·ω_n). What is left
   after is the part of the inclination error that is not timing.
5. The same output prediction given to both filters: d = the median of this
   filter's per-trial lags of item 4 (fitted WITH the reference), as this filter's
   ``sensor_delay`` and, for VQF, its 9-D output turned by exp((ω − b̂)·d) in the body
   frame with VQF's own bias estimate b̂ (the same formula as ``sensor_delay``). It
   shows which filter is ahead once neither pays for the IMU-to-camera timing.

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


def output_lag(q: np.ndarray, t: Any) -> tuple[float, float, float]:
    """(d [s], inclination RMS [°] of q, the same with the fitted lag term removed)
    for one trial: see item 4 of the module docstring."""
    from attitude_c import broad
    from attitude_c import reference as ref

    q_ref = np.asarray(t.quat, float)
    ok = np.asarray(t.movement, bool) & np.all(np.isfinite(q_ref), axis=1)
    e = ref.quat_to_rotvec(ref.quat_multiply(q[ok], ref.quat_conj(q_ref[ok])))
    w_n = np.einsum("nij,nj->ni", ref.quat_to_dcm(q_ref[ok]), t.gyr[ok])
    d = -float(np.sum(e[:, :2] * w_n[:, :2]) / np.sum(w_n[:, :2] ** 2))
    q_fix = q.copy()
    q_fix[ok] = ref.quat_multiply(ref.rotvec_to_quat(d * w_n), q[ok])
    before = broad.errors(q, q_ref, t.movement).inclination
    after = broad.errors(q_fix, q_ref, t.movement).inclination
    return d, before, after


def _have_vqf() -> bool:
    try:
        import vqf  # noqa: F401  (bench extra: pip install -e ".[bench]")
    except ImportError:
        return False
    return True


def vqf_predicted(t: Any, d: float) -> np.ndarray:
    """VQF's 9-D output (defaults, as in bench/broad.py) turned forward by d seconds:
    q ⊗ exp((ω − b̂)·d), b̂ VQF's own bias estimate (``sensor_delay``'s formula)."""
    from attitude_c import reference as ref
    from bench.broad import run_vqf_batch

    out = run_vqf_batch(t)
    w = np.asarray(t.gyr, float) - np.asarray(out["bias"], float)
    return np.asarray(ref.quat_multiply(np.asarray(out["quat9D"], float), ref.rotvec_to_quat(w * d)))


def lag_table(trials: list[Any]) -> tuple[list[str], list[float]]:
    """Item 4: the output's lag behind the reference, this filter and VQF; and this
    filter's per-trial lags (s)."""
    from bench.broad import run_vqf

    have_vqf = _have_vqf()
    out = [("**The output's lag behind the optical reference** (item 4 of the module docstring; ms, and BROAD "
            "inclination RMS in °, before → after the fitted lag term is removed; VQF 2 with its defaults as in "
            "the *broad* section). Not a filter property: it lies between the IMU's clock and the cameras'.\n"),
           "| trial | lag, this filter | inclination | lag, VQF | inclination, VQF |", "|---|---|---|---|---|"]
    rows = []
    for t in trials:
        a = output_lag(run_ours(t), t)
        b = output_lag(np.asarray(run_vqf(t), float), t) if have_vqf else (float("nan"),) * 3
        rows.append((a, b))
        out.append(f"| {t.name} | {a[0] * 1e3:.2f} | {a[1]:.3f} → {a[2]:.3f} | {b[0] * 1e3:.2f} | "
                   f"{b[1]:.3f} → {b[2]:.3f} |")
    mean = [float(np.mean([r[k][i] for r in rows])) for k in (0, 1) for i in (1, 2)]
    out.append(f"| **mean** | | **{mean[0]:.3f} → {mean[1]:.3f}** | | **{mean[2]:.3f} → {mean[3]:.3f}** |")
    if not have_vqf:
        out.append("\n(VQF not installed: its columns are empty; `pip install -e \".[bench]\"`.)")
    return out, [r[0][0] for r in rows]


def prediction_table(trials: list[Any], lags: list[float], dm: float) -> list[str]:
    """Item 5: both filters given the same output prediction d (the median lag)."""
    d = round(statistics.median(lags), 4)
    rows: list[tuple[str, list[np.ndarray]]] = [
        ("this filter, defaults", [run_ours(t) for t in trials]),
        (f"this filter, `sensor_delay` = {d * 1e3:g} ms", [run_ours(t, sensor_delay=d) for t in trials]),
        (f"this filter, `sensor_delay` = {d * 1e3:g} ms, `mag_delay` = {dm * 1e3:g} ms, `acc_delay` = 5 ms",
         [run_ours(t, sensor_delay=d, mag_delay=dm, acc_delay=0.005) for t in trials])]
    if _have_vqf():
        rows += [("VQF, defaults", [vqf_predicted(t, 0.0) for t in trials]),
                 (f"VQF, output turned forward by {d * 1e3:g} ms", [vqf_predicted(t, d) for t in trials])]
    out = [(f"\n**The same output prediction for both filters** (item 5: d = {d * 1e3:g} ms, the median of this "
            "filter's per-trial lags above, fitted WITH the reference; mean of per-trial RMS, °):\n"),
           "| filter, settings | total | heading | inclination | disturbed (total) | undisturbed (total) |",
           "|---|---|---|---|---|---|"]
    for label, qs in rows:
        gm = group_means(trials, score(trials, qs))
        m = gm["all"]
        out.append(f"| {label} | {m['total']:.3f} | {m['heading']:.3f} | {m['inclination']:.3f} | "
                   f"{gm.get('disturbed', {}).get('total', float('nan')):.3f} | "
                   f"{gm.get('undisturbed', {}).get('total', float('nan')):.3f} |")
    return out


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
               f"total RMS to double {dmax:.4f}°.\n")
    lag_lines, lags = lag_table(trials)
    out += lag_lines
    out += prediction_table(trials, lags, dm)
    return "\n".join(out)


if __name__ == "__main__":  # pragma: no cover
    data = sys.argv[sys.argv.index("--data") + 1] if "--data" in sys.argv else None
    t0 = time.time()
    print(run(quick="--quick" in sys.argv, data=data))
    print(f"\n({time.time() - t0:.0f} s)", file=sys.stderr)
