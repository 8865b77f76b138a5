"""Host throughput of our integrator against the peers a user might pick.

Same data for everybody: the paper's sinusoidal motion (the simulator's
``paper`` trajectory) sampled at 100 Hz, as exact angle increments for our
increment methods and as the mean rate of each interval (Δθ/h) for the
rate-driven ones: ``imufusion`` (x-io Fusion's Python package, gyroscope
only: gain 0, start-up skipped) and ``ahrs`` (``ahrs.filters.AngularRate``,
closed-form quaternion exponential). Throughput is the best of a few
repetitions (``time.perf_counter``); accuracy is the largest attitude-angle
error against the exact truth over the run.
"""

from __future__ import annotations

import importlib.metadata as md
import math
import time
from typing import Any, Callable

import numpy as np

TITLE = "Peers: our integrator vs imufusion and ahrs (host)"


def _best(fn: Callable[[], Any], reps: int) -> tuple[float, Any]:
    best, out = float("inf"), None
    for _ in range(reps):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def _version(pkg: str) -> str:
    try:
        return md.version(pkg)
    except md.PackageNotFoundError:
        return "not installed"


def run(quick: bool = False) -> str:
    import attitude_c
    from attitude_c.sim import PaperTrajectory
    from attitude_c.sim import attitude_angle as quat_angle_between

    h = 0.01
    n_peer = 6_000 if quick else 60_000  # peers loop in Python: 60 s or 600 s of data
    n_ours = 300_000 if quick else 3_000_000  # 30 000 s of data for the batch call
    reps = 2 if quick else 5
    tr = PaperTrajectory()
    # the batch timing runs the first 300 000 increments (50 min of motion) over
    # and over: the throughput does not depend on the data being continuous
    base = tr.increments(0.0, h, min(n_ours, 300_000))
    inc_all = np.ascontiguousarray(np.tile(base, (n_ours // len(base), 1)))
    q0 = tr.quat(0.0)
    rows: list[tuple[str, str, float, float | None]] = []  # name, data, samples/s, max error

    def err_of(q: np.ndarray, k_per: int, offset: float = 1.0, n: int | None = None) -> float:
        m = len(q)
        t = (np.arange(1, m + 1) * k_per - 1 + offset) * h
        return float(np.max(quat_angle_between(tr.quat(t), q)))

    per = {m: attitude_c.names.samples_per_update(m) for m in attitude_c.INCREMENT_METHODS}
    inc_peer = inc_all[:n_peer]
    precs = ["f64", "f32", "fixed"]
    for prec in precs:
        for m, k in per.items():
            dt, q = _best(lambda m=m, prec=prec: attitude_c.integrate(inc_all, method=m, q0=q0,
                                                                         precision=prec), reps)
            qp = attitude_c.integrate(inc_peer, method=m, q0=q0, precision=prec)
            rows.append((f"attitude_c.integrate {m} {prec}", "batch (C)", n_ours / dt,
                         err_of(qp, k)))
    # per-sample calls from Python, the way a streaming user calls us
    if hasattr(attitude_c, "Integrator"):
        integ = attitude_c.Integrator("rv3", q0, "f64")

        def loop_ours() -> np.ndarray:
            integ.reset(q0) if _takes_arg(integ.reset) else integ.reset()
            for i in range(n_peer):
                integ.update(inc_peer[i])  # (3,): the one-sample fast path
            return integ.q
        dt, _ = _best(loop_ours, reps)
        rows.append(("attitude_c.Integrator rv3 f64", "per-sample Python loop", n_peer / dt, None))
    rates = inc_peer / h
    try:
        import imufusion

        def fusion() -> np.ndarray:
            s = imufusion.AhrsSettings()
            s.gain = 0.0
            s.convention = imufusion.CONVENTION_ENU
            s.sample_rate = 1.0 / h
            a = imufusion.Ahrs()
            a.set_settings(s)
            a.set_quaternion(q0.copy())
            a.skip_startup()
            g = np.degrees(rates)
            acc = np.array([0.0, 0.0, 1.0])
            out = np.empty((n_peer, 4))
            for i in range(n_peer):
                a.update_no_magnetometer(g[i], acc)
                out[i] = a.get_quaternion()
            return out
        dt, q = _best(fusion, reps)
        rows.append((f"imufusion {_version('imufusion')} (gain 0)", "per-sample Python loop",
                     n_peer / dt, err_of(q, 1)))
    except ImportError:
        rows.append(("imufusion", "not installed (pip install attitude-c[bench])", float("nan"), None))
    try:
        from ahrs.filters import AngularRate

        # AngularRate sets Q[0] = q0 and Q[t] = update(Q[t-1], gyr[t]) for t >= 1,
        # never using gyr[0]: a leading zero row lines Q[1:] up with our outputs
        gyr_in = np.vstack([np.zeros(3), rates])

        def ahrs_run() -> np.ndarray:
            return np.asarray(AngularRate(gyr=gyr_in, q0=q0.copy(), frequency=1.0 / h).Q)
        dt, q = _best(ahrs_run, max(1, reps // 2))
        rows.append((f"ahrs {_version('ahrs')} AngularRate", "whole array (Python loop inside)",
                     n_peer / dt, err_of(q[1:], 1)))
    except ImportError:
        rows.append(("ahrs", "not installed (pip install attitude-c[bench])", float("nan"), None))

    ref = next((r[2] for r in rows if r[0].startswith("imufusion") and not math.isnan(r[2])), None)
    lines = [
        (f"Paper trajectory at 100 Hz (h = {h} s): our batch call on {n_ours:,} increments, "
         f"per-sample loops and peers on {n_peer:,} samples ({n_peer * h:.0f} s). "
         "Max error: largest attitude-angle error against the exact truth over the first "
         f"{n_peer * h:.0f} s (our increment methods get exact increments, the peers the mean "
         "rate of each interval). Source: `bench/peers.py`."),
        "",
        "| implementation | how called | samples/s | vs imufusion | max error (rad) |",
        "|---|---|---:|---:|---:|",
    ]
    for name, how, rate, err in rows:
        sp = f"{rate / ref:.1f}×" if ref and not math.isnan(rate) else "—"
        r = f"{rate:,.0f}" if not math.isnan(rate) else "—"
        e = f"{err:.2e}" if err is not None else "—"
        lines.append(f"| {name} | {how} | {r} | {sp} | {e} |")
    lines += ["", ("imufusion with gain 0 is a first-order (Euler) quaternion update "
                   "q += ½ q ⊗ ω h, hence its larger error; ahrs AngularRate applies the "
                   "exponential of the rate held constant over the interval (like our rv1).")]
    return "\n".join(lines)


def _takes_arg(fn: Callable[..., Any]) -> bool:
    import inspect

    try:
        return len(inspect.signature(fn).parameters) >= 1
    except (TypeError, ValueError):
        return False


if __name__ == "__main__":  # pragma: no cover
    print(run(quick=True))
