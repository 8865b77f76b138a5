"""The attitude filter on real recordings (BROAD), side by side with open filters.

BROAD: D. Laidig, M. Caruso, A. Cereatti, T. Seel, "BROAD — A Benchmark for
Robust Inertial Orientation Estimation", Data 6(7), 2021,
doi:10.3390/data6070072 (CC BY 4.0). The error metric is BROAD's
(``attitude_c.broad``): per trial the RMS over the movement phases of the
total, heading and inclination error of q_est ⊗ q_ref⁻¹, then the mean over
trials (all, undisturbed, disturbed).

Filters, all on the same trials in one run, each started from its own
first second at most (no filter is given the reference attitude); every
peer runs with its published default gains/noises — none is tuned on
BROAD, and neither is ours beyond the frozen defaults (the magnetic settings
chosen leave one trial out by ``bench/broad_loo.py``, the others once by the
coordinate descent below; the cross-validated table shows what tuning on
held-out trials would give):

* ``attitude_c`` — this library's filter (``attitude_c.ahrs``), frozen
  defaults, double and float builds;
* VQF (``vqf`` on PyPI, Laidig & Seel 2023): ``VQF(1/rate)`` with its
  default parameters, ``updateBatch`` (C++), 9-D output ``quat9D``;
  same units and frames as BROAD (its authors'); initialises itself;
* x-io Fusion (``imufusion``): ``AhrsSettings(sample_rate=rate,
  convention=ENU, gain=0.5, gyroscope_range=2000°/s,
  acceleration_rejection=10°, magnetic_rejection=10°,
  rejection_timeout=5 s)`` — gain 0.5 is Fusion's default, the rest the
  values of Fusion's README example — and its gyro offset corrector
  (``imufusion.Bias``, default settings); gyro in °/s, specific force in g
  (÷ 9.81), field as given (µT; only its direction matters); initialises
  itself (its start-up gain ramp);
* ``ahrs`` package (0.4) EKF: ``EKF(gyr, -acc, mag, frame="ENU",
  frequency=rate, magnetic_ref=dip, q0=q0)`` with its default noise
  variances (0.3², 0.5², 0.8²). Its ENU measurement model takes the
  accelerometer as the gravity direction (``a_ref = [0, 0, -1]``) whereas
  BROAD's reads specific force (+9.81 up at rest), so it is given
  ``-acc`` (with BROAD's sign it converged upside down, ~160° off on every
  trial: the figures before 2026-11-27 10:00 UTC). It cannot learn the
  field, so ``magnetic_ref`` is the dip measured over the trial's first
  second (BROAD's trials start at rest), in its documented float form;
  ``q0`` is its own default initialisation (``ecompass``, ENU) over that
  second. Field in µT (normalised inside);
* ``ahrs`` package Madgwick: ``Madgwick(frequency=rate)``, default MARG
  gain 0.041 (Madgwick's published value), its own ``ecompass`` (NED)
  start from the first sample; field in µT, normalized inside.

The peers' quaternion conventions are checked, not assumed: among q, q*
and those turned by a multiple of 90° about the vertical, the one that
agrees with the reference on the first static second of the first trial
is used for every trial (the mapping, printed below, is a frame
convention, the same for all trials).

Cross-validation: the filter's settings are chosen by coordinate descent
on a grid (the same procedure that chose the frozen defaults) on one half
of the trials (alternate trials of the sorted list) and scored on the
other half, and the other way round; the held-out scores of all trials
are averaged.

    python -m bench.broad [--quick] [--no-timing] [--no-cv] [--data DIR]
    python -m bench.broad --throughput-only [--quick] [--data DIR]   # host throughput tables only

The peers' attitudes are cached in ``results/bench-cache/broad`` (the ahrs
package's EKF runs at about 1 ms per sample here: a first full run takes
about half an hour; later runs a few minutes); an entry is keyed by the
filter, its package version, ``CONFIG_TAG`` and the trial file.
    invoke bench --only broad              # docs/bench/broad.md
"""

