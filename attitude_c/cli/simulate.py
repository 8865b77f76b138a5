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
from ..sim.accelmag import ACCEL_PRESETS, MAG_PRESETS
from ..sim.aided import AidedPlan
from ..sim.frontend import ACCEL_FRONTENDS, MAG_FRONTENDS
from ..sim.sensors import GYRO_PRESETS
from ..sim.trajectory import TRAJECTORIES
from . import options

#: Simulated time when --duration is not given (and the trajectory is not a file).
DEFAULT_DURATION_S = 60.0
#: The paper's sample period (s): the default --period of the gyro board.
PAPER_PERIOD_S = 0.08


# numeric options: the shared validator (attitude_c/cli/options.py)
_positive = options.positive
_nonneg = options.nonneg
_int_range = options.integer
_triple = options.triple
_ber = options.probability("BER", below=0.5)


def _floats(kind: str, counts: tuple[int, ...]) -> Callable[[str], tuple[float, ...]]:
    def conv(text: str) -> tuple[float, ...]:
        parts = [p for p in text.replace(" ", "").split(",") if p != ""]
        if len(parts) not in counts:
            raise argparse.ArgumentTypeError(f"{kind}: give {' or '.join(map(str, counts))} comma-separated "
                                             f"values, got {text!r}")
        try:
            vals = tuple(float(p) for p in parts)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{kind}: not a number in {text!r}") from None
        if not all(math.isfinite(v) for v in vals):
            raise argparse.ArgumentTypeError(f"{kind}: values must be finite, got {text!r}")
        return vals
    return conv


def _disturbance(text: str) -> tuple[float, float, tuple[float, float, float], float, str]:
    """START,END,X,Y,Z[,RAMP[,FRAME]] → (start, end, field, ramp, frame)."""
    parts = [p for p in text.replace(" ", "").split(",") if p != ""]
    frame = "body"
    if parts and parts[-1] in ("body", "nav"):
        frame = parts.pop()
    if len(parts) not in (5, 6):
        raise argparse.ArgumentTypeError(f"--disturbance: give START,END,X,Y,Z[,RAMP][,body|nav] (s, µT), "
                                         f"got {text!r}")
    try:
        v = [float(p) for p in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"--disturbance: not a number in {text!r}") from None
    if not all(math.isfinite(x) for x in v):
        raise argparse.ArgumentTypeError(f"--disturbance: values must be finite, got {text!r}")
    return v[0], v[1], (v[2], v[3], v[4]), v[5] if len(v) == 6 else 0.0, frame


