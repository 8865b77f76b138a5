"""Aiding solvers: ARMv4T cost, host throughput, and the static solvers on the
BROAD trials' rest phases against the optical truth.

* ARMv4T (ARM920T) instructions per alignment, TRIAD, Gauss–Newton solve
  (warm start), static-window sample, calibration sample and calibration
  solve, in the double and the float build (``qemu-arm -cpu ti925t``, exact
  counts, ``csrc/vectors/bench_aiding.c``);
* host throughput of the batch calls (``attitude_c.align`` ...);
* Gauss–Newton from a cold start on random attitudes: from the identity (as
  in the thesis) how often it stops with a status (the thesis' "outliers"),
  and without ``q0`` (the start is TRIAD's closed form);
* BROAD (D. Laidig, M. Caruso, A. Cereatti, T. Seel, "BROAD — A Benchmark for
  Robust Inertial Orientation Estimation", Data 6(7), 2021,
  doi:10.3390/data6070072, CC BY 4.0): TRIAD and Gauss–Newton per sample on
  every sample at rest (``movement`` = 0, optical truth present), and the
  static window over 2-s pieces of the rest phases; inclination and heading
  error (the benchmark's decomposition) as RMS per trial.

    python -m bench.aiding [--quick] [--no-timing]    # Markdown on stdout
    invoke bench --only aiding                        # docs/bench/aiding.md
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

TITLE = "Aiding solvers: ARMv4T cost, throughput, Gauss-Newton cold starts, BROAD rest phases"

OPS = ("align", "triad", "gn", "gn_simplified", "window_add", "magcal_add", "magcal_solve")
OP_LABEL = {
    "align": "alignment (`att_align_accmag`)",
    "triad": "TRIAD (`att_triad`)",
    "gn": "Gauss–Newton, warm start 0.17 rad (`att_gn_solve`)",
    "gn_simplified": "simplified Newton (eq. 3.40), same start",
    "window_add": "static window, per sample (`att_align_window_add`)",
    "magcal_add": "calibration, per sample (`att_magcal_add`)",
    "magcal_solve": "calibration solve, full model (`att_magcal_solve`)",
}
WINDOW_S = 2.0


def armv4t_counts(quick: bool) -> dict[tuple[str, str], float]:
    """(op, precision) -> instructions per call on the emulated ARM920T."""
    from toolchain import targets as T
    from toolchain.qemu_count import per_iteration

    t = T.load("armv4t-bare")
    out: dict[tuple[str, str], float] = {}
    with tempfile.TemporaryDirectory() as d:
        for prec in ("f64", "f32"):
            exe = t.build_program([ROOT / "csrc" / "vectors" / "bench_aiding.c"], Path(d) / f"bench_aiding_{prec}",
                                  defines=["ATT_REAL_F32"] if prec == "f32" else [])
            for op in OPS:
                # one pass over the 64-attitude table (every attitude counted once) against an
                # empty run; the solve of a fixed state costs the same every call: 8 suffice
                k = 8 if op == "magcal_solve" else 64

                def args(m: int, op: str = op) -> list[str]:
                    return [op, f"{m:06d}"]

                out[(op, prec)] = per_iteration(exe, args, 0, k)
    return out


def throughput(quick: bool) -> list[tuple[str, float]]:
    """(what, samples per second) of the batch calls on the host."""
    import attitude_c as ac
    from attitude_c import reference as R
    from attitude_c.reference import aiding as RA

    from .host import _best

    n = 20_000 if quick else 200_000
    rng = np.random.default_rng(1)
    e = np.column_stack([rng.uniform(-3, 3, n), rng.uniform(-1.4, 1.4, n), rng.uniform(-3, 3, n)])
    C = R.euler_to_dcm(e)
    f = np.einsum("nji,j->ni", C, [0.0, 0.0, 9.81])
    m = np.einsum("nji,j->ni", C, RA.field_nav(48.0, 1.1, 0.0))
    q0 = R.quat_multiply(R.euler_to_quat(e), R.rotvec_to_quat(np.full((n, 3), 0.1)))
    reps = 2 if quick else 4
    rows = []
    for prec in ("f64", "f32"):
        rows.append((f"align, {prec}", n / _best(lambda p=prec: ac.align(f, m, precision=p), reps)))
        rows.append((f"triad, {prec}", n / _best(lambda p=prec: ac.triad(f, m, precision=p), reps)))
        rows.append((f"gauss_newton (warm), {prec}", n / _best(lambda p=prec: ac.gauss_newton(f, m, q0, precision=p),
                                                               reps)))
        rows.append((f"magcal.fit (full), {prec}", n / _best(lambda p=prec: ac.magcal.fit(m, precision=p), reps)))
        cal = ac.magcal.fit(m)
        rows.append((f"magcal.apply, {prec}", n / _best(lambda p=prec, c=cal: c.apply(m, p), reps)))
    return rows


def cold_starts(n: int = 20_000, q0: Any = None) -> dict[str, Any]:
    """Gauss–Newton from ``q0`` (None: TRIAD's attitude) on random attitudes (|pitch| < 89°)."""
    import attitude_c as ac
    from attitude_c import reference as R
    from attitude_c.reference import aiding as RA
    from attitude_c.names import status_name

    rng = np.random.default_rng(2)
    lim = math.sin(math.radians(89))
    e = np.column_stack([rng.uniform(-math.pi, math.pi, n), np.arcsin(rng.uniform(-lim, lim, n)),
                         rng.uniform(-math.pi, math.pi, n)])
    C = R.euler_to_dcm(e)
    f = np.einsum("nji,j->ni", C, [0.0, 0.0, 9.81])
    m = np.einsum("nji,j->ni", C, RA.field_nav(48.0, 1.1, 0.0))
    q, info = ac.gauss_newton(f, m, q0, return_info=True)
    ok = info.status == 0
    err = R.quat_angle(q[ok], R.euler_to_quat(e[ok]))
    codes = {status_name(int(s)) or str(s): int(np.sum(info.status == s)) for s in np.unique(info.status[~ok])}
    return {"n": n, "ok": int(ok.sum()), "codes": codes, "worst": float(err.max()),
            "iters": np.percentile(info.iterations[ok], [50, 90, 99, 100])}


def _rms_deg(x: np.ndarray) -> float:
    return float(np.degrees(np.sqrt(np.mean(x * x)))) if x.size else math.nan


def _windows(rest: np.ndarray, k: int) -> list[slice]:
    """Non-overlapping k-sample pieces of the runs of consecutive rest samples."""
    out = []
    i, n = 0, len(rest)
    while i < n:
        if not rest[i]:
            i += 1
            continue
        j = i
        while j < n and rest[j]:
            j += 1
        out.extend(slice(a, a + k) for a in range(i, j - k + 1, k))
        i = j
    return out


def broad_table(quick: bool) -> tuple[list[dict[str, Any]], str | None]:
    """Per trial: rest samples, per-sample TRIAD / Gauss–Newton inclination and
    heading RMS (°), GN iterations, and the 2-s static window's figures."""
    import attitude_c as ac
    from attitude_c import broad

    folder = broad.default_dir()
    if folder is None:
        return [], "BROAD data not found (../shared/data/broad/)"
    rows = []
    for tr in broad.iter_trials(folder):
        rest = ~tr.movement & np.all(np.isfinite(tr.quat), axis=1)
        f, m, qr = tr.acc[rest], tr.mag[rest], tr.quat[rest]
        if quick:
            f, m, qr = f[::10], m[::10], qr[::10]
        qt = ac.triad(f, m)
        _, ht, it = broad.error_angles(qt, qr)
        # Gauss–Newton as a filter would call it: warm-started from the previous sample's answer
        qg = np.empty_like(qt)
        its = np.empty(len(f), dtype=np.int64)
        start = qt[:1]
        chunk = 1  # sequential by nature: each sample starts where the last ended
        for i in range(0, len(f), chunk):
            q1, info = ac.gauss_newton(f[i:i + 1], m[i:i + 1], start, return_info=True)
            qg[i] = q1[0]
            its[i] = info.iterations[0]
            start = q1 if info.status[0] == 0 else qt[i:i + 1]
        _, hg, ig = broad.error_angles(qg, qr)
        k = round(WINDOW_S * tr.rate)
        wi, wh, refused = [], [], 0
        if not quick:
            full_rest = ~tr.movement & np.all(np.isfinite(tr.quat), axis=1)
            for s in _windows(full_rest, k):
                q, st = ac.align_static(tr.acc[s], tr.mag[s], tr.gyr[s], return_stats=True)
                if st.status != 0:
                    refused += 1
                    continue
                ref = tr.quat[s][k // 2]
                _, h1, i1 = broad.error_angles(q[None, :], ref[None, :])
                wi.append(i1[0])
                wh.append(h1[0])
        rows.append({"name": tr.name, "disturbed": tr.disturbed, "n": len(f),
                     "triad": (_rms_deg(it), _rms_deg(ht)), "gn": (_rms_deg(ig), _rms_deg(hg)),
                     "gn_iter": float(its.mean()), "gn_iter_max": int(its.max()),
                     "win": (_rms_deg(np.array(wi)), _rms_deg(np.array(wh))), "n_win": len(wi),
                     "refused": refused})
    return rows, None


def run(quick: bool = False, timing: bool = True) -> str:
    out: list[str] = []
    out.append("**ARMv4T (ARM920T) instructions per call** (`qemu-arm -cpu ti925t`, exact counts, "
               "`csrc/vectors/bench_aiding.c`: 64 static attitudes cycled; difference of two runs; soft-float "
               "newlib, `-O2`). µs at 400 MHz with CPI 1.5 (the S3C2440's ARM920T, caches on).\n")
    out.append("| operation | f64 | f32 | f32 µs @400 MHz |")
    out.append("|---|---|---|---|")
    counts = armv4t_counts(quick)
    for op in OPS:
        a, b = counts[(op, "f64")], counts[(op, "f32")]
        out.append(f"| {OP_LABEL[op]} | {a:,.0f} | {b:,.0f} | {b * 1.5 / 400e6 * 1e6:.0f} |")
    for q0, start in (([1.0, 0.0, 0.0, 0.0], "the identity, as the thesis' listing: `q0=[1, 0, 0, 0]`"),
                      (None, "no `q0`: TRIAD's closed form, the default")):
        cs = cold_starts(4000 if quick else 20_000, q0)
        out.append(f"\n**Gauss–Newton from a cold start** ({start}; {cs['n']:,} random "
                   f"attitudes, |pitch| < 89°, noise-free): {cs['ok']:,} converge to the truth (worst error "
                   f"{cs['worst']:.1e} rad; iterations median / 90 % / 99 % / max "
                   f"{' / '.join(f'{x:.0f}' for x in cs['iters'])}); the others stop with a status "
                   f"({', '.join(f'{k}: {v}' for k, v in cs['codes'].items()) or 'none'}) — never a wrong or "
                   "non-finite attitude.")
    out.append("\nThe thesis' Fig. 3.5 outliers are the identity start's failures, returned as attitudes.\n")
    rows, missing = broad_table(quick)
    if missing:
        out.append(f"\nBROAD: {missing}.\n")
    else:
        out.append("**BROAD rest phases vs the optical truth** (every sample with `movement` = 0 and a "
                   "reference; " + ("every 10th sample, " if quick else "") +
                   "declination 0: the optical frame's north is the magnetic one). Inclination / heading "
                   "RMS in degrees (the benchmark's decomposition, `attitude_c.broad.error_angles`). "
                   "*per sample*: TRIAD, and Gauss–Newton warm-started from the previous sample (mean / max "
                   "iterations); they solve the same four equations, so they agree to 1e-9. *2-s window*: "
                   "`align_static` (default limits) on non-overlapping 2-s pieces of the rest runs, against "
                   "the reference at the window's middle; *refused*: windows the static check rejected.\n")
        out.append("| trial | samples | TRIAD incl | TRIAD heading | GN incl | GN heading | GN iter mean/max | "
                   "windows | window incl | window heading | refused |")
        out.append("|---|---|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            out.append(f"| {r['name']} | {r['n']:,} | {r['triad'][0]:.2f} | {r['triad'][1]:.2f} | {r['gn'][0]:.2f} | "
                       f"{r['gn'][1]:.2f} | {r['gn_iter']:.1f} / {r['gn_iter_max']} | {r['n_win']} | "
                       f"{r['win'][0]:.2f} | {r['win'][1]:.2f} | {r['refused']} |")
        for label, sel in (("undisturbed", [r for r in rows if not r["disturbed"]]),
                           ("disturbed", [r for r in rows if r["disturbed"]])):
            if not sel:
                continue

            def mean(key: str, i: int, sel: list[dict[str, Any]] = sel) -> float:
                return float(np.nanmean([r[key][i] for r in sel]))

            out.append(f"| **mean, {label}** ({len(sel)} trials) | | {mean('triad', 0):.2f} | {mean('triad', 1):.2f} "
                       f"| {mean('gn', 0):.2f} | {mean('gn', 1):.2f} | | | {mean('win', 0):.2f} | "
                       f"{mean('win', 1):.2f} | |")
        out.append("\nThe magnet trials (29, 33, 35) show what a static solver cannot know: a disturbed field "
                   "turns the heading, inclination stays. Data: BROAD (Laidig, Caruso, Cereatti, Seel, *Data* "
                   "6(7), 2021, doi:10.3390/data6070072, CC BY 4.0).\n")
    if timing:
        out.append("\n**Host throughput** of the batch calls (samples per second, best of a few runs, "
                   "`time.perf_counter`; noise-free random attitudes).\n")
        out.append("| call | samples/s |")
        out.append("|---|---|")
        for what, v in throughput(quick):
            out.append(f"| {what} | {v:,.0f} |")
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.aiding", description=TITLE)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--no-timing", action="store_true")
    a = ap.parse_args(argv)
    sys.stdout.write(run(quick=a.quick, timing=not a.no_timing))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