from __future__ import annotations

import math
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

TITLE = "The attitude filter on BROAD, against VQF, Fusion, the ahrs package's EKF and Madgwick"

PLOT = ROOT / "docs" / "img" / "broad-trials.png"
#: peers' attitudes are kept here between runs (the ahrs package's filters are pure
#: Python, ~1 ms per sample: the first full run takes long), keyed by filter,
#: package version and trial file (name, size, mtime)
CACHE = ROOT / "results" / "bench-cache" / "broad"
#: bumped when a peer's configuration changes, so its cached attitudes are recomputed
CONFIG_TAG = {"ahrs EKF": "-cfg2"}
FILTERS = ("attitude_c f64", "attitude_c f32", "VQF", "Fusion", "ahrs EKF", "ahrs Madgwick")

# the grid of the settings search (coordinate descent from the defaults)
GRID: dict[str, list[float]] = {
    "acc_noise": [0.015, 0.025, 0.04],
    "acc_tau": [1.0, 2.0, 3.0],
    "mag_noise": [0.03, 0.05, 0.09],
    "bias_noise": [3e-5, 1e-4, 3e-4],
    "mag_norm_tol": [0.03, 0.05, 0.1],
    "mag_dip_tol": [0.1, 0.17, 0.25],
    "rest_noise": [0.001, 0.005],
}


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    from attitude_c import reference as ref

    return np.asarray(ref.quat_multiply(a, b))


def _qz(deg: float) -> np.ndarray:
    h = math.radians(deg) / 2
    return np.array([math.cos(h), 0.0, 0.0, math.sin(h)])


# -- the filters --------------------------------------------------------------------------

#: how each peer is configured (printed into docs/bench/broad.md; details and reasons in
#: the module docstring): published defaults, none tuned on BROAD
PEER_CONFIG = {
    "VQF": "`VQF(1/rate)`, default parameters, 9-D output; initialises itself",
    "Fusion": "`imufusion` default gain 0.5, ENU, gyroscope_range 2000 °/s, acceleration/magnetic "
              "rejection 10°, rejection_timeout 5 s (Fusion's README example; its default disables "
              "rejection), with its default gyro offset corrector; °/s and g in",
    "ahrs EKF": "`ahrs` EKF, frame ENU, default noise variances (0.3², 0.5², 0.8²); given −acc (its ENU "
                "model takes the accelerometer along gravity, BROAD's reads specific force); magnetic_ref "
                "= dip measured over the trial's first (static) second; q0 = its `ecompass` (ENU) on that "
                "second",
    "ahrs Madgwick": "`ahrs` Madgwick, default MARG gain 0.041, its own `ecompass` start on the first sample",
}

def run_ours(tr: Any, precision: str = "f64", **settings: Any) -> np.ndarray:
    from attitude_c.ahrs_filter import ahrs

    return np.asarray(ahrs(tr.gyr, tr.acc, tr.mag, rate=tr.rate, precision=precision, **settings), float)


# --- the UAV thesis's own EKF, reproduced (attitude_c.ahrs_thesis; docs/ahrs.md "The thesis's EKF"):
# its defaults, double build, started from its first sample like the others
def run_thesis(tr: Any) -> np.ndarray:
    from attitude_c import ahrs_thesis

    return np.asarray(ahrs_thesis(tr.gyr, tr.acc, tr.mag, rate=tr.rate), float)
# --- end of the thesis EKF block


def run_vqf_batch(tr: Any) -> dict[str, Any]:
    """VQF as configured for every table here (``VQF(1/rate)``, defaults, 9-D): all of
    ``updateBatch``'s outputs."""
    from vqf import VQF

    v = VQF(1.0 / tr.rate)
    return dict(v.updateBatch(np.ascontiguousarray(tr.gyr), np.ascontiguousarray(tr.acc),
                              np.ascontiguousarray(tr.mag)))


