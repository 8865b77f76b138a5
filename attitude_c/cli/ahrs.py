"""attitude ahrs FILE: run the attitude filter on a recording.

Input: a BROAD trial (.mat, with its optical reference and movement phases;
needs SciPy: pip install 'attitude-c[broad]') or a CSV file with a header:

  t,gx,gy,gz,ax,ay,az,mx,my,mz,qw,qx,qy,qz
  0.00,0.01,-0.02,0.00,0.12,0.05,9.80,21.0,-3.5,-40.2,1,0,0,0

  gx gy gz  gyro, rad/s (--gyr-unit deg/s)
  ax ay az  specific force (+g upward at rest), m/s^2 (--acc-unit g)
  mx my mz  magnetic field, optional, uT (--mag-unit gauss|nT)
  t         time, s, optional (else give --rate)
  qw..qz    reference attitude, optional: the IMU's axes -> ENU, scalar first

Headers are matched in any case; other names are mapped with --columns
(e.g. --columns gx=GyroX,gy=GyroY,gz=GyroZ); the delimiter (, ; tab or
spaces) is found from the header. Example: examples/imu.csv.

Frames: the library's body frame is x right, y forward, z up, the
navigation frame ENU (x east, y north, z up). An IMU mounted otherwise is
declared with --axes (where its x, y, z axes point): an x-forward IMU read
as x-right has its pitch and roll swapped. Euler angles: by default the
library's z-x-y sequence (C = Rz(yaw) Rx(pitch) Ry(roll); yaw counter-
clockwise from north, pitch nose up, roll right side down); --euler zyx
gives aerospace yaw-pitch-roll (z-y-x of the x-forward, y-right, z-down body
in NED: yaw is the heading, clockwise from north).

A gyro that looks like deg/s (its rotation 57x the rotation the magnetometer
sees, or above 2000 deg/s read as rad/s) is refused unless --gyr-unit gives
its unit; an accelerometer that looks like g (median norm near 1) unless
--acc-unit does.

Output (--out DIR): attitude.csv (t, quaternion body -> ENU, yaw/pitch/roll
in degrees; its first line states the frames), attitude.png (estimate and
reference angles, error components, flags, bias estimate) and summary.json
(the printed summary; with a reference BROAD's error metric over the
movement phases of a BROAD trial). Files are written only once every figure
is computed (a run that fails leaves none), each to a temporary name, then
renamed; summary.json last.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .._io import check_output_dir, write_results
from .options import positive

PROG = "attitude ahrs"
#: ``attitude ahrs`` exit statuses (docs/ahrs.md, "Command").
EXIT_OK = 0
EXIT_IO = 1       # the input cannot be read, or an output cannot be written
EXIT_USAGE = 2    # bad option, or the file's content is not a usable recording
EXIT_MISSING = 3  # an optional package the input needs is not installed (SciPy for .mat)

#: Flag bits sampled this often (s) for the figure and the summary.
FLAG_PERIOD = 0.02


def _axes(text: str) -> str:
    from ..errors import InvalidArgument
    from ..frames import axes_matrix

    try:
        axes_matrix(text)
    except InvalidArgument as exc:
        raise argparse.ArgumentTypeError(f"--{exc}") from None
    return text.lower()


def add_csv_options(p: Any, names: str) -> None:
    """The options of a CSV recording (``attitude ahrs``, ``attitude allan``): --rate,
    --columns (``names``: the columns the command reads), the sensors' units and --axes."""
    from ..frames import AXES_PRESETS
    from ..recording import UNITS

    p.add_argument("--rate", type=positive("--rate"), default=None, help="sampling rate, Hz (CSV without a t column)")
    p.add_argument("--columns", action="append", default=[], metavar="NAME=HEADER[,NAME=HEADER...]",
                   help=f"CSV: the file's column for a name ({names})")
    for sensor, what in (("gyr", "gyro"), ("acc", "accelerometer"), ("mag", "magnetometer")):
        units = tuple(UNITS[sensor])
        p.add_argument(f"--{sensor}-unit", choices=units, default=None,
                       help=f"CSV: the {what}'s unit (default {units[0]})")
    p.add_argument("--axes", type=_axes, default="rfu", metavar="XYZ",
                   help="CSV: where the IMU's x, y, z axes point, letters of r l f b u d (right, left, forward, "
                   "back, up, down): " + "; ".join(f"{k} = {v}" for k, v in AXES_PRESETS.items())
                   + " (default rfu)")


