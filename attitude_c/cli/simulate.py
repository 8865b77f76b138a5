"""``attitude simulate``: the paper's whole system end to end in simulation."""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import math
import sys
import time
from pathlib import Path
from typing import Any, Callable

from ..core import METHODS as _METHODS
from ..sim.trajectory import TRAJECTORIES
from . import options

#: Simulated time when --duration is not given (and the trajectory is not a file).
DEFAULT_DURATION_S = 60.0


# numeric options: the shared validator (attitude_c/cli/options.py)
_positive = options.positive
_nonneg = options.nonneg
_int_range = options.integer
_triple = options.triple
_ber = options.probability("BER", below=0.5)


def _methods(text: str) -> tuple[str, ...]:
    ms = tuple(m.strip() for m in text.split(",") if m.strip())
    bad = [m for m in ms if m not in _METHODS]
    if bad or not ms:
        raise argparse.ArgumentTypeError(f"unknown method(s) {bad or text!r}; choose from "
                                         f"{', '.join(_METHODS)}")
    return ms


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "simulate",
        help="run the paper's system end to end in simulation (errors, plots, budget)",
        description="Simulate the whole attitude measurement system of the paper: a known "
        "trajectory, gyros, the TLC2543 ADC (C driver + device model), the acquisition board, "
        "the serial link (C sender/receiver, optional bit errors) and the integrator; compare "
        "the computed attitude with the truth. Writes errors.png (paper Fig. 8 style), "
        "attitude.png, timeseries.csv and summary.json into the output directory and prints a "
        "table. With --budget, switches the error sources on one at a time for every method.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    g = p.add_argument_group("scenario")
    g.add_argument("--trajectory", default=argparse.SUPPRESS,
                   choices=TRAJECTORIES,
                   help="reference motion (default: paper, or csv when --trajectory-file is given; "
                   "csv needs --trajectory-file)")
    g.add_argument("--trajectory-file", metavar="CSV", default=None,
                   help="CSV with columns time,yaw,pitch,roll (rad; *_deg for degrees) or "
                   "time,q0,q1,q2,q3; implies --trajectory csv")
    g.add_argument("--duration", type=_positive("--duration"), default=argparse.SUPPRESS, metavar="S",
                   help=f"simulated time (s) (default: {DEFAULT_DURATION_S:g}, or the span of the "
                   "--trajectory-file, which it may not exceed)")
    g.add_argument("--period", type=_positive("--period"), default=0.08, metavar="S",
                   help="gyro sample period: one angle increment per period (s); the paper: 0.08")
    g.add_argument("--amplitude", type=_triple("--amplitude"), default="30,20,25",
                   metavar="Y,P,R", help="paper trajectory: sinusoid amplitudes (deg)")
    g.add_argument("--frequency", type=_triple("--frequency"), default="0.20,0.25,0.30",
                   metavar="Y,P,R", help="paper trajectory: frequencies (Hz)")
    g.add_argument("--phase", type=_triple("--phase"), default="0,30,60",
                   metavar="Y,P,R", help="paper trajectory: phases (deg)")
    g.add_argument("--cone-angle", type=_nonneg("--cone-angle"), default=20.0, metavar="DEG",
                   help="coning trajectory: half-angle (deg)")
    g.add_argument("--cone-frequency", type=_nonneg("--cone-frequency"), default=0.5, metavar="HZ",
                   help="coning trajectory: coning frequency (Hz)")
    g.add_argument("--rate", type=_triple("--rate"), default="10,-5,20", metavar="X,Y,Z",
                   help="constant-rate trajectory: body rate (deg/s; write --rate=-10,5,0 when "
                   "it starts with a minus)")
    g = p.add_argument_group("system")
    g.add_argument("--method", default="rv3", choices=_METHODS, help="integrator method")
    g.add_argument("--precision", default="f64", choices=("f64", "f32", "fixed"),
                   help="integrator arithmetic")
    g.add_argument("--sensors", default="full", choices=("ideal", "quantized", "full"),
                   help="ideal: exact increments; quantized: perfect gyro through ADC and board; "
                   "full: plus gyro noise, bias, filter, saturation")
    g.add_argument("--gyro", default="cg-l53", choices=("cg-l53", "adxrs150", "ideal"),
                   help="gyro model preset (docs/simulation.md gives the figures and sources)")
    g.add_argument("--oversample", type=_int_range("--oversample", 1, 16), default=16, metavar="N",
                   help="ADC conversions per axis summed by the board per period")
    g.add_argument("--sample-at", default="mid", choices=("mid", "start"),
                   help="where in each sub-interval the board converts: mid (midpoint rule) or "
                   "start (one rate sample at the start: the naive design)")
    g.add_argument("--calibration", type=_nonneg("--calibration"), default=60.0, metavar="S",
                   help="static zero-rate calibration before the run (s)")
    g.add_argument("--adc", default="auto", choices=("auto", "tlc2543", "ideal"),
                   help="tlc2543: C driver against the device model; ideal: vectorized quantizer; "
                   "auto: tlc2543")
    g.add_argument("--firmware", choices=("none", "s51"), default="none",
                   help="s51: the acquisition side is the real AT89S51 firmware running in s51 "
                   "(a source checkout with sdcc, s51 and socat: run it as python -m toolchain.simulate "
                   "--firmware s51 ...); the motion is then the firmware's own sinusoidal body rates")
    g.add_argument("--link", default="c", choices=("c", "none"),
                   help="c: every sample through the C link sender and receiver; none: direct")
    g.add_argument("--ber", type=_ber, default=0.0, help="bit error rate of the channel simulator")
    g.add_argument("--attempts", type=_int_range("--attempts", 1, 255), default=5,
                   help="link sender attempts per block before giving up")
    g = p.add_argument_group("run")
    g.add_argument("--seed", type=_int_range("--seed", 0, 2**63 - 1), default=0,
                   help="random seed (noise, bias, channel errors)")
    g.add_argument("--out", metavar="DIR", default=None,
                   help="output directory (default results/<run>/)")
    g.add_argument("--budget", action="store_true",
                   help="error budget: sources on one at a time, for every method")
    g.add_argument("--methods", type=_methods, default=_METHODS, metavar="M1,M2",
                   help="methods of the budget")
    g.add_argument("--budget-ber", type=_ber, default=1e-3, metavar="BER",
                   help="BER of the budget's link stage")
    g.add_argument("--no-plots", action="store_true", help="skip the PNG files")
    g.add_argument("--no-progress", action="store_true", help="no progress bar")
    g.add_argument("--json", action="store_true", help="print the JSON summary instead of the table")
    p.set_defaults(func=run)