def run_vqf(tr: Any) -> np.ndarray:
    return np.asarray(run_vqf_batch(tr)["quat9D"])


def run_fusion(tr: Any) -> np.ndarray:
    import imufusion

    s = imufusion.AhrsSettings(sample_rate=tr.rate, convention=imufusion.CONVENTION_ENU, gain=0.5,
                               gyroscope_range=2000.0, acceleration_rejection=10.0,
                               magnetic_rejection=10.0, rejection_timeout=5.0)
    a = imufusion.Ahrs()
    a.set_settings(s)
    bias = imufusion.Bias()
    bias.set_settings(imufusion.BiasSettings(sample_rate=tr.rate))
    g = np.degrees(tr.gyr)
    f = tr.acc / 9.81
    out = np.empty((tr.n, 4))
    for i in range(tr.n):
        gi = bias.update(g[i])
        a.update(gi, f[i], tr.mag[i])
        out[i] = a.get_quaternion()
    return out


def run_ekf(tr: Any) -> np.ndarray:
    """The ``ahrs`` package's EKF, ENU, with its gravity convention and this trial's dip.

    Its ENU measurement model expects the accelerometer to point along gravity
    (``a_ref = [0, 0, -1]``, ``ahrs/filters/ekf.py`` ``_set_reference_frames``),
    while BROAD's accelerometer reads specific force (+9.81 upward at rest): it
    is given ``-acc``. Fed BROAD's sign it converges upside down (~160° off on
    every trial). Its magnetic reference is fixed (it does not learn one): the
    dip angle measured over the trial's first second (BROAD's trials start at
    rest), its documented float form. q0: its own default initialisation
    (``ecompass``, ENU) on the same first second, computed with BROAD's sign
    (its default would use the first sample of the negated input). Noises:
    its defaults (variances 0.3², 0.5², 0.8²).
    """
    from ahrs.common.orientation import ecompass
    from ahrs.filters import EKF

    first = slice(0, max(1, round(tr.rate)))
    a0, m0 = tr.acc[first].mean(axis=0), tr.mag[first].mean(axis=0)
    up = a0 / np.linalg.norm(a0)
    dip = math.degrees(math.asin(float(-up @ m0) / float(np.linalg.norm(m0))))
    q0 = np.asarray(ecompass(a0, m0, frame="ENU", representation="quaternion"), float)
    return np.asarray(EKF(gyr=tr.gyr, acc=-tr.acc, mag=tr.mag, frequency=tr.rate, frame="ENU",
                          magnetic_ref=dip, q0=q0 / np.linalg.norm(q0)).Q)


def run_madgwick(tr: Any) -> np.ndarray:
    from ahrs.filters import Madgwick

    return np.asarray(Madgwick(gyr=tr.gyr, acc=tr.acc, mag=tr.mag, frequency=tr.rate).Q)


def _version(filt: str) -> str:
    from importlib.metadata import PackageNotFoundError, version

    pkg = {"VQF": "vqf", "Fusion": "imufusion", "ahrs EKF": "ahrs", "ahrs Madgwick": "ahrs"}[filt]
    try:
        return version(pkg)
    except PackageNotFoundError:
        return "unknown"


def cached(filt: str, tr: Any, path: Path, fn: Callable[[Any], np.ndarray]) -> np.ndarray:
    """fn(tr), from the cache when this filter version already ran on this file."""
    st = path.stat()
    key = f"{filt.replace(' ', '_')}-{_version(filt)}{CONFIG_TAG.get(filt, '')}-{tr.name}-{st.st_size}-{int(st.st_mtime)}.npy"
    f = CACHE / key
    if f.is_file():
        return np.asarray(np.load(f))
    q = fn(tr)
    CACHE.mkdir(parents=True, exist_ok=True)
    tmp = f.with_suffix(".tmp.npy")
    np.save(tmp, q)
    tmp.replace(f)
    return q