def _ahrs_setting(text: str) -> tuple[str, Any]:
    """NAME=VALUE of the attitude filter's settings (names checked against the filter's)."""
    from ..ahrs_filter import SETTINGS

    name, sep, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not sep or not name or not value:
        raise argparse.ArgumentTypeError(f"--ahrs-setting expects NAME=VALUE, got {text!r}")
    if name == "method":
        return name, value
    if name not in SETTINGS:
        raise argparse.ArgumentTypeError(f"unknown filter setting {name!r} (known: method, "
                                         f"{', '.join(SETTINGS)}; docs/ahrs.md)")
    try:
        v = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--ahrs-setting {name}: expected a number, got {value!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"--ahrs-setting {name}: must be finite, got {value!r}")
    return name, v


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
    g.add_argument("--period", type=_positive("--period"), default=None, metavar="S",
                   help=f"gyro sample period: one angle increment per period (s) (default: the paper's "
                   f"{PAPER_PERIOD_S:g}; with --board aided9 the aided firmware's {AidedPlan().period_s:g})")
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
    g.add_argument("--translation", type=_triple("--translation"), default="5,5,1", metavar="E,N,U",
                   help="paper-translation trajectory: sinusoidal translation amplitudes (m, ENU)")
    g.add_argument("--translation-frequency", type=_triple("--translation-frequency"), default="0.15,0.10,0.25",
                   metavar="E,N,U", help="paper-translation trajectory: translation frequencies (Hz)")
    g.add_argument("--turntable-rate", type=options.real("--turntable-rate"), default=5.0, metavar="DEG_S",
                   help="turntable trajectory: rate about body z (deg/s; the FPGA+DSP paper's 5)")
    g.add_argument("--turn-rate", type=_positive("--turn-rate"), default=10.0, metavar="DEG_S",
                   help="level-turn trajectory: peak turn rate (deg/s)")
    g.add_argument("--turns", type=options.real("--turns"), default=1.0, metavar="N",
                   help="level-turn trajectory: turns (negative: clockwise)")
    g.add_argument("--rest", type=_nonneg("--rest"), default=10.0, metavar="S",
                   help="level-turn trajectory: rest before and after the turn (s)")
    g = p.add_argument_group("system")
    g.add_argument("--estimator", default="integrator", choices=("integrator", "ahrs"),
                   help="integrator: the paper's strapdown integrator of the gyros (--method, --precision); "
                   "ahrs: the attitude filter (docs/ahrs.md) fed the gyro rates, the accelerometer (needs "
                   "--accel) and the magnetometer (--mag; six-axis without)")
    g.add_argument("--ahrs-setting", type=_ahrs_setting, action="append", default=None, metavar="NAME=VALUE",
                   help="a setting of the attitude filter (attitude_c.ahrs keywords, SI units: rad, s; "
                   "method by name); may be repeated; declination and gravity default to the simulated "
                   "environment's")
    g.add_argument("--ahrs-init", default="truth", choices=("truth", "align"),
                   help="ahrs start: truth (the true initial attitude, as the integrator) or align (the "
                   "filter aligns itself on its first sample: tilt from the accelerometer, heading from "
                   "the magnetometer, or 0 without one)")
    g.add_argument("--method", default="rv3", choices=_METHODS, help="integrator method")
    g.add_argument("--precision", default="f64", choices=("f64", "f32", "fixed"),
                   help="integrator arithmetic (ahrs: f64 or f32)")
    g.add_argument("--sensors", default="full", choices=("ideal", "quantized", "full"),
                   help="ideal: exact increments; quantized: perfect gyro through ADC and board; "
                   "full: plus gyro noise, bias, filter, saturation")
    g.add_argument("--gyro", default=None, choices=tuple(GYRO_PRESETS),
                   help="gyro model preset (docs/simulation.md gives the figures and sources; default "
                   "cg-l53, adxrs150 with --adc ad7927)")
    g.add_argument("--oversample", type=_int_range("--oversample", 1, 16), default=16, metavar="N",
                   help="ADC conversions per axis summed by the board per period")
    g.add_argument("--sample-at", default="mid", choices=("mid", "start"),
                   help="where in each sub-interval the board converts: mid (midpoint rule) or "
                   "start (one rate sample at the start: the naive design)")
    g.add_argument("--calibration", type=_nonneg("--calibration"), default=60.0, metavar="S",
                   help="static zero-rate calibration before the run (s)")
    g.add_argument("--adc", default="auto", choices=("auto", "tlc2543", "ad7927", "ideal"),
                   help="tlc2543: C driver against the device model; ad7927: the UAV thesis's board "
                   "(C AD7927 driver against its model, 0-5 V, a unity-gain follower in front, "
                   "ADXRS150 gyros and ADXL202 accelerometers unless --gyro/--accel say otherwise); "
                   "ideal: vectorized quantizer; auto: tlc2543")
    g.add_argument("--firmware", choices=("none", "s51"), default="none",
                   help="s51: the acquisition side is the real AT89S51 firmware running in s51 "
                   "(a source checkout with sdcc, s51 and socat: run it as python -m toolchain.simulate "
                   "--firmware s51 ...); the motion is then the firmware's own sinusoidal body rates")
    g.add_argument("--link", default="c", choices=("c", "none"),
                   help="c: every sample through the C link sender and receiver; none: direct")
    g.add_argument("--ber", type=_ber, default=0.0, help="bit error rate of the channel simulator")
    g.add_argument("--attempts", type=_int_range("--attempts", 1, 255), default=5,
                   help="link sender attempts per block before giving up")
    _aided_options(p)
    g = p.add_argument_group("accelerometer and magnetometer (read by the host beside the gyros; "
                             "docs/simulation.md)")
    g.add_argument("--accel", default=None, choices=("none", *ACCEL_PRESETS),
                   help="accelerometer preset (default none; adxl202 with --adc ad7927)")
    g.add_argument("--mag", default="none", choices=("none", *MAG_PRESETS), help="magnetometer preset")
    g.add_argument("--field", type=_floats("--field", (3,)), default=None, metavar="F,I,D",
                   help="local geomagnetic field: total intensity (µT), inclination and declination (deg) "
                   "(default 50.6,46.9,-5.1: Nanjing, an assumption)")
    g.add_argument("--gravity", type=_positive("--gravity"), default=None, metavar="M_S2",
                   help="magnitude of gravity (default 9.80665)")
    g.add_argument("--hard-iron", type=_triple("--hard-iron"), default=None, metavar="X,Y,Z",
                   help="magnetometer hard iron: an offset in the body frame (µT)")
    g.add_argument("--soft-iron", type=_floats("--soft-iron", (3, 9)), default=None, metavar="S",
                   help="magnetometer soft iron: 3 diagonal or 9 row-major matrix elements")
    g.add_argument("--disturbance", type=_disturbance, action="append", default=None,
                   metavar="START,END,X,Y,Z[,RAMP][,FRAME]",
                   help="a field (µT) added to the magnetometer's from START to END (s), raised-cosine "
                   "edges of RAMP s, in the body (default) or nav frame; may be repeated")
    g = p.add_argument_group("wavelet denoising of the gyro rates (docs/denoise.md)")
    g.add_argument("--denoise", default="none", choices=("none", "haar", "db2", "db4"),
                   help="denoise the host's gyro rates with this wavelet before the estimator")
    g.add_argument("--denoise-levels", type=_int_range("--denoise-levels", 1, 8), default=None, metavar="L",
                   help="decomposition levels (default: the library's, 4)")
    g.add_argument("--denoise-mode", default=None, choices=("soft", "hard"),
                   help="thresholding (default: the library's, soft)")
    g.add_argument("--denoise-block", type=_int_range("--denoise-block", 8, 4096), default=None, metavar="N",
                   help="window length (default 128; the dropped window edges scale with it)")
    g.add_argument("--denoise-timing", default="aligned", choices=("aligned", "realtime"),
                   help="aligned: post-processing (sample k stays at k); realtime: each attitude judged "
                   "the denoiser's latency later")
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


