"""Run outputs: Fig. 8-style error plots, attitude plot, CSV, JSON, tables.

Every file is written to a temporary name beside it and renamed into place,
so a run interrupted half-way never leaves a truncated result file.
"""

from __future__ import annotations

import contextlib
import csv
import json
import math
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .._plot import panels as _panels
from .chain import PAPER_MAXIMA, SimResult

__all__ = ["format_ratio", "format_table", "plot_attitude", "plot_errors", "sensor_rows", "to_jsonable",
           "write_run"]


def _atomic(path: Path) -> contextlib.AbstractContextManager[Path]:
    """A temporary path beside ``path``, fsynced and renamed onto it when the
    block succeeds, removed when it fails (attitude_c._io.atomic_path)."""
    from .._io import atomic_path

    return atomic_path(path)


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


def _title(res: SimResult) -> str:
    c = res.config
    est = c.method if c.estimator == "integrator" else c.estimator
    return (f"{c.trajectory.name} trajectory, {est}, {c.precision}, sensors {c.sensors}, "
            f"h = {c.period:g} s")


def plot_errors(res: SimResult, path: Path, dpi: int = 90) -> None:
    """Heading, pitch and roll error curves, one panel each (paper Fig. 8 style), to ``path``
    complete or not at all."""
    with _atomic(path) as tmp:
        _draw_errors(res, tmp, dpi)


def _draw_errors(res: SimResult, path: Path, dpi: int = 90) -> None:
    series = [("a. heading", res.err_heading, "heading"),
              ("b. pitch", res.err[:, 1], "pitch"),
              ("c. roll", res.err[:, 2], None)]
    with _panels(path, dpi, 7.0, "Attitude error curves — " + _title(res), legend=False) as axes:
        for ax, (label, e, key) in zip(axes, series):
            ax.plot(res.t, e, color="black", linewidth=0.9)
            ax.axhline(0.0, color="0.6", linewidth=0.6)
            ax.set_ylabel("error / rad")
            deg = ax.secondary_yaxis("right", functions=(np.degrees, np.radians))  # the same axis in degrees
            deg.set_ylabel("error / °")
            hi_e, lo_e = np.max(e, initial=0), np.min(e, initial=0)
            txt = (f"{label}: max {hi_e:.2e}, min {lo_e:.2e} rad "
                   f"({_deg(hi_e)}°, {_deg(lo_e)}°)")
            if key is not None:
                lo, hi = PAPER_MAXIMA[key]
                txt += f"; paper {lo:+.2f} … {hi:+.2f} rad"
            ax.set_title(txt, fontsize=8.5, loc="right")
            ax.ticklabel_format(axis="y", style="sci", scilimits=(-2, 2))


def _deg(rad: float) -> str:
    """An angle given in radians, in degrees to 3 significant digits."""
    return f"{math.degrees(rad):.3g}"


def plot_attitude(res: SimResult, path: Path, dpi: int = 90) -> None:
    """The attitude itself: truth and computed yaw, pitch, roll (degrees), to ``path``
    complete or not at all."""
    with _atomic(path) as tmp:
        _draw_attitude(res, tmp, dpi)


def _draw_attitude(res: SimResult, path: Path, dpi: int = 90) -> None:
    c = res.config
    t_a = c.trajectory.t_start
    tt = np.linspace(t_a, res.t[-1] if len(res.t) else t_a + c.duration, 2000)
    truth = c.trajectory.euler(tt)
    with _panels(path, dpi, 6.0, "Attitude — " + _title(res)) as axes:
        for i, (ax, name) in enumerate(zip(axes, ("yaw ψ", "pitch θ", "roll γ"))):
            ax.plot(tt, np.degrees(truth[:, i]), color="0.55", linewidth=2.2, label="truth")
            ax.plot(res.t, np.degrees(res.euler_est[:, i]), color="black", linewidth=0.8,
                    linestyle="--", label="computed")
            ax.set_ylabel(f"{name} / °")