def convention(q: np.ndarray, tr: Any) -> tuple[str, Callable[[np.ndarray], np.ndarray]]:
    """The frame mapping (q or q*, turned by k·90° about up) that agrees with the
    reference over the first static second with a valid reference."""
    from attitude_c import broad

    ok = np.flatnonzero(np.isfinite(tr.quat).all(axis=1) & ~tr.movement)[: int(tr.rate)]
    best: tuple[float, str, Callable[[np.ndarray], np.ndarray]] | None = None
    for conj in (False, True):
        for deg in (0.0, 90.0, 180.0, -90.0):
            def m(x: np.ndarray, conj: bool = conj, deg: float = deg) -> np.ndarray:
                y = x * np.array([1.0, -1.0, -1.0, -1.0]) if conj else x
                return _qmul(_qz(deg), y) if deg else y
            e = float(np.mean(broad.error_angles(m(q[ok]), tr.quat[ok])[0]))
            name = ("q*" if conj else "q") + (f" turned {deg:+.0f}° about up" if deg else "")
            if best is None or e < best[0]:
                best = (e, name, m)
    assert best is not None
    return best[1], best[2]


# -- scoring ------------------------------------------------------------------------------

def score(trials: list[Any], qs: list[np.ndarray]) -> list[Any]:
    from attitude_c import broad

    return [broad.errors(q, t.quat, t.movement) for t, q in zip(trials, qs)]


def group_means(trials: list[Any], figs: list[Any]) -> dict[str, dict[str, float]]:
    from attitude_c import broad

    out = {"all": broad.mean_figures(figs)}
    for g in ("undisturbed", "disturbed"):
        sel = [f for t, f in zip(trials, figs) if g in t.groups or f"_{g}_" in t.name]
        if sel:
            out[g] = broad.mean_figures(sel)
    return out


def tune(trials: list[Any], rounds: int = 2) -> tuple[dict[str, float], float]:
    """Coordinate descent over GRID from the defaults, minimizing the mean total error."""
    from attitude_c import broad

    def total(kw: dict[str, float]) -> float:
        return broad.mean_figures(score(trials, [run_ours(t, **kw) for t in trials]))["total"]

    cur: dict[str, float] = {}
    best = total(cur)
    for _ in range(rounds):
        changed = False
        for k, vals in GRID.items():
            for v in vals:
                if cur.get(k) == v:
                    continue
                c = dict(cur)
                c[k] = v
                s = total(c)
                if s < best - 1e-4:
                    best, cur, changed = s, c, True
        if not changed:
            break
    return cur, best


def cross_validate(trials: list[Any], rounds: int) -> tuple[list[tuple[str, dict[str, float], float]], float]:
    """Two folds (alternate trials); returns per-fold (held-out names, settings, held-out
    mean total) and the held-out mean total over all trials."""
    from attitude_c import broad

    folds = [trials[0::2], trials[1::2]]
    rows = []
    held: list[Any] = []
    for i in (0, 1):
        kw, _ = tune(folds[i], rounds)
        test = folds[1 - i]
        figs = score(test, [run_ours(t, **kw) for t in test])
        held += figs
        rows.append((", ".join(t.name[:2] for t in test), kw, broad.mean_figures(figs)["total"]))
    return rows, broad.mean_figures(held)["total"]