def _aided_options(p: argparse.ArgumentParser) -> None:
    plan = AidedPlan()
    g = p.add_argument_group("the aided board (nine channels over link v2 into the filter; docs/simulation.md)")
    g.add_argument("--board", default="gyro3", choices=("gyro3", "aided9"),
                   help="gyro3: the paper's AT89S51 gyro board (default); aided9: the AT89S52 board with "
                   "the accelerometer and magnetometer front ends on the same TLC2543, its records over "
                   "link v2 (--link c, --ber) into the filter (sets --estimator ahrs)")
    g.add_argument("--acc-every", type=_int_range("--acc-every", 1, 255), default=plan.acc_every, metavar="N",
                   help=f"aided9: an accelerometer record every N samples (default {plan.acc_every}: the firmware's)")
    g.add_argument("--mag-every", type=_int_range("--mag-every", 1, 255), default=plan.mag_every, metavar="N",
                   help=f"aided9: a magnetometer record every N samples (default {plan.mag_every})")
    g.add_argument("--mag-sr", action="store_true",
                   help="aided9: magnetometer set/reset (the firmware's FW_MAG_SR: bridge offsets cancelled)")
    g.add_argument("--host-config", default=plan.host_config, choices=("nominal", "calibrated"),
                   help="aided9: the host's acc-*/mag-* conversion: calibrated (default: this run's part errors "
                   "undone exactly, a perfect attitude calibrate) or nominal (the parts' typical figures: an "
                   "uncalibrated board)")
    g.add_argument("--accel-frontend", default=plan.accel, choices=tuple(ACCEL_FRONTENDS),
                   help=f"aided9: the analog accelerometer front end (default {plan.accel})")
    g.add_argument("--mag-frontend", default=plan.mag, choices=tuple(MAG_FRONTENDS),
                   help=f"aided9: the AMR magnetometer front end (default {plan.mag})")


