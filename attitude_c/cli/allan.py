"""attitude allan FILE: the sensors' noise terms from a rest recording, and the
attitude filter's settings they give (docs/noise.md).

Input: a recording of the sensor at rest (the longer the better: two hours
give the bias terms; docs/noise.md says how well), one of

  a CSV file as attitude ahrs reads it (gx gy gz, ax ay az, t or --rate;
      --columns, --gyr-unit, --acc-unit, --axes as there);
  a BROAD trial (.mat; needs SciPy: pip install 'attitude-c[broad]');
  a recording of the board's stream: attitude-rx's JSON Lines (its rate_dps:
      the gyro only), as attitude view --replay reads it.

Per gyro and accelerometer axis: the overlapping Allan deviation at octave
cluster times with its 1-sigma interval (allantools: pip install
'attitude-c[noise]'), and the fit of the white noise N (slope -1/2, read at
tau = 1 s), the bias instability B (the flat floor is 0.664 B) and the bias
random walk K (slope +1/2, read at tau = 3 s), each with its 1-sigma.
From them the filter's settings (gyr_noise_rest, gyr_noise, bias_noise,
rest_noise, acc_noise: docs/noise.md says which term sets which and why).
With --calibrated (parts whose only error in motion is their noise: scale
and misalignment calibrated out, as on a turntable) the settings carry no
allowance for model error, and a magnetometer in the file (mx my mz; a
BROAD trial's) gives mag_noise: the reported covariance is then the one to
pass on (docs/noise.md, "Parts whose only error is their noise").

Output (--out DIR): allan.json (the deviations, the terms, the settings) and
allan.png (log-log, with the fitted lines); --write-config FILE writes the
settings into attitude-rx's config file (its other lines kept), written to
a temporary name, then renamed.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._io import check_output_dir, write_text, write_with
from .ahrs import EXIT_OK, _csv_options, _Usage, add_csv_options, guarded
from .options import positive

PROG = "attitude allan"
#: Units of the terms, per sensor: (white noise N, bias instability B, random walk K).
UNITS = {"gyro": ("rad/√s", "rad/s", "rad/s/√s"), "accel": ("m/s²·√s", "m/s²", "m/s²/√s"),
         "mag": ("µT·√s", "µT", "µT/√s")}
#: The deviation's unit, per sensor (the plot's axes).
RATE_UNITS = {"gyro": "rad/s", "accel": "m/s²", "mag": "µT"}


def register(sub: Any) -> None:
    p = sub.add_parser(
        "allan", help="noise terms (Allan deviation) of a rest recording and the filter settings they give",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="exit statuses: 0 done; 1 the input cannot be read or an output cannot be written; 2 bad option "
        "or unusable file content (too short, not finite, no rates); 3 a package is missing (allantools; SciPy "
        "for .mat). See docs/noise.md.")
    p.add_argument("file", metavar="FILE", help="CSV with a header, BROAD trial (.mat) or attitude-rx JSON Lines")
    p.add_argument("--out", metavar="DIR", default=None, help="output folder (default: results/allan-<file stem>)")
    add_csv_options(p, "t gx gy gz ax ay az")
    p.add_argument("--gravity", type=positive("--gravity"), default=None,
                   help="local gravity, m/s² (acc_noise = N/gravity; default the filter's 9.81)")
    p.add_argument("--calibrated", action="store_true",
                   help="parts whose only error in motion is their noise (turntable-calibrated): no model-error "
                        "floors, mag_noise from the magnetometer (mx my mz) when the file has one")
    p.add_argument("--write-config", metavar="FILE", default=None,
                   help="write the filter settings into this attitude-rx config file (other lines kept)")
    p.add_argument("--no-plots", action="store_true", help="do not write allan.png")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=main)


@dataclass(frozen=True)
class _Block:
    """The filter settings as a block of attitude-rx config lines (cli.calibrate.merged_config)."""

    prefix: str
    text: str
    comment: str = "# attitude allan: filter noise settings from the Allan deviation (docs/noise.md)"

    def keys(self) -> list[str]:
        return [ln.split("=", 1)[0].strip() for ln in self.lines()]

    def lines(self) -> list[str]:
        return [ln for ln in self.text.splitlines() if ln and not ln.startswith("#")]


def main(args: argparse.Namespace) -> int:
    return guarded(PROG, _main, args)


def _is_stream(path: Path) -> bool:
    """attitude-rx JSON Lines: the first line that is not a comment is a JSON object."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            s = line.strip()
            if s and not s.startswith("#"):
                return s.startswith("{")
    return False


def _read(path: Path, args: argparse.Namespace) -> tuple[dict[str, np.ndarray], float]:
    """The sensors' samples ({"gyro": (N, 3) rad/s, "accel": (N, 3) m/s², "mag": (N, 3) µT where
    the file has one}) and their rate (Hz)."""
    if path.suffix.lower() == ".mat":
        from .. import broad

        tr = broad.load_trial(path)
        return {"gyro": tr.gyr, "accel": tr.acc, "mag": tr.mag}, float(tr.rate)
    if _is_stream(path):
        return _read_stream(path)
    from ..recording import read_csv

    rec = read_csv(path, rate=args.rate, **_csv_options(args))
    out = {"gyro": rec.gyr, "accel": rec.acc}
    return (out if rec.mag is None else out | {"mag": rec.mag}), float(rec.rate)