def ratio_lines(trials: list[Any], figs: dict[str, list[Any]]) -> list[str]:
    """This filter's per-trial total error as a ratio to VQF's: each group's mean beside VQF's and the
    distribution (min / median / max, trials above 1.5×)."""
    import statistics

    r = np.array([a.total / b.total for a, b in zip(figs["attitude_c f64"], figs["VQF"])])
    out = ["\n**Per-trial ratio to VQF** (total error, attitude_c f64 / VQF):\n",
           "| group | trials | attitude_c f64 mean total | VQF mean total | ratio min / median / max | above 1.5× |",
           "|---|---|---|---|---|---|"]
    for g in ("all", "undisturbed", "disturbed"):
        sel = [i for i, t in enumerate(trials) if g == "all" or (t.disturbed == (g == "disturbed"))]
        if not sel:
            continue
        rs = r[sel]
        above = ", ".join(trials[i].name[:2] for i in sel if r[i] > 1.5) or "none"
        out.append(f"| {g} | {len(sel)} | {np.mean([figs['attitude_c f64'][i].total for i in sel]):.3f} | "
                   f"{np.mean([figs['VQF'][i].total for i in sel]):.3f} | {rs.min():.2f} / "
                   f"{statistics.median(rs):.2f} / {rs.max():.2f} | {above} |")
    return out


# -- cost -----------------------------------------------------------------------------------

def armv4t_counts(delays: bool = False, precisions: tuple[str, ...] = ("f32", "f64")) -> list[tuple[str, float]]:
    """Instructions per sample (acc + mag every sample) on the emulated ARM920T; ``delays``:
    with acc_delay 5 ms and mag_delay 13 ms (``-DBENCH_AHRS_DELAYS``, bench/broad_timing.py)."""
    from attitude_c.ahrs_filter import default_settings
    from toolchain import targets as T
    from toolchain.qemu_count import per_iteration

    t = T.load("armv4t-bare")
    # the steady per-sample path: the difference of two runs that both end after the reported
    # inclination's running-mean start (tilt_tau at bench_ahrs.c's 200 Hz, in motion), one
    # field-table period (256 samples) apart
    n_small = math.ceil(default_settings()["tilt_tau"] * 200.0) + 100
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for prec in precisions:
            defines = (["ATT_REAL_F32"] if prec == "f32" else []) + (["BENCH_AHRS_DELAYS"] if delays else [])
            exe = t.build_program([ROOT / "csrc" / "vectors" / "bench_ahrs.c"], Path(d) / f"bench_ahrs_{prec}",
                                  defines=defines)
            rows.append((prec, per_iteration(exe, lambda m: [str(m)], n_small, n_small + 256)))
    return rows


def throughput(trials: list[Any], rounds: int) -> list[tuple[str, float, float, float]]:
    """Samples/s of one batch call over all trials concatenated: ours (f64, f32) and VQF's
    ``updateBatch`` on the same float64 arrays, same rate, 9-axis, each constructing its filter
    inside the timed call. The three alternate within each round (so load changes hit all of
    them alike); a warm-up call of each precedes. Returns (label, best, median, median of the
    per-round ratio to VQF)."""
    import statistics

    from vqf import VQF

    from attitude_c.ahrs_filter import Ahrs

    g = np.ascontiguousarray(np.vstack([t.gyr for t in trials]))
    a = np.ascontiguousarray(np.vstack([t.acc for t in trials]))
    m = np.ascontiguousarray(np.vstack([t.mag for t in trials]))
    rate = trials[0].rate
    n = len(g)
    calls: dict[str, Callable[[], Any]] = {
        f"attitude_c.Ahrs.update, {p}, one block": (lambda p=p: Ahrs(rate=rate, precision=p).update(g, a, m))
        for p in ("f64", "f32")}
    calls["VQF.updateBatch (C++)"] = lambda: VQF(1.0 / rate).updateBatch(g, a, m)
    for fn in calls.values():  # warm-up: imports, first-touch of the buffers
        fn()
    sps: dict[str, list[float]] = {k: [] for k in calls}
    for _ in range(rounds):
        for k, fn in calls.items():
            t0 = time.perf_counter()
            fn()
            sps[k].append(n / (time.perf_counter() - t0))
    vqf = sps["VQF.updateBatch (C++)"]
    return [(k, max(v), statistics.median(v), statistics.median(x / y for x, y in zip(v, vqf)))
            for k, v in sps.items()]