def _aided(args: argparse.Namespace) -> dict[str, Any]:
    """The --board options as SimConfig keywords."""
    plan = AidedPlan(acc_every=args.acc_every, mag_every=args.mag_every, mag_sr=args.mag_sr,
                     host_config=args.host_config, accel=args.accel_frontend, mag=args.mag_frontend)
    if args.board == "gyro3":
        if plan != AidedPlan():
            raise ValueError("--acc-every, --mag-every, --mag-sr, --host-config, --accel-frontend and --mag-frontend "
                             "need --board aided9")
        return {}
    if args.accel not in (None, "none") or args.mag != "none":
        raise ValueError("--board aided9 carries its own front ends (--accel-frontend, --mag-frontend): "
                         "drop --accel and --mag")
    if args.firmware != "none" or args.adc == "ad7927" or args.budget:
        raise ValueError("--board aided9 runs the modeled TLC2543 board: drop --firmware, --adc ad7927, --budget")
    if args.precision == "fixed":
        raise ValueError("--board aided9 ends in the filter: --precision f64 or f32, not fixed")
    return {"board_kind": "aided9", "aided": plan, "estimator": "ahrs",
            "ahrs_settings": dict(args.ahrs_setting or ()), "ahrs_init": args.ahrs_init}


def _denoise(args: argparse.Namespace) -> Any:
    """The --denoise options as a Denoise stage (None: off)."""
    if args.denoise == "none":
        if any(v is not None for v in (args.denoise_levels, args.denoise_mode, args.denoise_block)):
            raise ValueError("--denoise-levels/-mode/-block need --denoise WAVELET")
        return None
    from ..denoise import DenoiseConfig
    from ..sim import Denoise

    kw: dict[str, Any] = {"wavelet": args.denoise}
    if args.denoise_levels is not None:
        kw["levels"] = args.denoise_levels
    if args.denoise_mode is not None:
        kw["threshold"] = args.denoise_mode
    if args.denoise_block is not None:
        d = DenoiseConfig()
        n = args.denoise_block
        kw.update(block=n, edge_start=round(d.edge_start * n / d.block), edge_end=round(d.edge_end * n / d.block))
    return Denoise(DenoiseConfig(**kw), timing=args.denoise_timing)


def _magnetometer(args: argparse.Namespace) -> dict[str, Any]:
    from ..sim import Environment, MagDisturbance, mag_preset
    from ..sim.trajectory import EARTH

    kw: dict[str, Any] = {}
    env = EARTH
    if args.field is not None or args.gravity is not None:
        f, i, d = args.field if args.field is not None else (EARTH.field_ut, math.degrees(EARTH.inclination),
                                                             math.degrees(EARTH.declination))
        env = Environment(gravity=args.gravity if args.gravity is not None else EARTH.gravity, field_ut=f,
                          inclination=math.radians(i), declination=math.radians(d))
    kw["environment"] = env
    if args.mag != "none":
        kw["mag"] = mag_preset(args.mag)
    if args.hard_iron is not None:
        kw["hard_iron"] = tuple(args.hard_iron)
    if args.soft_iron is not None:
        v = args.soft_iron
        kw["soft_iron"] = [[v[0], 0, 0], [0, v[1], 0], [0, 0, v[2]]] if len(v) == 3 else \
            [list(v[0:3]), list(v[3:6]), list(v[6:9])]
    if args.disturbance:
        kw["disturbances"] = tuple(MagDisturbance(a, b, f, frame, ramp) for a, b, f, ramp, frame in args.disturbance)
    if args.mag == "none" and ("hard_iron" in kw or "soft_iron" in kw or "disturbances" in kw):
        raise ValueError("--hard-iron, --soft-iron and --disturbance need a magnetometer: give --mag PART")
    return kw


def _estimator(args: argparse.Namespace, has_accel: bool) -> dict[str, Any]:
    """The --estimator options as SimConfig keywords (one-line errors for the CLI)."""
    if args.estimator == "integrator":
        if args.ahrs_setting or args.ahrs_init != "truth":
            raise ValueError("--ahrs-setting and --ahrs-init need --estimator ahrs")
        return {}
    if args.budget:
        raise ValueError("--budget compares the integrator's methods: drop --estimator ahrs")
    if not has_accel:
        raise ValueError("--estimator ahrs needs an accelerometer: give --accel PART (e.g. --accel adis16405)")
    if args.precision == "fixed":
        raise ValueError("--estimator ahrs runs in --precision f64 or f32, not fixed")
    return {"estimator": "ahrs", "ahrs_settings": dict(args.ahrs_setting or ()), "ahrs_init": args.ahrs_init}


