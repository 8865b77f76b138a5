"""Leave-one-trial-out choice of the filter's magnetic settings on BROAD, judged by the worst trial too.

BROAD: D. Laidig, M. Caruso, A. Cereatti, T. Seel, "BROAD — A Benchmark for Robust
Inertial Orientation Estimation", Data 6(7), 2021, doi:10.3390/data6070072
(CC BY 4.0); metric, loading and VQF as ``bench/broad.py`` (whose functions this
module reuses).

1. Every point of a small grid of the settings that decide how far the heading
   trusts the field (``GRID``) is run on every trial once; VQF (defaults) too.
2. Leave one trial out: for each trial the grid point is chosen on the other 14 and
   scored on it, by two rules — the mean total error of the 14 alone, and the
   worst-case-aware rule (the mean plus ``WORST_WEIGHT`` degrees per unit of the
   largest per-trial ratio to VQF among the 14: 0.02° of mean buys 0.4 of that
   ratio). The held-out figures: per-group means beside VQF's, and the distribution
   of the per-trial ratio to VQF (min / median / max, count above 1.5×).
3. The choice of each rule on all 15 trials, and where the frozen defaults stand.
4. Start-up: each undisturbed trial started at several offsets within its first,
   static seconds, heading RMS over the movement phases: the spread across offsets
   with the defaults and with a reference taken from one sample
   (``mag_ref_window`` = 0).

    python -m bench.broad_loo [--quick] [--data DIR]
    invoke bench --only broad_loo        # docs/bench/broad_loo.md
"""

from __future__ import annotations

import itertools
import statistics
import sys
import time
from typing import Any

import numpy as np

from bench.broad import group_means, run_ours, run_vqf, score

TITLE = "Leave-one-trial-out choice of the magnetic settings on BROAD (mean and worst trial)"

#: the settings that decide how far the heading trusts the field, around the defaults
#: (the default first in each list: of equal scores, the first point is chosen)
GRID: dict[str, list[float]] = {
    "mag_norm_tol": [0.08, 0.05, 0.1],
    "mag_dip_tol": [0.17, 0.25],
    "mag_noise": [0.1, 0.05],
    "mag_ref_window": [5.0, 2.0, 10.0],
}
#: degrees of mean total error one unit of the worst per-trial ratio to VQF is worth
WORST_WEIGHT = 0.05
#: start offsets (s) for the start-up spread, all within BROAD's static first seconds
OFFSETS = (0.0, 0.5, 1.0, 1.5, 2.0)


def points(quick: bool) -> list[dict[str, float]]:
    grid = {k: v[::2] for k, v in GRID.items()} if quick else GRID
    return [dict(zip(grid, vals)) for vals in itertools.product(*grid.values())]


def objective(tot: np.ndarray, ratio: np.ndarray, rule: str) -> float:
    """The rule's score of one grid point over some trials (lower is better)."""
    return float(tot.mean() + (WORST_WEIGHT * ratio.max() if rule == "worst-aware" else 0.0))


def leave_one_out(tot: np.ndarray, vqf: np.ndarray, rule: str) -> tuple[np.ndarray, list[int]]:
    """tot: (points, trials) total errors. Per trial, the point chosen on the others and
    its total on the held-out trial."""
    n = tot.shape[1]
    held, chosen = np.empty(n), []
    for i in range(n):
        rest = [j for j in range(n) if j != i]
        k = min(range(len(tot)), key=lambda p: objective(tot[p, rest], tot[p, rest] / vqf[rest], rule))
        chosen.append(k)
        held[i] = tot[k, i]
    return held, chosen


def distribution(ratio: np.ndarray) -> str:
    return (f"{ratio.min():.2f} / {statistics.median(ratio):.2f} / {ratio.max():.2f}, "
            f"{int(np.count_nonzero(ratio > 1.5))} above 1.5×")


def kw_text(kw: dict[str, float]) -> str:
    return ", ".join(f"{k} {v:g}" for k, v in kw.items())