def draw_vehicle(traj: Any, path: Path, title: str, dpi: int = 90) -> None:
    """A vehicle trajectory (:mod:`.vehicle`): its ground track (north over east, m;
    start marked) and, over t, its bank and pitch (°) and its speed (m/s); PNG to
    ``path`` as it is (the caller makes the write atomic)."""
    from .._plot import plt

    pyplot = plt()
    t = np.linspace(0.0, traj.total, 3000)
    p, e = traj.position(t), np.degrees(traj.euler(t))
    fig, (ax0, ax1) = pyplot.subplots(1, 2, figsize=(9.0, 3.6))
    try:
        ax0.plot(p[:, 0], p[:, 1], color="black", linewidth=1.0)
        ax0.plot(p[:1, 0], p[:1, 1], "o", color="black", markersize=4, label="start")
        ax0.set_aspect("equal", adjustable="datalim")
        ax0.set_xlabel("east / m")
        ax0.set_ylabel("north / m")
        ax1.plot(t, e[:, 2], color="black", linewidth=1.0, label="bank (roll γ) / °")
        ax1.plot(t, e[:, 1], color="0.5", linewidth=1.0, linestyle="--", label="pitch θ / °")
        ax1.plot(t, traj.speed(t), color="0.3", linewidth=0.8, linestyle=":", label="speed / (m/s)")
        ax1.set_xlabel("t / s")
        for ax in (ax0, ax1):
            ax.grid(True, linestyle=":", linewidth=0.6)
            ax.legend(loc="best", fontsize=8)
        fig.suptitle(title, fontsize=9.5)
        fig.tight_layout()
        fig.savefig(path, dpi=dpi, format="png")
    finally:
        pyplot.close(fig)


def plot_bias(res: SimResult, path: Path, dpi: int = 90) -> None:
    """The filter's gyro-bias estimate per body axis (°/s) beside the bias the
    estimator's rates actually carry (their mean minus the true rates' over the run),
    to ``path`` complete or not at all."""
    if res.bias is None or res.bias_t is None:
        raise ValueError("plot_bias: the run has no filter bias estimate (estimator 'integrator')")
    with _atomic(path) as tmp:
        _draw_bias(res, tmp, dpi)


def _draw_bias(res: SimResult, path: Path, dpi: int = 90) -> None:
    assert res.bias is not None and res.bias_t is not None
    resid = res.summary.get("estimator", {}).get("bias_residual_rad_s")
    with _panels(path, dpi, 6.0, "Gyro bias estimate — " + _title(res)) as axes:
        for i, (ax, axis) in enumerate(zip(axes, "xyz")):
            ax.plot(res.bias_t, np.degrees(res.bias[:, i]), color="black", linewidth=0.9, label="estimate")
            if resid is not None:
                ax.axhline(math.degrees(resid[i]), color="0.55", linewidth=2.0, label="rates − truth, run mean")
            ax.set_ylabel(f"b_{axis} / (°/s)")


def write_csv(res: SimResult, path: Path) -> None:
    """timeseries.csv (one row per update) to ``path`` complete or not at all."""
    with _atomic(path) as tmp:
        _write_csv(res, tmp)


_ERRORS = ("err_yaw", "err_pitch", "err_roll", "err_heading", "err_angle")
#: timeseries.csv's columns, each named with its unit (quaternions are unitless)
TIMESERIES_COLUMNS = (
    "t_s", *(f"{a}_{w}_rad" for w in ("true", "est") for a in ("yaw", "pitch", "roll")),
    *(f"{e}_rad" for e in _ERRORS), *(f"{e}_deg" for e in _ERRORS),
    *(f"q{i}_{w}" for w in ("est", "true") for i in range(4)))


def _write_csv(res: SimResult, path: Path) -> None:
    err = np.column_stack([res.err, -res.err[:, 0], res.err_angle]) if len(res.t) else np.zeros((0, 5))
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(TIMESERIES_COLUMNS)
        for k in range(len(res.t)):
            row = [res.t[k], *res.euler_true[k], *res.euler_est[k], *err[k], *np.degrees(err[k]),
                   *res.q_est[k], *res.q_true[k]]
            w.writerow([f"{v:.6f}" if j == 0 else f"{v:.12e}" for j, v in enumerate(row)])


def sensor_rows(res: SimResult) -> tuple[list[str], np.ndarray]:
    """The per-period sensor streams of a run: header and rows (n, columns).

    One row per sample period k: ``sample``, ``t_start_s``, ``t_mid_s``; the
    gyro rates the estimator got (``gyro_x_rad_s..``: the host's increments
    over h, after the denoiser when it runs; NaN for a sample never delivered)
    beside the exact mean rates (``gyro_true_x_rad_s..``); then for each extra
    sensor its host readings (``accel_x_m_s2..``, ``mag_x_ut..``) beside the
    exact period means (``accel_true_*``: specific force; ``mag_true_*``: the
    geomagnetic field in the body frame) and, for the magnetometer, the
    disturbance field (``mag_disturbance_*_ut``). Every name ends in its unit."""
    c = res.config
    n = 0 if res.period_t is None else len(res.period_t)
    h = c.period
    t0 = c.trajectory.t_start
    k = np.arange(n)
    cols: list[np.ndarray] = [k.astype(float), t0 + k * h, t0 + (k + 0.5) * h]
    head = ["sample", "t_start_s", "t_mid_s"]
    unit = {"gyro": "rad_s", "accel": "m_s2", "mag": "ut"}
    gyro = np.full((n, 3), np.nan)
    idx = np.asarray(res.sample_index, dtype=np.int64)
    first = np.unique(idx, return_index=True)[1]  # a duplicated sample: its first delivery
    ok = idx[first] < n
    gyro[idx[first][ok]] = np.asarray(res.increments)[first][ok] / h
    true = c.trajectory.increments(t0, h, n) / h if n else np.zeros((0, 3))
    for name, arr in (("gyro", gyro), ("gyro_true", true)):
        head += [f"{name}_{a}_{unit['gyro']}" for a in "xyz"]
        cols += list(arr.T)
    for name, s in res.aux.items():
        parts = [(name, s.values), (f"{name}_true", s.truth)]
        if name == "mag":
            parts.append(("mag_disturbance", s.disturbance))
        for label, arr in parts:
            head += [f"{label}_{a}_{unit[name]}" for a in "xyz"]
            cols += list(np.asarray(arr, dtype=float).T)
    return head, np.column_stack(cols) if n else np.zeros((0, len(head)))