class _Progress:
    """tqdm bar per stage, shown only for stages with enough work."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.bars: dict[str, Any] = {}

    def __call__(self, stage: str, done: int, total: int) -> None:
        if not self.enabled or total < 2000 and stage != "budget":
            return
        bar = self.bars.get(stage)
        if bar is None:
            from tqdm import tqdm

            bar = tqdm(total=total, desc=stage, unit="it", leave=False, file=sys.stderr,
                       dynamic_ncols=True, mininterval=0.3)
            self.bars[stage] = bar
        bar.update(done - bar.n)
        if done >= total:
            bar.close()

    def close(self) -> None:
        for b in self.bars.values():
            b.close()


def build_config(args: argparse.Namespace) -> Any:
    from ..sim import AdcModel, Board, SimConfig, gyro_preset, make_trajectory
    from ..sim.adc import AdcBackend

    given = getattr(args, "trajectory", None)
    trajectory = given or ("csv" if args.trajectory_file else "paper")
    duration: float | None = getattr(args, "duration", None)
    if args.firmware != "none":
        from ..sim import Conditioning, source

        if given or args.trajectory_file:
            raise ValueError(f"--firmware {args.firmware} uses the firmware's own motion: drop --trajectory")
        # a source registered by the tooling layer (toolchain/firmware.py): its own motion
        traj: Any = source(args.firmware).trajectory(args.period, gyro_preset(args.gyro), Conditioning(),
                                                     duration or DEFAULT_DURATION_S)
    elif trajectory == "csv":
        if not args.trajectory_file:
            raise ValueError("--trajectory csv needs --trajectory-file CSV")
        traj = make_trajectory("csv", path=args.trajectory_file)
        if duration is None:
            duration = traj.span  # the whole file, not a minute of it held still
        elif duration > traj.span * (1 + 1e-9):
            raise ValueError(f"--duration {duration:g} s is longer than the trajectory file "
                             f"{args.trajectory_file} ({traj.span:g} s, t = {traj.t_start:g} .. "
                             f"{traj.t_end:g} s): give at most {traj.span:g} s, or leave --duration "
                             "out to run the whole file")
    elif args.trajectory_file:
        raise ValueError("--trajectory-file is only used with --trajectory csv")
    elif trajectory == "paper":
        traj = make_trajectory("paper", amplitude=[math.radians(v) for v in args.amplitude],
                               frequency=list(args.frequency),
                               phase=[math.radians(v) for v in args.phase])
    elif trajectory == "coning":
        traj = make_trajectory("coning", half_angle=math.radians(args.cone_angle),
                               frequency=args.cone_frequency)
    elif trajectory == "constant-rate":
        traj = make_trajectory("constant-rate", rate=[math.radians(v) for v in args.rate])
    else:
        traj = make_trajectory("static")
    adc: AdcBackend = "tlc2543" if args.adc == "auto" else args.adc
    return SimConfig(trajectory=traj, duration=duration or DEFAULT_DURATION_S, period=args.period,
                     method=args.method, precision=args.precision, sensors=args.sensors,
                     gyro=gyro_preset(args.gyro), adc=AdcModel(backend=adc),
                     board=Board(oversample=args.oversample, sample_at=args.sample_at), calibration_s=args.calibration,
                     link=args.link, ber=args.ber, link_attempts=args.attempts, seed=args.seed,
                     firmware=None if args.firmware == "none" else args.firmware)


def run(args: argparse.Namespace) -> int:
    from ..errors import AttitudeError
    from . import EXIT_OS, EXIT_USAGE, os_error_line

    try:
        return _run(args)
    except OSError as exc:  # the output location, a full disk (ResultsIncomplete says which files)
        print(f"attitude simulate: error: {os_error_line(exc)}", file=sys.stderr)
        return EXIT_OS
    except (AttitudeError, ValueError, TypeError) as exc:
        print(f"attitude simulate: error: {exc}", file=sys.stderr)
        return EXIT_USAGE


def _run(args: argparse.Namespace) -> int:
    from .._io import check_output_dir, write_results
    from ..sim import format_budget, format_table, plot_budget, run_budget, simulate, write_run
    from ..sim.report import to_jsonable

    cfg = build_config(args)
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    name = f"{stamp}-{'budget' if args.budget else cfg.method}-{cfg.trajectory.name}-s{cfg.seed}"
    out = Path(args.out) if args.out else Path("results") / name
    made = not out.exists()
    check_output_dir(out)  # before the run: a wrong --out costs nothing
    prog = _Progress(enabled=not args.no_progress)
    t0 = time.perf_counter()
    ok = False
    try:
        if args.budget:
            b = run_budget(cfg, methods=args.methods, ber=args.budget_ber, progress=prog)
            d = b.to_dict()
            d["elapsed_s"] = time.perf_counter() - t0
            steps: list[tuple[Path, Callable[[Path], object]]] = [
                (out / "budget.json", lambda p: p.write_text(json.dumps(to_jsonable(d), indent=2) + "\n")),
                (out / "budget.md", lambda p: p.write_text(format_budget(b, markdown=True) + "\n"))]
            if not args.no_plots:
                steps.append((out / "budget.png", lambda p: plot_budget(b, p)))
            prog.close()
            write_results(steps)
            if args.json:
                print(json.dumps(to_jsonable(d), indent=2))
            else:
                print("error budget: RMS attitude-angle error (rad) after each stage "
                      "(contribution of the stage's source)")
                print(format_budget(b))
                print(f"wrote {out}/ (budget.json, budget.md{', budget.png' if not args.no_plots else ''})"
                      f" in {time.perf_counter() - t0:.1f} s")
            ok = True
            return 0
        res = simulate(cfg, progress=prog)
        files = write_run(res, out, plots=not args.no_plots)
        ok = True
    finally:
        prog.close()
        if not ok and made:
            with contextlib.suppress(OSError):  # the directory made for this run, if left empty
                out.rmdir()
    if args.json:
        print(json.dumps(to_jsonable(res.summary), indent=2))
    else:
        print(format_table(res.summary))
        print(f"wrote {out}/ ({', '.join(p.name for p in files.values())})")
    return 0