def register(sub: Any) -> None:
    p = sub.add_parser(
        "ahrs", help="run the attitude filter (gyro + accelerometer + magnetometer) on a recording",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="exit statuses: 0 done; 1 the input cannot be read or an output cannot be written; 2 bad "
        "option or unusable file content; 3 a package the input needs is missing (SciPy for .mat). "
        "See docs/ahrs.md.")
    p.add_argument("file", metavar="FILE", help="BROAD trial (.mat) or CSV with a header")
    p.add_argument("--out", metavar="DIR", default=None,
                   help="output folder (default: results/ahrs-<file stem>)")
    p.add_argument("--precision", choices=("f64", "f32"), default="f64")
    p.add_argument("--six-axis", action="store_true", help="ignore the magnetometer")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a filter setting (docs/ahrs.md), e.g. --set acc_tau=3 --set method=rv1")
    add_csv_options(p, "t gx gy gz ax ay az mx my mz qw qx qy qz")
    p.add_argument("--euler", choices=("zxy", "zyx"), default="zxy",
                   help="Euler sequence of the output: zxy the library's (default), zyx aerospace yaw-pitch-roll")
    p.add_argument("--estimate-mag-delay", action="store_true",
                   help="also print the magnetometer's lag behind the gyro estimated from this run's attitude "
                   "(attitude_c.aiding_delay; over the movement phases of a BROAD trial), to pass back as "
                   "--set mag_delay=D (docs/ahrs.md, \"Sensor timing\")")
    p.add_argument("--no-plots", action="store_true", help="do not write attitude.png")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=main)


class _Usage(Exception):
    pass


def _settings(items: list[str]) -> dict[str, Any]:
    """The --set options: filter settings, parsed by the one parser every command shares."""
    from ..ahrs_filter import parse_setting

    return dict(parse_setting(it, "--set") for it in items)


def _columns(items: list[str]) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        for part in item.split(","):
            k, sep, v = part.partition("=")
            if not sep or not k.strip() or not v.strip():
                raise _Usage(f"--columns {item!r}: expected NAME=HEADER[,NAME=HEADER...]")
            out[k.strip().lower()] = v.strip()
    return out


def _csv_options(args: argparse.Namespace) -> dict[str, Any]:
    units = {s: u for s in ("gyr", "acc", "mag") if (u := getattr(args, f"{s}_unit")) is not None}
    return {"columns": _columns(args.columns), "units": units, "axes": args.axes}


def _read(path: Path, args: argparse.Namespace) -> tuple[Any, np.ndarray | None]:
    """The recording (attitude_c.recording.Recording) and its movement mask (BROAD)."""
    from ..recording import Recording, read_csv

    opts = _csv_options(args)
    if path.suffix.lower() != ".mat":
        return read_csv(path, rate=args.rate, **opts), None
    given = ([f"--{s}-unit" for s in opts["units"]] + ["--columns"] * bool(opts["columns"])
             + ["--axes"] * (opts["axes"] != "rfu") + ["--rate"] * (args.rate is not None))
    if given:
        raise _Usage(f"{', '.join(given)}: for CSV files (a BROAD trial carries its own)")
    from .. import broad

    tr = broad.load_trial(path)
    rec = Recording(t=np.arange(tr.n) / tr.rate, rate=tr.rate, gyr=tr.gyr, acc=tr.acc, mag=tr.mag, ref=tr.quat)
    return rec, tr.movement


def guarded(prog: str, body: Callable[[argparse.Namespace], int], args: argparse.Namespace) -> int:
    """``body(args)``, with a user mistake, a missing package or an OS error reported as its
    one line and exit status (EXIT_USAGE, EXIT_MISSING, EXIT_IO); also ``attitude allan``'s."""
    from ..errors import AttitudeError
    from . import fail, os_error_line

    try:
        return body(args)
    except (_Usage, AttitudeError, ValueError, TypeError) as exc:
        return fail(prog, str(exc), EXIT_USAGE)
    except ImportError as exc:  # the message names what to install
        return fail(prog, str(exc), EXIT_MISSING)
    except OSError as exc:
        if getattr(sys.stdout, "failed", None) is exc:  # stdout itself: the command's caller reports it
            raise
        return fail(prog, os_error_line(exc), EXIT_IO)


