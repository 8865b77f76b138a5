"""attitude calibrate: calibrate the aided board's accelerometer and magnetometer
from recorded codes and write the attitude-rx config file (docs/sensor.md).

Input, per sensor one file or several:
* JSON Lines recorded by "attitude link-rx --port DEV --decode > FILE.jsonl" from an
  aided board, started before the board (the recording needs its BOOT and CHANNELS
  reports): its accelerometer ("part": "acc") or magnetometer ("part": "mag")
  records; the stream's OVERSAMPLE report gives the conversions per word.
* CSV with a header naming its columns (others are ignored; lines starting with #
  are skipped; an empty cell is a sensor absent from that row):
    acc_x, acc_y, acc_z   accelerometer words
    mag_x, mag_y, mag_z   magnetometer words
    pose                  optional: the static position of the row, 0, 1, 2, ...;
                          empty or negative while the board is moved
  Words are sums of --oversample conversions (1: plain 12-bit codes).
A file without pose labels (every JSON Lines file) is cut into its still positions:
windows of --window rows in which no axis varies by more than --still codes (standard
deviation), consecutive ones agreeing within 10 codes, at least three windows long (less
the first and last, which may hold the end of a movement). The report lists them.

Accelerometer: hold the board still in each position. Six positions (each axis
up, then down) fit per-axis zero and scale (model diagonal); twelve or more
positions (the six, then tilts between them) also fit the non-orthogonality of
the axes (model full). Magnetometer: turn the board slowly through as many
directions as you can (all three axes), away from iron, for a minute.

Output (--out FILE): the attitude-rx config file with the keys acc-zero,
acc-scale, acc-axes, acc-matrix, acc-bias and mag-zero, mag-scale, mag-axes,
mag-matrix, mag-bias; the file's other lines are kept, the keys replaced. It is
written to a temporary name, then renamed. A report goes to standard output.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import sensorcal
from .._io import write_text
from ..errors import InvalidArgument
from ..sim.frontend import ACCEL_FRONTENDS, FLIP_ZERO, MAG_FRONTENDS
from .options import integer, positive, triple

PROG = "attitude calibrate"
#: Beyond the shared 0 / 1 / 2 (docs/cli.md):
EXIT_REFUSED = 3  # the recording cannot calibrate: too few positions, too little rotation, no convergence
ACC_PART, MAG_PART = ACCEL_FRONTENDS["adxl335"], MAG_FRONTENDS["hmc1043-ad623"]
WARN_ACC_RMS = 0.02  # of g: an RMS residual above it means a position was not still, or the part is not linear


class _Usage(Exception):
    """A mistake in the input file or the options (exit status 2)."""


class _Refused(Exception):
    """The recording does not determine the calibration (exit status 3)."""


def register(sub: Any) -> None:
    p = sub.add_parser(
        "calibrate", help="calibrate the accelerometer and magnetometer from recorded codes; write the "
        "attitude-rx config", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="exit statuses: 0 written; 1 an input cannot be read or the config cannot be written; 2 bad "
        "option or file content; 3 the recording cannot calibrate (too few positions, too little rotation, "
        "no convergence). See docs/sensor.md.")
    p.add_argument("--acc", metavar="FILE", type=Path, nargs="+",
                   help="static positions: CSV with a pose column, or recordings cut into still positions")
    p.add_argument("--mag", metavar="FILE", type=Path, nargs="+", help="a rotation (one file or several)")
    p.add_argument("--out", metavar="FILE", type=Path, required=True,
                   help="the attitude-rx config file to write (updated if it exists)")
    p.add_argument("--oversample", type=integer("--oversample", 1, 16), default=1, metavar="N",
                   help="conversions summed into each word (default 1)")
    p.add_argument("--acc-zero", type=triple("--acc-zero"), default=(2048.0,) * 3, metavar="C[,C,C]",
                   help="nominal code at 0 g (default 2048: Vs/2 on REF+ = Vs)")
    p.add_argument("--acc-scale", type=triple("--acc-scale"), default=(ACC_PART.units_per_code,) * 3,
                   metavar="K[,K,K]", help=f"nominal m/s^2 per code (default {ACC_PART.units_per_code:.6g}: "
                   f"{ACC_PART.name} on the TLC2543)")
    p.add_argument("--acc-axes", default="x,y,z", metavar="AXES",
                   help="body axes from channels, as attitude-rx's axes (default x,y,z)")
    p.add_argument("--acc-model", choices=sensorcal.ACCEL_MODELS, default="auto",
                   help="diagonal (6+ positions), full (12+), auto: full from 12 positions (default)")
    p.add_argument("--window", type=integer("--window", 2), default=20, metavar="ROWS",
                   help="accelerometer files without a pose column: rows per window of the search for still "
                   "positions (default 20)")
    p.add_argument("--still", type=positive("--still"), default=4.0, metavar="CODES",
                   help="a window is still when no axis varies by more than this standard deviation in codes "
                   "(default 4)")
    p.add_argument("--gravity", type=positive("--gravity"), default=9.80665, metavar="G",
                   help="local gravity, m/s^2 (default 9.80665)")
    p.add_argument("--mag-zero", type=triple("--mag-zero"), default=(FLIP_ZERO,) * 3, metavar="C[,C,C]",
                   help=f"nominal code at zero field (default {FLIP_ZERO}: set/reset codes)")
    p.add_argument("--mag-scale", type=triple("--mag-scale"), default=(MAG_PART.units_per_code,) * 3,
                   metavar="K[,K,K]", help=f"nominal uT per code (default {MAG_PART.units_per_code:.6g}: "
                   f"{MAG_PART.name} on the TLC2543)")
    p.add_argument("--mag-axes", default="x,y,z", metavar="AXES",
                   help="body axes from channels, as attitude-rx's axes (default x,y,z)")
    p.add_argument("--mag-model", choices=("full", "diagonal", "offset"), default="full",
                   help="soft iron: full (default), diagonal, offset (hard iron only)")
    p.add_argument("--mag-field", type=positive("--mag-field"), default=None, metavar="UT",
                   help="local field strength in uT (a geomagnetic model's F): scale the correction to it")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.set_defaults(func=main)


@dataclass
class _Rows:
    """One sensor's records from the input files: ``words`` (N, 3), ``n`` (N,)
    conversions per word, ``pose`` (N,) position labels (−1: none)."""

    words: np.ndarray
    n: np.ndarray
    pose: np.ndarray


def _cell(text: str, what: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise _Usage(f"{what}: {text!r} is not a number") from None
    if not math.isfinite(v):
        raise _Usage(f"{what}: {text!r} is not a finite number")
    return v


def _check_words(path: Path, rows: _Rows, where: list[int]) -> _Rows:
    w = rows.words
    bad = ~((w == np.round(w)) & (w >= 0) & (w <= rows.n[:, None] * 4095)).all(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise _Usage(f"{path}:{where[i]}: {w[i].tolist()} are not words of {rows.n[i]} 12-bit code(s) "
                     f"(0..{rows.n[i] * 4095})")
    return _Rows(w.astype(np.int64), rows.n, rows.pose)


def _read_csv(path: Path, prefix: str, oversample: int) -> _Rows:
    """The rows of a CSV that have all three of the sensor's columns; its pose column if any."""
    with open(path, encoding="utf-8", newline="") as fh:
        lines = [(i, ln) for i, ln in enumerate(fh, 1) if ln.strip() and not ln.lstrip().startswith("#")]
    reader = csv.reader(ln for _, ln in lines)
    header = [h.strip() for h in next(reader, [])]
    cols = [f"{prefix}_{a}" for a in "xyz"]
    missing = [c for c in cols if c not in header]
    if missing:
        raise _Usage(f"{path}: no column {', '.join(missing)} in the header {','.join(header) or '(empty)'}")
    idx = [header.index(c) for c in cols]
    ip = header.index("pose") if "pose" in header else None
    words, pose, where = [], [], []
    for (lineno, _), row in zip(lines[1:], reader):
        cells = [row[i].strip() if i < len(row) else "" for i in idx]
        if all(cells):
            words.append([_cell(c, f"{path}:{lineno}") for c in cells])
            label = row[ip].strip() if ip is not None and ip < len(row) else ""
            pose.append(_cell(label, f"{path}:{lineno}: pose") if label else -1)
            where.append(lineno)
    p = np.array(pose, dtype=float)
    if (p != np.round(p)).any():
        raise _Usage(f"{path}: pose must be an integer label (negative or empty: not a position)")
    w = np.array(words, dtype=float).reshape(-1, 3)
    return _check_words(path, _Rows(w, np.full(len(w), oversample), p.astype(np.int64)), where)