def throughput_table(trials: list[Any], rounds: int) -> list[str]:
    import os

    load = os.getloadavg()
    out = [(f"**Host throughput** (all {sum(t.n for t in trials):,} samples of the trials concatenated, one "
            f"call each, {rounds} rounds alternating the three calls, `time.perf_counter`; a shared "
            f"2-core machine, load average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} at the start):\n"),
           "| what | samples/s, best round | median round | ratio to VQF (median of rounds) |",
           "|---|---|---|---|"]
    for label, best, med, ratio in throughput(trials, rounds):
        out.append(f"| {label} | {best:,.0f} | {med:,.0f} | {ratio:.2f} |")
    return out


def streaming(trials: list[Any], n: int, rounds: int) -> dict[str, list[float]]:
    """µs per sample of one-sample-per-call streaming from Python, per round: ours
    (``Ahrs.update``, f64), VQF's ``update`` and Fusion's ``update`` on the same first ``n``
    samples of the trials concatenated, each row a (3,) view of a C-contiguous float64 array
    (Fusion's in its units: °/s and g, converted before the clock starts), 9-axis every
    sample; a fresh filter per round, made before the clock starts; the three alternate
    within each round. "loop only" is the same loop fetching the three rows and calling
    nothing: the share of every row that is the loop's own."""
    import imufusion
    from vqf import VQF

    from attitude_c.ahrs_filter import Ahrs

    g, a, m = (np.ascontiguousarray(np.vstack([getattr(t, k) for t in trials])[:n]) for k in ("gyr", "acc", "mag"))
    rate = trials[0].rate
    g_deg, a_g = np.degrees(g), a / 9.81

    def fusion() -> Any:
        f = imufusion.Ahrs()
        f.set_settings(imufusion.AhrsSettings(sample_rate=rate, convention=imufusion.CONVENTION_ENU))
        return f

    def loop(update: Callable[..., Any], g: np.ndarray, a: np.ndarray) -> float:
        t0 = time.thread_time()  # CPU time: a preemption on a shared machine is not counted
        for i in range(n):
            update(g[i], a[i], m[i])
        return (time.thread_time() - t0) / n * 1e6

    calls: dict[str, Callable[[], float]] = {
        "attitude_c.Ahrs.update, f64": lambda: loop(Ahrs(rate=rate).update, g, a),
        f"VQF.update ({_version('VQF')}, C++)": lambda: loop(VQF(1.0 / rate).update, g, a),
        f"imufusion.Ahrs.update ({_version('Fusion')}, C)": lambda: loop(fusion().update, g_deg, a_g),
        "loop only (no call)": lambda: loop(lambda *_: None, g, a)}
    for fn in calls.values():  # warm-up
        fn()
    us: dict[str, list[float]] = {k: [] for k in calls}
    for _ in range(rounds):
        for k, fn in calls.items():
            us[k].append(fn())
    return us


def streaming_table(trials: list[Any], rounds: int, n: int = 20_000) -> list[str]:
    import os
    import statistics

    load = os.getloadavg()
    us = streaming(trials, n, rounds)
    out = [(f"\n**Streaming, one sample per call from Python** (the first {n:,} samples of the trials "
            f"concatenated; `for i in range(n): f.update(gyr[i], acc[i], mag[i])`, rows as (3,) views "
            f"of float64 arrays, 9-axis every sample, a fresh filter per round; {rounds} rounds alternating "
            f"the calls, the thread's CPU time (`time.thread_time`); load average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} at "
            "the start; the times include the loop's own, shown in the last row):\n"),
           "| what | µs/sample, best round | median round |", "|---|---|---|"]
    for k, v in us.items():
        out.append(f"| {k} | {min(v):.2f} | {statistics.median(v):.2f} |")
    return out


# -- plot -------------------------------------------------------------------------------------