def write_sensors_csv(res: SimResult, path: Path) -> None:
    """sensors.csv (:func:`sensor_rows`) to ``path`` complete or not at all."""
    with _atomic(path) as tmp:
        _write_sensors_csv(res, tmp)


def _write_sensors_csv(res: SimResult, path: Path) -> None:
    head, rows = sensor_rows(res)
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(head)
        for r in rows:
            w.writerow([str(int(r[0])), f"{r[1]:.6f}", f"{r[2]:.6f}", *(f"{v:.12e}" for v in r[3:])])


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


def _aided_link_line(lk: dict[str, Any]) -> str:
    """The aided board's accounting: samples (groups) and records per part, link v2's figures."""
    sent, got = lk.get("records_sent", {}), lk.get("records_received", {})
    parts = ", ".join(f"{p} {got.get(p, 0)}/{sent.get(p, 0)}" for p in ("gyr", "acc", "mag"))
    via = (f"link v2 at {lk.get('baud')} baud, BER {lk.get('ber', 0):g}, {lk.get('overrun_samples', 0)} samples "
           f"lost to a full ring" if lk.get("link") == "v2" else "no link")
    return (f"aided board ({via}): samples sent {lk.get('sent')}, delivered {lk.get('delivered')}, "
            f"lost {lk.get('lost')}; records received/sent {parts}")


def format_table(summary: dict[str, Any]) -> str:
    e = summary["errors_rad"]
    p = summary["parameters"]
    est = f"method {p['method']}" if p.get("estimator", "integrator") == "integrator" else \
        f"estimator {p['estimator']}"
    lines = [
        (f"attitude simulate: {p['trajectory']['trajectory']} trajectory, {est}, "
         f"precision {p['precision']}, sensors {p['sensors']} ({p['gyro']['name']}), "
         f"period {p['period_s']:g} s, {p['duration_s']:g} s, seed {p['seed']}"),
        "",
        (f"{'error':<16}{'max rad':>11}{'min rad':>11}{'RMS rad':>11}{'max °':>9}{'min °':>9}{'RMS °':>9}"
         f"{'paper max rad':>15}{'× better':>10}"),
    ]
    better = summary.get("times_better_than_paper", {})
    for key in ("heading", "pitch", "roll", "attitude_angle"):
        s = e[key]
        pm = summary["paper_maxima_rad"].get(key)
        pm_s = f"{pm:>15.2f}" if pm is not None else f"{'':>15}"
        b = better.get(key)
        b_s = f"{format_ratio(b):>10}" if b is not None else f"{'':>10}"
        rad = "".join(f"{s[k]:>11.3e}" for k in ("max", "min", "rms"))
        deg = "".join(f"{_deg(s[k]):>9}" for k in ("max", "min", "rms"))
        lines.append(f"{key:<16}{rad}{deg}{pm_s}{b_s}")
    if any(v < 1 for v in better.values()):
        lines.append("(× better below 1: the error is larger than the paper's maximum)")
    lk = summary.get("link", {})
    if lk.get("link") == "c":
        lines += ["", (f"link ({lk.get('backend')}, BER {lk.get('ber', 0):g}): sent {lk.get('sent')}, "
                       f"delivered {lk.get('delivered')} (ok {lk.get('delivered_ok')}, duplicated "
                       f"{lk.get('duplicated')}, corrupted undetected "
                       f"{lk.get('corrupted_undetected')}), lost {lk.get('lost')}")]
    elif lk.get("link") == "v2" or "records_sent" in lk:
        lines += ["", _aided_link_line(lk)]
    for name, st in summary.get("sensors", {}).items():
        rms = ", ".join(f"{v:.3g}" for v in st["rms_error"])
        mean = ", ".join(f"{v:.3g}" for v in st["mean_error"])
        extra = f", saturated {st['saturated_samples']}" if st["saturated_samples"] else ""
        if st.get("disturbed_samples"):
            extra += f", disturbed {st['disturbed_samples']}"
        lines.append(f"{name} ({st['part']}): reading − truth per axis ({st['unit']}): mean {mean}; "
                     f"RMS {rms} ({st['samples']} samples{extra})")
    dn = summary.get("denoise")
    if dn:
        r = dn["rates"]
        lines.append(f"denoise ({dn['wavelet']}, L{dn['levels']}, {dn['threshold']}, N {dn['block']}, "
                     f"{dn['timing']}, latency {dn['latency_s']:.3g} s): gyro rate ptp ratio "
                     + "/".join(f"{v:.3f}" for v in r["ptp_ratio"]) + ", RMS ratio "
                     + "/".join(f"{v:.3f}" for v in r["rms_ratio"]) + f", mean change {r['mean_change_rel']:.1e}")
    es = summary.get("estimator")
    if es:
        b = ", ".join(f"{math.degrees(v):.4f}" for v in es["bias_final_rad_s"])
        r = ", ".join(f"{math.degrees(v):.4f}" for v in es["bias_residual_rad_s"])
        lines.append(f"{es['estimator']} ({es['axes']}-axis, init {es['init']}): gyro bias estimate at the end "
                     f"{b} °/s (the rates' bias over the run: {r} °/s); rest "
                     f"{es['rest_fraction']:.0%}, magnetometer rejected {es['mag_rejected_fraction']:.0%}")
    lines.append(f"updates {summary['updates']}, elapsed {summary.get('elapsed_s', 0):.2f} s")
    return "\n".join(lines)