def _read_jsonl(path: Path, prefix: str) -> _Rows:
    """The sensor's records of an ``attitude link-rx --decode`` recording (JSON
    Lines): those with ``"part": PREFIX`` and no error; the stream's OVERSAMPLE
    report sets n, a BOOT resets it to 1."""
    words, ns, where = [], [], []
    n = 1
    with open(path, encoding="utf-8") as fh:
        for lineno, line in enumerate(fh, 1):
            if not line.strip():
                continue
            try:
                rec = json.loads(line)
            except ValueError:
                raise _Usage(f"{path}:{lineno}: not a JSON line of attitude link-rx --decode") from None
            if not isinstance(rec, dict):
                raise _Usage(f"{path}:{lineno}: not a JSON object")
            if rec.get("report") in ("BOOT", "OVERSAMPLE"):
                n = rec.get("n", 1)
                if not isinstance(n, int) or not 1 <= n <= 16:
                    raise _Usage(f"{path}:{lineno}: OVERSAMPLE n must be 1..16, got {n!r}")
            elif rec.get("part") == prefix and "error" not in rec:
                codes = rec.get("codes")
                if not (isinstance(codes, list) and len(codes) == 3 and all(isinstance(c, int) for c in codes)):
                    raise _Usage(f"{path}:{lineno}: codes must be three integers, got {codes!r}")
                words.append([float(c) for c in codes])
                ns.append(n)
                where.append(lineno)
    w = np.array(words, dtype=float).reshape(-1, 3)
    return _check_words(path, _Rows(w, np.array(ns, dtype=np.int64), np.full(len(w), -1)), where)