def plot(trials: list[Any], figs: dict[str, list[Any]]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [t.name[:2] for t in trials]
    x = np.arange(len(trials))
    keys = [k for k in FILTERS if k in figs and k != "attitude_c f32"]
    w = 0.8 / len(keys)
    fig, ax = plt.subplots(figsize=(11, 4))
    for i, k in enumerate(keys):
        ax.bar(x + (i - (len(keys) - 1) / 2) * w, [f.total for f in figs[k]], w, label=k)
    ax.set_xticks(x, names)
    ax.set_yscale("log")
    ax.set_ylabel("total error, RMS over movement (°)")
    ax.set_xlabel("BROAD trial")
    ax.set_title("BROAD (Laidig et al., Data 2021, CC BY 4.0): per-trial total error")
    ax.legend(ncol=3, fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    PLOT.parent.mkdir(parents=True, exist_ok=True)
    tmp = PLOT.with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    tmp.replace(PLOT)


# -- report -----------------------------------------------------------------------------------

def run(quick: bool = False, timing: bool = True, cv: bool = True, data: str | None = None) -> str:
    from attitude_c import broad
    from attitude_c.ahrs_filter import default_settings

    folder = data or None
    paths = broad.find_trials(folder)
    trials = [broad.load_trial(p) for p in paths]
    out: list[str] = []
    out.append(f"BROAD: {broad.CITATION}. {len(trials)} trials from "
               f"`{'the upstream data_mat folder given' if data else '../shared/data/broad'}`; metric of the "
               "BROAD paper (`attitude_c.broad`), degrees, mean of per-trial RMS over movement phases. "
               "Peers' configuration (details: module docstring of `bench/broad.py`):\n")
    out.extend(f"* {k}: {v}." for k, v in PEER_CONFIG.items())
    out.append("")
    qs: dict[str, list[np.ndarray]] = {k: [] for k in FILTERS}
    conv: dict[str, tuple[str, Callable[[np.ndarray], np.ndarray]]] = {}
    runners: dict[str, Callable[[Any], np.ndarray]] = {
        "attitude_c f64": lambda t: run_ours(t, "f64"), "attitude_c f32": lambda t: run_ours(t, "f32"),
        "VQF": run_vqf, "Fusion": run_fusion, "ahrs EKF": run_ekf, "ahrs Madgwick": run_madgwick}
    # the thesis's EKF: one more column (run_thesis above)
    runners["attitude_c thesis EKF"] = run_thesis
    qs["attitude_c thesis EKF"] = []
    skipped: dict[str, str] = {}
    for k, fn in runners.items():
        try:
            for t, p in zip(trials, paths):
                q = fn(t) if k.startswith("attitude_c") else cached(k, t, p, fn)
                if k in ("Fusion", "ahrs EKF", "ahrs Madgwick"):
                    if k not in conv:
                        conv[k] = convention(q, t)
                    q = conv[k][1](q)
                qs[k].append(q)
        except ImportError as exc:
            skipped[k] = str(exc)
            qs.pop(k)
    figs = {k: score(trials, v) for k, v in qs.items()}
    keys = list(figs)
    out.append("**Per trial** (total / heading / inclination, °):\n")
    out.append("| trial | " + " | ".join(keys) + " |")
    out.append("|---|" + "---|" * len(keys))
    for i, t in enumerate(trials):
        out.append(f"| {t.name} | " + " | ".join(
            f"{figs[k][i].total:.2f} / {figs[k][i].heading:.2f} / {figs[k][i].inclination:.2f}" for k in keys) + " |")
    out.append("\n**Means** (total / heading / inclination, °):\n")
    out.append("| group | " + " | ".join(keys) + " |")
    out.append("|---|" + "---|" * len(keys))
    gm = {k: group_means(trials, figs[k]) for k in keys}
    for g in gm[keys[0]]:
        out.append(f"| {g} | " + " | ".join(
            f"{gm[k][g]['total']:.3f} / {gm[k][g]['heading']:.3f} / {gm[k][g]['inclination']:.3f}"
            for k in keys) + " |")
    if "VQF" in figs:
        out.extend(ratio_lines(trials, figs))
    if "attitude_c f32" in qs:
        d = max(abs(a.total - b.total) for a, b in zip(figs["attitude_c f64"], figs["attitude_c f32"]))
        ang = max(float(np.degrees(np.max(broad.error_angles(a, b)[0])))
                  for a, b in zip(qs["attitude_c f64"], qs["attitude_c f32"]))
        out.append(f"\nFloat build vs double: largest per-trial difference of the total RMS {d:.4f}°; "
                   f"largest angle between the two attitudes at any sample {ang:.4f}°.")
    for k, (name, _) in conv.items():
        out.append(f"\n{k}: quaternion mapping found on the first static second of {trials[0].name}: {name}.")
    for k, why in skipped.items():
        out.append(f"\n{k}: not run ({why}).")
    plot(trials, figs)
    out.append(f"\nPlot: `{PLOT.relative_to(ROOT)}` (total error per trial, log scale).\n")
    d = default_settings()
    out.append("Frozen defaults of the filter: " + ", ".join(f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {v}"
                                                           for k, v in d.items()) + ".\n")
    if cv:
        rows, held = cross_validate(trials, rounds=1 if quick else 2)
        out.append("**Cross-validated** (settings chosen by coordinate descent over the grid "
                   f"{ {k: v for k, v in GRID.items()} } on one half of the trials, scored on the other):\n")
        out.append("| held-out trials | settings chosen on the other half (changes from the defaults) | "
                   "held-out mean total ° |")
        out.append("|---|---|---|")
        for names_, kw, tot in rows:
            out.append(f"| {names_} | {kw or 'defaults'} | {tot:.3f} |")
        out.append(f"\nHeld-out mean total over all {len(trials)} trials: **{held:.3f}°**.\n")
    try:
        counts = armv4t_counts()
        out.append("**ARMv4T (ARM920T) instructions per sample**, gyro + accelerometer + magnetometer update "
                   "every sample (`qemu-arm -cpu ti925t`, exact counts, `csrc/vectors/bench_ahrs.c`, "
                   "soft-float newlib, `-O2`; difference of two run lengths):\n")
        out.append("| precision | instructions/sample | µs/sample @400 MHz, CPI 1.5 | load at 200 Hz |")
        out.append("|---|---|---|---|")
        for prec, c in counts:
            us = c * 1.5 / 400e6 * 1e6
            out.append(f"| {prec} | {c:,.0f} | {us:.1f} | {us * 200 / 1e6 * 100:.1f} % |")
    except Exception as exc:  # noqa: BLE001 - a missing cross toolchain must not lose the rest
        out.append(f"\nARMv4T counts: not measured ({type(exc).__name__}: {exc}).")
    if timing:
        out.append("")
        out.extend(throughput_table(trials, 2 if quick else 9))
        out.extend(streaming_table(trials, 2 if quick else 9))
    return "\n".join(out)


if __name__ == "__main__":  # pragma: no cover
    data = None
    if "--data" in sys.argv:
        data = sys.argv[sys.argv.index("--data") + 1]
    t0 = time.time()
    if "--throughput-only" in sys.argv:  # just the host throughput table (ours vs VQF, same run)
        from attitude_c import broad as _broad

        _trials = [_broad.load_trial(p) for p in _broad.find_trials(data)]
        print("\n".join(throughput_table(_trials, 2 if "--quick" in sys.argv else 9)
                        + streaming_table(_trials, 2 if "--quick" in sys.argv else 9)))
        sys.exit(0)
    print(run(quick="--quick" in sys.argv, timing="--no-timing" not in sys.argv, cv="--no-cv" not in sys.argv,
              data=data))
    print(f"\n({time.time() - t0:.0f} s)", file=sys.stderr)