def _gnss_log_step(res: SimResult, path: Path, steps: list[tuple[Path, Callable[[Path], object]]]) -> dict[str, Any]:
    """Add the GNSS log's writer to ``steps``; the receiver and its fix counts for the summary."""
    from .gnss_log import log_format, nmea_stream, ubx_stream

    cfg = res.config
    rx = cfg.gnss
    assert rx is not None
    fixes = rx.fixes(cfg.trajectory, cfg.duration, cfg.seed)
    stream = nmea_stream if log_format(path) == "nmea" else ubx_stream
    steps.append((path, lambda p: p.write_bytes(stream(fixes, rx.utc_start))))
    return {**rx.to_dict(), "epochs": len(fixes), "fixes_3d": int(np.sum(fixes["fix_type"] == 3)),
            "fixes_2d": int(np.sum(fixes["fix_type"] == 2)), "no_fix": int(np.sum(fixes["fix_type"] == 0))}


def write_run(res: SimResult, out: Path, plots: bool = True) -> dict[str, Path]:
    """Write timeseries.csv (sensors.csv when the run has an accelerometer or a
    magnetometer), errors.png, attitude.png and summary.json (last) into out,
    each complete or not at all (attitude_c._io: temp file, fsync, rename); an
    OSError names the files complete and absent."""
    from .._io import write_results

    out.mkdir(parents=True, exist_ok=True)
    files = {"summary": out / "summary.json", "csv": out / "timeseries.csv"}
    if res.aux:
        files["sensors_csv"] = out / "sensors.csv"
    if plots:
        files["errors_png"] = out / "errors.png"
        files["attitude_png"] = out / "attitude.png"
        if res.bias is not None:
            files["bias_png"] = out / "bias.png"
        if hasattr(res.config.trajectory, "vehicle"):
            files["vehicle_png"] = out / "vehicle.png"
    summary = dict(res.summary)
    summary["files"] = {k: v.name for k, v in files.items()}
    # write_results gives each writer the temporary path it renames into place: the writers
    # write to it as it is (one temporary file and one rename per result file)
    steps: list[tuple[Path, Callable[[Path], object]]] = [(files["csv"], lambda p: _write_csv(res, p))]
    if res.aux:
        steps.append((files["sensors_csv"], lambda p: _write_sensors_csv(res, p)))
    if plots:
        steps += [(files["errors_png"], lambda p: _draw_errors(res, p)),
                  (files["attitude_png"], lambda p: _draw_attitude(res, p))]
        if res.bias is not None:
            steps.append((files["bias_png"], lambda p: _draw_bias(res, p)))
        if "vehicle_png" in files:
            steps.append((files["vehicle_png"], lambda p: draw_vehicle(res.config.trajectory, p,
                                                                       "Vehicle — " + _title(res))))
    if res.config.gnss is not None and res.config.gnss_log:
        files["gnss_log"] = out / res.config.gnss_log
        summary["gnss"] = _gnss_log_step(res, files["gnss_log"], steps)
        summary["files"]["gnss_log"] = str(res.config.gnss_log)
    steps.append((files["summary"], lambda p: p.write_text(json.dumps(to_jsonable(summary), indent=2) + "\n",
                                                            encoding="utf-8")))
    write_results(steps)
    return files