def start_spread(trials: list[Any]) -> list[str]:
    """Heading RMS per start offset, undisturbed trials, defaults vs a one-sample reference."""
    from attitude_c import broad
    from attitude_c.ahrs_filter import ahrs

    out = ["| trial | " + " | ".join(f"defaults, start {o:g} s" for o in OFFSETS)
           + " | spread, defaults | spread, mag_ref_window 0 |", "|---|" + "---|" * (len(OFFSETS) + 2)]
    spreads: dict[str, list[float]] = {"d": [], "0": []}
    for t in (t for t in trials if not t.disturbed):
        row = {}
        runs: tuple[tuple[str, dict[str, Any]], ...] = (("d", {}), ("0", {"mag_ref_window": 0.0}))
        for label, kw in runs:
            hs = []
            for o in OFFSETS:
                k = round(o * t.rate)
                q = np.asarray(ahrs(t.gyr[k:], t.acc[k:], t.mag[k:], rate=t.rate, **kw), dtype=np.float64)
                hs.append(broad.errors(q, t.quat[k:], t.movement[k:]).heading)
            row[label] = hs
            spreads[label].append(max(hs) - min(hs))
        out.append(f"| {t.name} | " + " | ".join(f"{h:.2f}" for h in row["d"])
                   + f" | {spreads['d'][-1]:.2f} | {spreads['0'][-1]:.2f} |")
    out.append(f"\nLargest spread of the heading RMS across start offsets: defaults **{max(spreads['d']):.2f}°** "
               f"(mean {np.mean(spreads['d']):.2f}°), one-sample reference {max(spreads['0']):.2f}° "
               f"(mean {np.mean(spreads['0']):.2f}°).")
    return out


def run(quick: bool = False, data: str | None = None) -> str:
    from attitude_c import broad
    from attitude_c.ahrs_filter import default_settings

    trials = [broad.load_trial(p) for p in broad.find_trials(data or None)]
    names = [t.name[:2] for t in trials]
    vqf = np.array([f.total for f in score(trials, [run_vqf(t) for t in trials])])
    pts = points(quick)
    tot = np.array([[f.total for f in score(trials, [run_ours(t, "f64", **kw) for t in trials])] for kw in pts])
    d = default_settings()
    dflt = next(i for i, kw in enumerate(pts) if all(d[k] == v for k, v in kw.items()))
    gv = group_means(trials, score(trials, [run_vqf(t) for t in trials]))
    out = [f"BROAD: {broad.CITATION}. {len(trials)} trials; metric of the BROAD paper, total error, degrees "
           "(mean of per-trial RMS over movement phases); VQF 2.1.2 defaults (`VQF(1/rate)`, 9-D) in the same "
           f"run. Grid ({len(pts)} points, every other setting at its default): "
           + "; ".join(f"{k} {v}" for k, v in (GRID if not quick else {k: v[::2] for k, v in GRID.items()}).items())
           + f". Worst-aware rule: mean + {WORST_WEIGHT}° × largest ratio to VQF.\n",
           "**Leave one trial out** (each trial scored with the grid point chosen on the other 14):\n",
           ("| rule | held-out mean total | undisturbed | disturbed | ratio to VQF: min / median / max | "
            "points chosen |"), "|---|---|---|---|---|---|"]
    und = np.array([not t.disturbed for t in trials])
    for rule in ("mean", "worst-aware"):
        held, chosen = leave_one_out(tot, vqf, rule)
        r = held / vqf
        picks = sorted({kw_text(pts[k]) for k in chosen})
        out.append(f"| {rule} | **{held.mean():.3f}** | {held[und].mean():.3f} | {held[~und].mean():.3f} | "
                   f"{distribution(r)} | {'; '.join(picks)} |")
    out.append(f"| VQF | {vqf.mean():.3f} | {gv['undisturbed']['total']:.3f} | {gv['disturbed']['total']:.3f} "
               "| 1 | — |")
    out.append("\n**Chosen on all 15** (in-sample) and the frozen defaults:\n")
    out.append("| choice | settings | mean total | undisturbed | disturbed | ratio to VQF: min / median / max | "
               "per trial (" + " ".join(names) + ") |")
    out.append("|---|---|---|---|---|---|---|")
    for label, k in (("rule: mean", min(range(len(pts)), key=lambda p: objective(tot[p], tot[p] / vqf, "mean"))),
                     ("rule: worst-aware", min(range(len(pts)),
                                               key=lambda p: objective(tot[p], tot[p] / vqf, "worst-aware"))),
                     ("frozen defaults", dflt)):
        r = tot[k] / vqf
        out.append(f"| {label} | {kw_text(pts[k])} | {tot[k].mean():.3f} | {tot[k][und].mean():.3f} | "
                   f"{tot[k][~und].mean():.3f} | {distribution(r)} | " + " ".join(f"{x:.2f}" for x in r) + " |")
    out.append("\nVQF per trial (total, °): " + ", ".join(f"{n} {v:.2f}" for n, v in zip(names, vqf)) + ".\n")
    out.append("**Start-up** (undisturbed trials started later by the offset; heading RMS over the movement "
               "phases, °):\n")
    out.extend(start_spread(trials))
    return "\n".join(out)


if __name__ == "__main__":  # pragma: no cover
    t0 = time.time()
    print(run(quick="--quick" in sys.argv, data=sys.argv[sys.argv.index("--data") + 1] if "--data" in sys.argv
              else None))
    print(f"\n({time.time() - t0:.0f} s)", file=sys.stderr)