def _read(paths: list[Path], prefix: str, oversample: int, window: int = 0, still: float = 0.0) -> _Rows:
    """Every file's records of the sensor. ``window`` > 0: a file without pose labels is
    cut into its still positions (sensorcal.still_segments)."""
    parts, next_label = [], 0
    for path in paths:
        with open(path, "rb") as fh:
            jsonl = fh.read(4096).lstrip().startswith(b"{")
        rows = _read_jsonl(path, prefix) if jsonl else _read_csv(path, prefix, oversample)
        if not len(rows.words):
            what = f'"part": "{prefix}" records' if jsonl else f"rows with {prefix}_x, {prefix}_y, {prefix}_z"
            raise _Usage(f"{path}: no {what}")
        if (rows.pose < 0).all() and window:
            found = sensorcal.still_segments(rows.words / rows.n[:, None], window, still)
            rows.pose[found >= 0] = found[found >= 0] + next_label
        else:
            rows.pose[rows.pose >= 0] += next_label
        next_label = int(rows.pose.max(initial=next_label - 1)) + 1
        parts.append(rows)
    return _Rows(*(np.concatenate([getattr(r, f) for r in parts]) for f in ("words", "n", "pose")))


def _uncorrected(nominal: sensorcal.SensorConfig, rows: _Rows) -> np.ndarray:
    """The values (N, 3) with the nominal zero, scale and axes, through the C converter (one call per n)."""
    out = np.empty(rows.words.shape)
    for n in np.unique(rows.n):
        sel = rows.n == n
        out[sel] = nominal.convert(rows.words[sel], int(n), corrected=False)
    return out


def _nominal(prefix: str, zero: Any, scale: Any, axes: str) -> sensorcal.SensorConfig:
    try:
        return sensorcal.SensorConfig(prefix, zero, scale, axes)  # type: ignore[arg-type]
    except InvalidArgument as exc:
        raise _Usage(f"--{prefix}-zero/--{prefix}-scale/--{prefix}-axes: {exc}") from None


def _accel(args: argparse.Namespace) -> tuple[sensorcal.SensorConfig, dict[str, Any]]:
    nominal = _nominal("acc", args.acc_zero, args.acc_scale, args.acc_axes)
    rows = _read(args.acc, "acc", args.oversample, args.window, args.still)
    means, counts, _, labels = sensorcal.pose_means(_uncorrected(nominal, rows), rows.pose)
    stds = sensorcal.pose_means(rows.words / rows.n[:, None], rows.pose)[2]
    try:
        fit = sensorcal.fit_accel(means, nominal, args.gravity, args.acc_model)
    except InvalidArgument as exc:
        raise _Refused(f"accelerometer: {exc}") from None
    poses = [{"pose": int(k), "rows": int(c), "norm_error_mg": float(r / args.gravity * 1e3),
              "code_std": s.round(3).tolist()} for k, c, r, s in zip(labels, counts, fit.residuals, stds)]
    return fit.config, {"model": fit.model, "positions": len(labels), "rms_mg": fit.rms / args.gravity * 1e3,
                        "condition": fit.condition, "poses": poses}