def main(args: argparse.Namespace) -> int:
    return guarded(PROG, _main, args)


def _run(rec: Any, mag: np.ndarray | None, precision: str,
         settings: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The filter over the recording in blocks of FLAG_PERIOD: the attitude (N, 4),
    and at each block's last sample its index, flags and bias estimate (rad/s)."""
    from ..ahrs_filter import Ahrs

    f = Ahrs(rate=rec.rate, precision=precision, **settings)  # type: ignore[arg-type]
    n = len(rec.gyr)
    step = max(1, round(FLAG_PERIOD * rec.rate))
    q = np.empty((n, 4))
    ends, flags, bias = [], [], []
    for a in range(0, n, step):
        b = min(n, a + step)
        q[a:b] = f.update(rec.gyr[a:b], rec.acc[a:b], None if mag is None else mag[a:b])
        ends.append(b - 1)
        flags.append(f.flags)
        bias.append(f.bias)
    return q, np.array(ends), np.array(flags), np.array(bias)


def _about(path: Path, fn: Any, *a: Any) -> Any:
    """``fn(*a)``, its complaint about the file's content naming the file."""
    from ..errors import InvalidArgument

    try:
        return fn(*a)
    except (InvalidArgument, ValueError) as exc:
        text = str(exc)
        raise _Usage(text if str(path) in text else f"{path}: {text}") from None


def _main(args: argparse.Namespace) -> int:
    path = Path(args.file)
    if not path.is_file():
        raise FileNotFoundError(2, "no such file", str(path))
    settings = _settings(args.set)
    out = check_output_dir(Path(args.out) if args.out else Path("results") / f"ahrs-{path.stem}")
    rec, movement = _about(path, _read, path, args)
    mag = None if args.six_axis else rec.mag
    if args.estimate_mag_delay and mag is None:
        raise _Usage("--estimate-mag-delay needs a magnetometer (mx my mz columns, not --six-axis)")
    if rec.gyr_scale is not None and "gyr" in _csv_options(args)["units"] and not 0.5 < rec.gyr_scale < 2:
        print(f"{PROG}: warning: with --gyr-unit {args.gyr_unit} the gyro's rotation is "
              f"{1 / rec.gyr_scale:.3g}x the rotation the magnetometer sees (1x expected)", file=sys.stderr)
    q, ends, flags, bias = _run(rec, mag, args.precision, settings)
    summary = _summary(args, path, rec, mag, settings, out, flags, bias)
    if args.estimate_mag_delay:
        from ..timing import aiding_delay

        summary["mag_delay_estimate_s"] = aiding_delay(rec.gyr, np.asarray(mag), q, float(rec.rate), mask=movement)
    if rec.ref is not None:
        from .. import broad

        summary["errors_deg"] = _about(path, broad.errors, q, rec.ref, movement).as_dict()
        summary["errors_over"] = "movement phases" if movement is not None else "all samples"
    e, table, head = _attitude_table(rec.t, q, args)
    files: list[tuple[Path, Any]] = [(out / "attitude.csv", lambda tmp: np.savetxt(
        tmp, table, delimiter=",", fmt="%.9g", header=head, comments=""))]
    if not args.no_plots:
        files.append((out / "attitude.png", lambda tmp: _plot(tmp, path, rec, q, e, movement, (ends, flags, bias),
                                                               args.euler)))
    summary["files"] = [f.name for f, _ in files] + ["summary.json"]
    text = json.dumps(summary, indent=2) + "\n"
    files.append((out / "summary.json", lambda tmp: tmp.write_text(text, encoding="utf-8")))
    write_results(files)  # only now, every figure computed: a run that fails leaves no file of its own
    _print(summary, path, mag is None, args)
    return EXIT_OK


def _summary(args: argparse.Namespace, path: Path, rec: Any, mag: Any, settings: dict[str, Any], out: Path,
             flags: np.ndarray, bias: np.ndarray) -> dict[str, Any]:
    from ..names import C
    from .ahrs_plot import FLAGS

    s: dict[str, Any] = {"file": str(path), "samples": len(rec.gyr), "rate_hz": float(rec.rate),
                         "six_axis": mag is None, "precision": args.precision, "settings": settings,
                         "euler": args.euler, "out": str(out)}
    if path.suffix.lower() != ".mat":
        s["csv"] = _csv_options(args)
        s["gyr_scale_vs_field"] = None if rec.gyr_scale is None else round(rec.gyr_scale, 4)
    s["flag_fractions"] = {lab: float(np.mean((flags & C[name]) != 0)) for name, lab in FLAGS}
    s["bias_final_deg_s"] = np.degrees(bias[-1]).round(5).tolist()
    return s


def _attitude_table(t: np.ndarray, q: np.ndarray, args: argparse.Namespace) -> tuple[np.ndarray, np.ndarray, str]:
    """The Euler angles (°), attitude.csv's rows and its header (its first line states the frames)."""
    from ..frames import euler

    e = np.degrees(euler(q, args.euler))
    seq = ("z-x-y (C = Rz(yaw) Rx(pitch) Ry(roll), yaw counter-clockwise from north)" if args.euler == "zxy"
           else "z-y-x aerospace (x-forward y-right z-down body in NED, yaw clockwise from north)")
    note = (f"# body x right, y forward, z up (IMU axes {args.axes}); quaternion body -> ENU, scalar first; "
            f"Euler {seq}, degrees")
    head = f"t,qw,qx,qy,qz,yaw_{args.euler}_deg,pitch_{args.euler}_deg,roll_{args.euler}_deg"
    return np.asarray(e), np.column_stack([t, q, e]), note + "\n" + head


def _plot(path: Path, src: Path, rec: Any, q: np.ndarray, e: np.ndarray, movement: Any,
          blocks: tuple[np.ndarray, np.ndarray, np.ndarray], sequence: str) -> None:
    from .. import broad
    from ..frames import euler
    from .ahrs_plot import Trace, write_plot

    ends, flags, bias = blocks
    ref_e = errs = None
    if rec.ref is not None:
        ok = np.all(np.isfinite(rec.ref), axis=1)
        ref_e = np.full((len(q), 3), np.nan)
        ref_e[ok] = np.degrees(euler(rec.ref[ok], sequence))  # type: ignore[arg-type]
        tot, head, incl = (np.degrees(a) for a in broad.error_angles(q, rec.ref))
        errs = (tot, head, incl)
    tr = Trace(t=rec.t, euler=e, ref_euler=ref_e, errors=errs, movement=movement, tb=rec.t[ends], flags=flags,
               bias=np.degrees(bias), sequence=sequence)
    write_plot(path, tr, f"{src.name}: attitude filter" + (" vs reference" if ref_e is not None else ""))


def _print(summary: dict[str, Any], path: Path, six: bool, args: argparse.Namespace) -> None:
    if args.json:
        print(json.dumps(summary, indent=2))
        return
    print(f"{path.name}: {summary['samples']} samples at {summary['rate_hz']:.6g} Hz, "
          f"{'six-axis' if six else 'nine-axis'}, {args.precision}")
    if "errors_deg" in summary:
        f = summary["errors_deg"]
        print(f"error vs reference ({summary['errors_over']}): total {f['total']:.3f}°, heading "
              f"{f['heading']:.3f}°, inclination {f['inclination']:.3f}° (RMS, BROAD metric)")
    fr = summary["flag_fractions"]
    print("flags (share of the run): " + ", ".join(f"{k} {v:.1%}" for k, v in fr.items())
          + "; final gyro bias " + ", ".join(f"{b:+.3f}" for b in summary["bias_final_deg_s"]) + " °/s")
    if "mag_delay_estimate_s" in summary:
        d = summary["mag_delay_estimate_s"]
        used = summary["settings"].get("mag_delay", 0.0)
        print(f"magnetometer lag behind the gyro (relative to this run's attitude, mag_delay {used:g} s): "
              f"{d * 1e3:.2f} ms" + (f"; use it with --set mag_delay={d:.4f}" if abs(d) <= 0.05
                                     else " (outside the filter's |mag_delay| <= 0.05 s: not a lag)"))
    print(f"wrote {summary['out']}/ ({', '.join(summary['files'])})")