def build_config(args: argparse.Namespace) -> Any:
    from ..sim import (
        AdcModel,
        Board,
        Conditioning,
        SimConfig,
        accel_preset,
        gyro_preset,
        make_trajectory,
    )
    from ..sim.adc import AdcBackend

    given = getattr(args, "trajectory", None)
    trajectory = given or ("csv" if args.trajectory_file else "paper")
    duration: float | None = getattr(args, "duration", None)
    thesis_board = args.adc == "ad7927"
    gyro_name = args.gyro or ("adxrs150" if thesis_board else "cg-l53")
    aided = _aided(args)
    if args.period is None:
        args.period = aided["aided"].period_s if aided else PAPER_PERIOD_S
    if args.firmware != "none":
        from ..sim import source

        if given or args.trajectory_file:
            raise ValueError(f"--firmware {args.firmware} uses the firmware's own motion: drop --trajectory")
        # a source registered by the tooling layer (toolchain/firmware.py): its own motion
        traj: Any = source(args.firmware).trajectory(args.period, gyro_preset(gyro_name), Conditioning(),
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
    elif trajectory in ("paper", "paper-translation"):
        kw: dict[str, Any] = {"amplitude": [math.radians(v) for v in args.amplitude],
                              "frequency": list(args.frequency), "phase": [math.radians(v) for v in args.phase]}
        if trajectory == "paper-translation":
            kw.update(translation=list(args.translation), translation_frequency=list(args.translation_frequency))
        traj = make_trajectory("paper-translation" if trajectory == "paper-translation" else "paper", **kw)
    elif trajectory == "coning":
        traj = make_trajectory("coning", half_angle=math.radians(args.cone_angle),
                               frequency=args.cone_frequency)
    elif trajectory == "constant-rate":
        traj = make_trajectory("constant-rate", rate=[math.radians(v) for v in args.rate])
    elif trajectory == "turntable":
        traj = make_trajectory("turntable", rate=[0.0, 0.0, math.radians(args.turntable_rate)])
    elif trajectory == "level-turn":
        traj = make_trajectory("level-turn", peak_rate=math.radians(args.turn_rate), turns=args.turns,
                               rest=args.rest)
    else:
        traj = make_trajectory("static")
    if duration is None:
        duration = getattr(traj, "default_duration", None) or DEFAULT_DURATION_S
    adc: AdcBackend = "tlc2543" if args.adc == "auto" else args.adc
    accel_name = args.accel if args.accel is not None else ("adxl202" if thesis_board else "none")
    extra: dict[str, Any] = _magnetometer(args)
    if accel_name != "none":
        extra["accel"] = accel_preset(accel_name)
    extra.update(aided or _estimator(args, has_accel=accel_name != "none"))
    return SimConfig(trajectory=traj, duration=duration, period=args.period,
                     method=args.method, precision=args.precision, sensors=args.sensors,
                     gyro=gyro_preset(gyro_name), adc=AdcModel(backend=adc),
                     conditioning=Conditioning(follower=thesis_board),
                     board=Board(oversample=args.oversample, sample_at=args.sample_at), calibration_s=args.calibration,
                     link=args.link, ber=args.ber, link_attempts=args.attempts, seed=args.seed,
                     firmware=None if args.firmware == "none" else args.firmware,
                     denoise=_denoise(args), **extra)


def run(args: argparse.Namespace) -> int:
    from ..errors import AttitudeError
    from . import EXIT_OS, EXIT_USAGE, fail, os_error_line

    try:
        return _run(args)
    except OSError as exc:  # the output location, a full disk (ResultsIncomplete says which files)
        return fail("attitude simulate", os_error_line(exc), EXIT_OS)
    except (AttitudeError, ValueError, TypeError) as exc:
        return fail("attitude simulate", str(exc), EXIT_USAGE)


def _run(args: argparse.Namespace) -> int:
    from .._io import check_output_dir, write_results
    from ..sim import format_budget, format_table, plot_budget, run_budget, simulate, write_run
    from ..sim.chain import WALL_DECIMALS
    from ..sim.report import to_jsonable

    cfg = build_config(args)
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    name = f"{stamp}-{'budget' if args.budget else cfg.method if cfg.estimator == 'integrator' else 'ahrs'}-{cfg.trajectory.name}-s{cfg.seed}"
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
            d["elapsed_s"] = round(time.perf_counter() - t0, WALL_DECIMALS)
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
