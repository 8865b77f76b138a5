"""How honest the attitude filter's reported covariance is on real recordings (BROAD).

BROAD: D. Laidig, M. Caruso, A. Cereatti, T. Seel, "BROAD — A Benchmark for Robust
Inertial Orientation Estimation", Data 6(7), 2021, doi:10.3390/data6070072 (CC BY 4.0).

Per trial, over the movement samples with a valid reference (BROAD's scored samples):
the true attitude error δθ (``attitude_c.uncertainty.attitude_error``: q_ref = exp(δθ) ⊗
q_est, ENU) against the covariance the filter reports after that sample
(``ahrs(..., covariance=True)``: P, the heading's field term and the turn term):
the fraction inside the 3σ ellipsoid (δθᵀ P⁻¹ δθ ≤ 9;
a consistent Gaussian error: 97.1 %), the fraction whose heading error is within 3σ_ψ
(99.7 %), the median reported σ; before (``turn_sigma = 0``: without the turn term)
and after (the defaults, with the fast-turn term). The accuracy of both and VQF's
(``VQF(1/rate)``, defaults, 9-D) from the same run: ``turn_sigma`` enters the reported
covariance only, so the attitudes are bit-identical and the accuracy cost is zero.

    python -m bench.broad_uncertainty [--quick] [--data DIR]
    invoke bench --only broad_uncertainty              # docs/bench/broad_uncertainty.md
"""

from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np

TITLE = "The attitude filter's reported covariance on BROAD: 3σ coverage per trial"


def _run(tr: Any, precision: str = "f64", **kw: Any) -> tuple[np.ndarray, np.ndarray]:
    from attitude_c.ahrs_filter import ahrs

    q, c = ahrs(tr.gyr, tr.acc, tr.mag, rate=tr.rate, precision=precision, covariance=True, **kw)
    return np.asarray(q, float), np.asarray(c, float)


def _observable(tr: Any) -> float:
    """Fraction of the movement samples flagged heading-observable (streaming, blocks of 1 s)."""
    from attitude_c.ahrs_filter import Ahrs

    f = Ahrs(rate=tr.rate)
    step = max(1, round(tr.rate))
    obs = np.zeros(tr.n, bool)
    for a in range(0, tr.n, step):  # the flag of each block's last sample stands for the block
        f.update(tr.gyr[a:a + step], tr.acc[a:a + step], tr.mag[a:a + step])
        obs[a:a + step] = f.heading_observable
    return float(np.mean(obs[tr.movement]))


def run(quick: bool = False, data: str | None = None) -> str:
    from attitude_c import broad
    from attitude_c.ahrs_filter import default_settings
    from attitude_c.uncertainty import attitude_error, coverage
    from bench.broad import run_vqf

    paths = broad.find_trials(data or None)
    if quick:
        paths = paths[:3]
    turn = default_settings()["turn_sigma"]
    rows, tot = [], {"before": [], "after": [], "VQF": []}
    f32_gap = 0.0
    for p in paths:
        tr = broad.load_trial(p)
        ok = tr.movement & np.isfinite(tr.quat).all(axis=1)
        cells = [tr.name]
        for label, kw in (("before", {"turn_sigma": 0.0}), ("after", {})):
            q, c = _run(tr, **kw)
            cv = coverage(attitude_error(q, tr.quat), c, mask=ok)
            sig = np.degrees(np.sqrt(np.median(c[ok][:, [0, 1, 2], [0, 1, 2]], axis=0)))
            err = broad.errors(q, tr.quat, tr.movement)
            tot[label].append(err.total)
            cells += [f"{100 * cv.ellipsoid:.1f} / {100 * cv.heading:.1f}", f"{sig[0]:.2f} / {sig[2]:.2f}"]
        q32, _ = _run(tr, "f32")
        f32_gap = max(f32_gap, float(np.degrees(np.nanmax(broad.error_angles(q32, q)[0]))))
        tot["VQF"].append(broad.errors(run_vqf(tr), tr.quat, tr.movement).total)
        cells += [f"{100 * _observable(tr):.0f}", f"{err.heading:.2f}", f"{tot['after'][-1]:.2f}",
                  f"{tot['VQF'][-1]:.2f}"]
        rows.append("| " + " | ".join(cells) + " |")
    out = [f"BROAD: {broad.CITATION}. {len(paths)} trials; movement samples with a valid reference. "
           "Inside 3σ: the ellipsoid δθᵀP⁻¹δθ ≤ 9 (a consistent Gaussian error: "
           f"{100 * coverage(np.zeros((1, 3)), np.eye(3)[None]).expected_ellipsoid:.1f} %) / the heading "
           "|δθ_z| ≤ 3σ_ψ (99.7 %). *Before*: `turn_sigma = 0` (the Kalman filter's P and the "
           "heading's field term, docs/ahrs.md \"Uncertainty\"); *after*: "
           f"the defaults (`turn_sigma = {turn:g}`, reported covariance only). σ: median reported "
           "1σ, inclination (east axis) / heading, degrees. Heading observable: % of the movement "
           "samples without `ATT_AHRS_F_NO_HEADING` (1 s blocks). Heading, total: BROAD's RMS heading "
           "and total errors (°), the same for before and after.\n",
           "| trial | before: inside 3σ, ellipsoid / heading % | before: σ incl / head ° | after: inside 3σ, "
           "ellipsoid / heading % | after: σ incl / head ° | heading observable % | heading ° (ours) | "
           "total ° (ours) | total ° (VQF) |",
           "|---|---|---|---|---|---|---|---|---|", *rows]
    same = all(math.isclose(a, b, rel_tol=0, abs_tol=0) for a, b in zip(tot["before"], tot["after"]))
    out.append("\nAccuracy (total °): " + ", ".join(
        f"{k}: mean {np.mean(v):.3f}, worst {np.max(v):.2f}" for k, v in tot.items())
        + f". Before and after {'identical' if same else 'DIFFER'} (the term is reported only). "
        f"Float build vs double: largest angle between their attitudes {f32_gap:.4f}°.")
    return "\n".join(out)


if __name__ == "__main__":  # pragma: no cover
    data = sys.argv[sys.argv.index("--data") + 1] if "--data" in sys.argv else None
    print(run(quick="--quick" in sys.argv, data=data))
