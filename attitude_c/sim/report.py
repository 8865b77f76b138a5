"""Run outputs: Fig. 8-style error plots, attitude plot, CSV, JSON, tables."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .chain import PAPER_MAXIMA, SimResult

__all__ = ["format_ratio", "format_table", "plot_attitude", "plot_errors", "to_jsonable", "write_run"]


def to_jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): to_jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [to_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return to_jsonable(x.tolist())
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else None
    return x


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _title(res: SimResult) -> str:
    c = res.config
    return (f"{c.trajectory.name} trajectory, {c.method}, {c.precision}, sensors {c.sensors}, "
            f"h = {c.period:g} s")


def plot_errors(res: SimResult, path: Path, dpi: int = 90) -> None:
    """Heading, pitch and roll error curves, one panel each (paper Fig. 8 style)."""
    plt = _plt()
    fig, axes = plt.subplots(3, 1, figsize=(7.0, 7.0), sharex=True)
    series = [("a. heading error", res.err_heading, "heading"),
              ("b. pitch error", res.err[:, 1], "pitch"),
              ("c. roll error", res.err[:, 2], None)]
    for ax, (label, e, key) in zip(axes, series):
        ax.plot(res.t, e, color="black", linewidth=0.9)
        ax.axhline(0.0, color="0.6", linewidth=0.6)
        ax.set_ylabel("error / rad")
        ax.grid(True, linestyle=":", linewidth=0.6)
        txt = f"{label}: max {np.max(e, initial=0):.2e}, min {np.min(e, initial=0):.2e} rad"
        if key is not None:
            lo, hi = PAPER_MAXIMA[key]
            txt += f"  (paper: {lo:+.2f} … {hi:+.2f} rad)"
        ax.set_title(txt, fontsize=8.5, loc="right")
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-2, 2))
    axes[-1].set_xlabel("t / s")
    fig.suptitle("Attitude error curves — " + _title(res), fontsize=9.5)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def plot_attitude(res: SimResult, path: Path, dpi: int = 90) -> None:
    """The attitude itself: truth and computed yaw, pitch, roll (degrees)."""
    plt = _plt()
    fig, axes = plt.subplots(3, 1, figsize=(7.0, 6.0), sharex=True)
    c = res.config
    t_a = c.trajectory.t_start
    tt = np.linspace(t_a, res.t[-1] if len(res.t) else t_a + c.duration, 2000)
    truth = c.trajectory.euler(tt)
    for i, (ax, name) in enumerate(zip(axes, ("yaw ψ", "pitch θ", "roll γ"))):
        ax.plot(tt, np.degrees(truth[:, i]), color="0.55", linewidth=2.2, label="truth")
        ax.plot(res.t, np.degrees(res.euler_est[:, i]), color="black", linewidth=0.8,
                linestyle="--", label="computed")
        ax.set_ylabel(f"{name} / °")
        ax.grid(True, linestyle=":", linewidth=0.6)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("t / s")
    fig.suptitle("Attitude — " + _title(res), fontsize=9.5)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def write_csv(res: SimResult, path: Path) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["t_s", "yaw_true", "pitch_true", "roll_true", "yaw_est", "pitch_est", "roll_est",
                    "err_yaw", "err_pitch", "err_roll", "err_heading", "err_angle",
                    "q0_est", "q1_est", "q2_est", "q3_est", "q0_true", "q1_true", "q2_true", "q3_true"])
        for k in range(len(res.t)):
            row = [res.t[k], *res.euler_true[k], *res.euler_est[k], *res.err[k], -res.err[k, 0],
                   res.err_angle[k], *res.q_est[k], *res.q_true[k]]
            w.writerow([f"{v:.6f}" if j == 0 else f"{v:.12e}" for j, v in enumerate(row)])


def format_ratio(ratio: float) -> str:
    """The paper's maximum over ours, for a table: the true ratio, truncated
    (never rounded up): ``212.9 -> "212"``, ``3.46 -> "3.4"``, ``0.996 ->
    "0.99"`` (worse than the paper stays below 1), ``0.138 -> "0.13"``."""
    from decimal import ROUND_DOWN, Decimal

    if not math.isfinite(ratio):
        return "inf" if ratio > 0 else "nan"
    if ratio <= 0:
        return "0"
    d = Decimal(repr(float(ratio)))
    if d >= 10:
        return str(int(d))  # int() truncates
    q = d.quantize(Decimal(1).scaleb(d.adjusted() - 1), rounding=ROUND_DOWN)  # 2 significant digits
    return format(q.normalize(), "f") if q >= Decimal("0.001") else f"{float(q):.1e}"


def format_table(summary: dict[str, Any]) -> str:
    e = summary["errors_rad"]
    p = summary["parameters"]
    lines = [
        (f"attitude simulate: {p['trajectory']['trajectory']} trajectory, method {p['method']}, "
         f"precision {p['precision']}, sensors {p['sensors']} ({p['gyro']['name']}), "
         f"period {p['period_s']:g} s, {p['duration_s']:g} s, seed {p['seed']}"),
        "",
        f"{'error (rad)':<16}{'max':>12}{'min':>12}{'RMS':>12}{'paper max':>12}{'× better':>10}",
    ]
    better = summary.get("times_better_than_paper", {})
    for key in ("heading", "pitch", "roll", "attitude_angle"):
        s = e[key]
        pm = summary["paper_maxima_rad"].get(key)
        pm_s = f"{pm:>12.2f}" if pm is not None else f"{'':>12}"
        b = better.get(key)
        b_s = f"{format_ratio(b):>10}" if b is not None else f"{'':>10}"
        lines.append(f"{key:<16}{s['max']:>12.3e}{s['min']:>12.3e}{s['rms']:>12.3e}{pm_s}{b_s}")
    if any(v < 1 for v in better.values()):
        lines.append("(× better below 1: the error is larger than the paper's maximum)")
    lk = summary.get("link", {})
    if lk.get("link") == "c":
        lines += ["", (f"link ({lk.get('backend')}, BER {lk.get('ber', 0):g}): sent {lk.get('sent')}, "
                       f"delivered {lk.get('delivered')} (ok {lk.get('delivered_ok')}, duplicated "
                       f"{lk.get('duplicated')}, corrupted undetected "
                       f"{lk.get('corrupted_undetected')}), lost {lk.get('lost')}")]
    lines.append(f"updates {summary['updates']}, elapsed {summary.get('elapsed_s', 0):.2f} s")
    return "\n".join(lines)


def write_run(res: SimResult, out: Path, plots: bool = True) -> dict[str, Path]:
    """Write timeseries.csv, errors.png, attitude.png and summary.json (last)
    into out, each complete or not at all (attitude_c._io: temp file, fsync,
    rename); an OSError names the files complete and absent."""
    from .._io import write_results

    out.mkdir(parents=True, exist_ok=True)
    files = {"summary": out / "summary.json", "csv": out / "timeseries.csv"}
    if plots:
        files["errors_png"] = out / "errors.png"
        files["attitude_png"] = out / "attitude.png"
    summary = dict(res.summary)
    summary["files"] = {k: v.name for k, v in files.items()}
    steps: list[tuple[Path, Callable[[Path], object]]] = [(files["csv"], lambda p: write_csv(res, p))]
    if plots:
        steps += [(files["errors_png"], lambda p: plot_errors(res, p)),
                  (files["attitude_png"], lambda p: plot_attitude(res, p))]
    steps.append((files["summary"], lambda p: p.write_text(json.dumps(to_jsonable(summary), indent=2) + "\n")))
    write_results(steps)
    return files