def _mag(args: argparse.Namespace) -> tuple[sensorcal.SensorConfig, dict[str, Any]]:
    nominal = _nominal("mag", args.mag_zero, args.mag_scale, args.mag_axes)
    rows = _read(args.mag, "mag", args.oversample)
    try:
        fit = sensorcal.fit_mag(_uncorrected(nominal, rows), nominal, args.mag_field, args.mag_model)
    except InvalidArgument as exc:
        raise _Refused(f"magnetometer: {exc}") from None
    return fit.config, {"model": args.mag_model, "samples": int(fit.cal.n), "span": fit.cal.span,
                        "field_ut": fit.field, "fit_field_ut": fit.cal.field, "rms_ut": fit.rms,
                        "max_ut": float(np.abs(fit.norm_error).max()), "hard_iron_ut": fit.cal.h.tolist()}


def merged_config(old: str, configs: list[sensorcal.SensorConfig]) -> str:
    """The config text ``old`` with the configs' keys replaced (at the first
    occurrence of each sensor's keys, else appended) and every other line kept."""
    ours = {k for c in configs for k in c.keys()}
    out: list[str] = []
    placed: set[str] = set()
    for line in old.splitlines():
        key = line.split("#", 1)[0].split("=", 1)[0].strip()
        if key not in ours:
            out.append(line)
            continue
        for c in configs:
            if key in c.keys() and c.prefix not in placed:
                out.extend(c.lines())
                placed.add(c.prefix)
    for c in configs:
        if c.prefix not in placed:
            out.extend([getattr(c, "comment", "# attitude calibrate"), *c.lines()])
    return "\n".join(out) + "\n"


def _print_report(report: dict[str, Any], out: Path) -> None:
    acc, mag = report.get("acc"), report.get("mag")
    if acc:
        print(f"accelerometer: {acc['positions']} positions, model {acc['model']}, |a| - g RMS "
              f"{acc['rms_mg']:.2f} mg (condition {acc['condition']:.3g})")
        for p in acc["poses"]:
            print(f"  pose {p['pose']:3d}: {p['rows']:6d} rows, |a| - g {p['norm_error_mg']:+8.2f} mg, code std "
                  + " ".join(f"{s:.2f}" for s in p["code_std"]))
    if mag:
        print(f"magnetometer: {mag['samples']} samples, model {mag['model']}, span {mag['span']:.3f}, field "
              f"{mag['field_ut']:.2f} uT, |m| - field RMS {mag['rms_ut']:.3f} uT (max {mag['max_ut']:.3f}), "
              "hard iron " + ",".join(f"{h:.2f}" for h in mag["hard_iron_ut"]) + " uT")
    print(f"written: {out}")


def _run(args: argparse.Namespace) -> dict[str, Any]:
    if args.acc is None and args.mag is None:
        raise _Usage("give --acc FILE..., --mag FILE... or both")
    configs, report = [], {}
    for name, step, given in (("acc", _accel, args.acc), ("mag", _mag, args.mag)):
        if given is not None:
            config, report[name] = step(args)
            configs.append(config)
    old = args.out.read_text(encoding="utf-8") if args.out.exists() else ""
    write_text(args.out, merged_config(old, configs))
    return report


def main(args: argparse.Namespace) -> int:
    from . import EXIT_OK, EXIT_OS, EXIT_USAGE, fail, os_error_line  # the package's, once it is loaded

    try:
        report = _run(args)
    except _Usage as exc:
        return fail(PROG, str(exc), EXIT_USAGE)
    except _Refused as exc:
        return fail(PROG, str(exc), EXIT_REFUSED)
    except UnicodeDecodeError as exc:
        return fail(PROG, f"an input is not a text file: {exc.reason}", EXIT_USAGE)
    except OSError as exc:
        return fail(PROG, os_error_line(exc), EXIT_OS)
    acc = report.get("acc")
    if acc and acc["rms_mg"] > WARN_ACC_RMS * 1e3:
        print(f"{PROG}: warning: the positions disagree by {acc['rms_mg']:.0f} mg RMS: was every position "
              "still?", file=sys.stderr)
    if args.json:
        print(json.dumps(report, indent=1))
    else:
        _print_report(report, args.out)
    return EXIT_OK