def _read_stream(path: Path) -> tuple[dict[str, np.ndarray], float]:
    from ..view.sources import load_recording
    from ..view.stream import COLUMNS

    rec = load_recording(path)
    rows = np.array([p for _, what, p in rec.items() if what == "sample"], dtype=float)
    i = COLUMNS.index("rate_x")
    rate, t = rows[:, i:i + 3], rows[:, COLUMNS.index("t")]
    if not np.all(np.isfinite(rate)):
        raise _Usage(f"{path}: samples without rate_dps (attitude-rx --format jsonl carries the gyro's rates)")
    dt = np.diff(t)
    if len(dt) == 0 or not np.median(dt) > 0:
        raise _Usage(f"{path}: the samples' times do not advance")
    return {"gyro": rate}, 1.0 / float(np.median(dt))


def _main(args: argparse.Namespace) -> int:
    from ..noise import allan, config_text

    path = Path(args.file)
    if not path.is_file():
        raise FileNotFoundError(2, "no such file", str(path))
    out = check_output_dir(Path(args.out) if args.out else Path("results") / f"allan-{path.stem}")
    data, rate = _read(path, args)
    if args.calibrated and "accel" not in data:
        raise _Usage(f"{path}: --calibrated needs the accelerometer (ax ay az): the stream carries the gyro only")
    _warn_motion(data["gyro"])
    res = {name: allan(x, rate) for name, x in data.items()}
    settings = _settings(res, data, args)
    summary: dict[str, Any] = {"file": str(path), "samples": len(data["gyro"]), "rate_hz": rate, "hours": len(data["gyro"]) / rate / 3600,
               "units": {k: dict(zip("NBK", UNITS[k])) for k in res}, "settings": settings,
               "sensors": {k: r.as_dict() for k, r in res.items()}, "out": str(out), "files": ["allan.json"]}
    if not args.no_plots:
        from ..noise import plot

        write_with(out / "allan.png", lambda tmp: plot({k: (r, RATE_UNITS[k]) for k, r in res.items()}, tmp,
                                                       f"{path.name}: Allan deviation, {summary['hours']:.2g} h at rest"))
        summary["files"].append("allan.png")
    write_text(out / "allan.json", json.dumps(summary, indent=1) + "\n")
    if args.write_config:
        _write_config(Path(args.write_config), config_text(settings, path.name))
    _print(summary, res, args)
    return EXIT_OK


def _settings(res: dict[str, Any], data: dict[str, np.ndarray], args: argparse.Namespace) -> dict[str, float]:
    """MAPPING, or with --calibrated MAPPING_CALIBRATED (mag_noise where there is a magnetometer,
    across the horizontal field of the recording's mean)."""
    from ..noise import filter_settings, horizontal_field

    if not args.calibrated:
        return filter_settings(res["gyro"], res.get("accel"), args.gravity)
    mag_h = horizontal_field(data["accel"], data["mag"]) if "mag" in data else None
    return filter_settings(res["gyro"], res["accel"], args.gravity, calibrated=True, mag=res.get("mag"),
                           mag_h=mag_h)


def _warn_motion(gyr: np.ndarray) -> None:
    """A warning (not an error) when the gyro moves: more than 1 % of the samples further than
    the filter's rest threshold (rest_gyr_th) from zero, as its rest detector judges."""
    import sys

    from ..ahrs_filter import default_settings

    th = float(default_settings()["rest_gyr_th"])
    moving = float(np.mean(np.linalg.norm(gyr, axis=1) > th))
    if moving > 0.01:
        print(f"{PROG}: warning: the gyro is not at rest ({moving:.1%} of the samples turn faster than "
              f"rest_gyr_th = {th:g} rad/s): the terms describe the motion, not the noise", file=sys.stderr)


def _write_config(path: Path, text: str) -> None:
    from .calibrate import merged_config

    old = path.read_text(encoding="utf-8") if path.exists() else ""
    write_text(path, merged_config(old, [_Block("allan", text)]))  # type: ignore[list-item]


def _print(summary: dict[str, Any], res: dict[str, Any], args: argparse.Namespace) -> None:
    if args.json:
        print(json.dumps({k: v for k, v in summary.items() if k != "sensors"} | {
            "terms": {k: [t.as_dict() for t in r.terms] for k, r in res.items()}}, indent=1))
        return
    print(f"{Path(summary['file']).name}: {summary['samples']} samples at {summary['rate_hz']:.6g} Hz "
          f"({summary['hours']:.3g} h)")
    for name, r in res.items():
        un, ub, uk = UNITS[name]
        for j, t in enumerate(r.terms):
            print(f"  {name} {'xyz'[j]}: N {t.n:.4g} ± {t.n_sigma:.2g} {un}, B {t.b:.4g} ± {t.b_sigma:.2g} {ub}, "
                  f"K {t.k:.4g} ± {t.k_sigma:.2g} {uk} (floor {t.adev_min:.3g} at τ {t.tau_min:g} s)")
    print("filter settings: " + ", ".join(f"{k} {v:.4g}" for k, v in summary["settings"].items()))
    if args.write_config:
        print(f"wrote {args.write_config}")
    print(f"wrote {summary['out']}/ ({', '.join(summary['files'])})")
