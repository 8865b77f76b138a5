"""``attitude ahrs FILE``: run the attitude filter on a recording.

Input: a BROAD trial (``.mat``, with its optical reference) or a CSV file
with a header naming its columns: ``gx gy gz`` (rad/s), ``ax ay az``
(m/s², specific force), optionally ``mx my mz`` (field, any unit), ``t``
(s; else ``--rate``) and a reference attitude ``qw qx qy qz`` (body → ENU).
Output (``--out DIR``): ``attitude.csv`` (t, quaternion, yaw/pitch/roll in
degrees); with a reference also ``errors.json`` (BROAD's metric: total,
heading and inclination RMS, over the movement phases for a BROAD trial)
and ``errors.png``. Files are written to a temporary name, then renamed.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from .._io import write_with
from .options import positive

#: ``attitude ahrs`` exit statuses (docs/ahrs.md, "Command").
EXIT_OK = 0
PROG = "attitude ahrs"
EXIT_IO = 1     # the input cannot be read, or an output cannot be written
EXIT_USAGE = 2  # bad option, or the file's content is not a usable recording


def register(sub: Any) -> None:
    p = sub.add_parser(
        "ahrs", help="run the attitude filter (gyro + accelerometer + magnetometer) on a recording",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="exit statuses: 0 done; 1 the input cannot be read or an output cannot be written; 2 bad "
        "option or unusable file content. See docs/ahrs.md.")
    p.add_argument("file", metavar="FILE", help="BROAD trial (.mat) or CSV with a header")
    p.add_argument("--out", metavar="DIR", default=None,
                   help="output folder (default: results/ahrs-<file stem>)")
    p.add_argument("--rate", type=positive("--rate"), default=None, help="sampling rate, Hz (CSV without a t column)")
    p.add_argument("--precision", choices=("f64", "f32"), default="f64")
    p.add_argument("--six-axis", action="store_true", help="ignore the magnetometer")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a filter setting (docs/ahrs.md), e.g. --set acc_tau=3 --set method=rv1")
    p.add_argument("--estimate-mag-delay", action="store_true",
                   help="also print the magnetometer's lag behind the gyro estimated from this run's attitude "
                   "(attitude_c.aiding_delay; over the movement phases of a BROAD trial), to pass back as "
                   "--set mag_delay=D (docs/ahrs.md, \"Sensor timing\")")
    p.add_argument("--no-plots", action="store_true", help="do not write errors.png")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=main)


class _Usage(Exception):
    pass


def _settings(items: list[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for it in items:
        k, sep, v = it.partition("=")
        if not sep or not k:
            raise _Usage(f"--set {it!r}: expected NAME=VALUE")
        if k == "method":
            out[k] = v
        else:
            try:
                out[k] = float(v)
            except ValueError:
                raise _Usage(f"--set {it!r}: {v!r} is not a number") from None
    return out


def _read_csv(path: Path, rate: float | None) -> dict[str, Any]:
    with open(path, encoding="utf-8") as fh:
        header = fh.readline()
    cols = [c.strip() for c in header.replace(";", ",").split(",")]
    need = ["gx", "gy", "gz", "ax", "ay", "az"]
    missing = [c for c in need if c not in cols]
    if missing:
        raise _Usage(f"{path}: CSV header lacks column(s) {', '.join(missing)} (header: {header.strip()!r})")
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as exc:
        raise _Usage(f"{path}: not a numeric CSV below the header ({exc})") from None
    if data.shape[1] != len(cols) or data.shape[0] < 2:
        raise _Usage(f"{path}: expected {len(cols)} columns and at least 2 rows, got {data.shape}")

    def take(names: list[str]) -> np.ndarray | None:
        return data[:, [cols.index(c) for c in names]] if all(c in cols for c in names) else None

    t = data[:, cols.index("t")] if "t" in cols else None
    if rate is None:
        if t is None:
            raise _Usage(f"{path}: no t column: give --rate")
        d = np.diff(t)
        if not np.all(d > 0):
            raise _Usage(f"{path}: the t column must increase")
        rate = 1.0 / float(np.median(d))
    if t is None:
        t = np.arange(len(data)) / rate
    return {"t": t, "rate": rate, "gyr": take(["gx", "gy", "gz"]), "acc": take(["ax", "ay", "az"]),
            "mag": take(["mx", "my", "mz"]), "ref": take(["qw", "qx", "qy", "qz"]), "movement": None}


def _read(path: Path, rate: float | None) -> dict[str, Any]:
    if path.suffix.lower() == ".mat":
        from .. import broad

        tr = broad.load_trial(path)
        return {"t": np.arange(tr.n) / tr.rate, "rate": tr.rate, "gyr": tr.gyr, "acc": tr.acc, "mag": tr.mag,
                "ref": tr.quat, "movement": tr.movement}
    return _read_csv(path, rate)


def _plot(path: Path, t: np.ndarray, angles: tuple[np.ndarray, ...], title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 4))
    for a, lab in zip(angles, ("total", "heading", "inclination")):
        ax.plot(t, np.degrees(a), lw=0.8, label=lab)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("error (°)")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    write_with(path, lambda tmp: fig.savefig(tmp, format="png", dpi=100))
    plt.close(fig)


def main(args: argparse.Namespace) -> int:
    from ..errors import AttitudeError
    from . import fail, os_error_line

    try:
        return _main(args)
    except (_Usage, AttitudeError, ValueError, TypeError) as exc:
        return fail(PROG, str(exc), EXIT_USAGE)
    except OSError as exc:
        return fail(PROG, os_error_line(exc), EXIT_IO)


def _main(args: argparse.Namespace) -> int:
    from .. import broad
    from ..ahrs_filter import ahrs
    from ..core import quat_to_euler

    path = Path(args.file)
    if not path.is_file():
        from . import fail

        return fail(PROG, f"{path}: no such file", EXIT_IO)
    if args.rate is not None and not (math.isfinite(args.rate) and args.rate > 0):
        raise _Usage(f"--rate must be > 0, got {args.rate}")
    settings = _settings(args.set)
    rec = _read(path, args.rate)
    mag = None if args.six_axis else rec["mag"]
    if args.estimate_mag_delay and mag is None:
        raise _Usage("--estimate-mag-delay needs a magnetometer (mx my mz columns, not --six-axis)")
    q = np.asarray(ahrs(rec["gyr"], rec["acc"], mag, rate=rec["rate"], precision=args.precision, **settings),
                   dtype=np.float64)
    e = np.degrees(quat_to_euler(q))
    out = Path(args.out) if args.out else Path("results") / f"ahrs-{path.stem}"
    out.mkdir(parents=True, exist_ok=True)
    table = np.column_stack([rec["t"], q, e])
    write_with(out / "attitude.csv", lambda tmp: np.savetxt(
        tmp, table, delimiter=",", fmt="%.9g", header="t,qw,qx,qy,qz,yaw_deg,pitch_deg,roll_deg", comments=""))
    summary: dict[str, Any] = {"file": str(path), "samples": len(q), "rate_hz": float(rec["rate"]),
                               "six_axis": mag is None, "precision": args.precision, "settings": settings,
                               "out": str(out)}
    written = ["attitude.csv"]
    if args.estimate_mag_delay:
        from ..timing import aiding_delay

        sel = None if rec["movement"] is None else np.asarray(rec["movement"], dtype=bool)
        d = aiding_delay(rec["gyr"], np.asarray(mag), q, float(rec["rate"]), mask=sel)
        summary["mag_delay_estimate_s"] = d
    if rec["ref"] is not None:
        figs = broad.errors(q, rec["ref"], rec["movement"])
        summary["errors_deg"] = figs.as_dict()
        summary["errors_over"] = "movement phases" if rec["movement"] is not None else "all samples"
        write_with(out / "errors.json", lambda tmp: Path(tmp).write_text(json.dumps(summary, indent=2) + "\n"))
        written.append("errors.json")
        if not args.no_plots:
            _plot(out / "errors.png", rec["t"], broad.error_angles(q, rec["ref"]),
                  f"{path.name}: attitude filter vs reference")
            written.append("errors.png")
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"{path.name}: {len(q)} samples at {rec['rate']:.6g} Hz, "
              f"{'six-axis' if mag is None else 'nine-axis'}, {args.precision}")
        if "errors_deg" in summary:
            f = summary["errors_deg"]
            print(f"error vs reference ({summary['errors_over']}): total {f['total']:.3f}°, heading "
                  f"{f['heading']:.3f}°, inclination {f['inclination']:.3f}° (RMS, BROAD metric)")
        if "mag_delay_estimate_s" in summary:
            d = summary["mag_delay_estimate_s"]
            used = settings.get("mag_delay", 0.0)
            print(f"magnetometer lag behind the gyro (relative to this run's attitude, mag_delay {used:g} s): "
                  f"{d * 1e3:.2f} ms" + (f"; use it with --set mag_delay={d:.4f}" if abs(d) <= 0.05
                                         else " (outside the filter's |mag_delay| <= 0.05 s: not a lag)"))
        print(f"wrote {out}/ ({', '.join(written)})")
    return EXIT_OK
