"""The simulator's options: one declarative table (:data:`OPTIONS`).

Each :class:`Option` says what one setting of a simulated run is: its name
(the key of :meth:`SimConfig.from_dict <attitude_c.sim.chain.SimConfig.from_dict>`,
of a sweep spec, and ``--name-with-dashes`` on the command line), its type
(the shared validator, :mod:`attitude_c._options`, or its choices), unit,
default, help and group. ``attitude simulate`` generates its parser from this
table (:func:`attitude_c.cli.simulate.register`); sweeps
(:mod:`attitude_c.sim.sweeps`) and the display (:mod:`attitude_c.view.simsource`)
build configurations from dicts with :func:`parse` and ``SimConfig.from_dict``.
An option added here is on the command line, sweepable and in the display.

:func:`parse` turns a dict of option values -- as text (``"30,20,25"``) or as
Python/TOML values (``[30, 20, 25]``) -- into typed values, each checked
alone (ValueError/TypeError naming the option); what the options mean
together is :mod:`attitude_c.sim.configure`'s.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Literal, get_args

from .._options import (
    OptionError,
    OptionTypeError,
    floats,
    integer,
    nonneg,
    positive,
    probability,
    real,
    triple,
)
from ..core import METHODS, PRECISIONS
from .accelmag import ACCEL_PRESETS, MAG_PRESETS
from .aided import AidedPlan, BoardKind, HostConfig
from .denoising import DENOISE_TIMINGS
from .estimator import ESTIMATORS
from .frontend import ACCEL_FRONTENDS, MAG_FRONTENDS
from .gnss_model import GNSS_PRESETS
from .sensors import GYRO_PRESETS
from .trajectory import TRAJECTORIES

__all__ = ["GROUPS", "OPTIONS", "Option", "add_arguments", "by_name", "defaults", "from_namespace", "parse", "parse_value"]

#: Simulated time when duration is not given (and the trajectory is not a file).
DEFAULT_DURATION_S = 60.0
#: The paper's sample period (s): the default period of the gyro board.
PAPER_PERIOD_S = 0.08

AhrsInit = Literal["truth", "align"]
SensorMode = Literal["ideal", "quantized", "full"]
SampleAt = Literal["mid", "start"]
AdcChoice = Literal["auto", "tlc2543", "ad7927", "ideal"]
Firmware = Literal["none", "s51"]
LinkChoice = Literal["c", "none"]
Wavelet = Literal["none", "haar", "db2", "db4"]
DenoiseMode = Literal["soft", "hard"]

Kind = Literal["value", "switch", "repeat"]

SCENARIO = "scenario"
SYSTEM = "system"
AIDED = "the aided board (nine channels over link v2 into the filter; docs/simulation.md)"
ACCELMAG = "accelerometer and magnetometer (read by the host beside the gyros; docs/simulation.md)"
DENOISE = "wavelet denoising of the gyro rates (docs/denoise.md)"
GNSS = "GNSS receiver (a fix log beside the run's files; docs/simulation.md)"
RUN = "run"
#: The groups, in the order ``attitude simulate --help`` shows them.
GROUPS = (SCENARIO, SYSTEM, AIDED, ACCELMAG, DENOISE, GNSS, RUN)


@dataclass(frozen=True)
class Option:
    """One setting of a simulated run."""

    name: str                          #: ``cone_angle``: dict key, spec name; ``--cone-angle`` on the command line
    help: str
    group: str                         #: one of :data:`GROUPS`
    default: Any = None                #: as the command line writes it (text goes through ``type``); None: unset
    type: Any = None                   #: converter: ``type(text)`` and ``type.value(x)`` (attitude_c._options)
    choices: tuple[str, ...] | None = None  #: the allowed values (from a Literal or a preset table)
    unit: str | None = None            #: the value's unit as a plot axis writes it
    metavar: str | None = None
    kind: Kind = "value"               #: "switch": true/false; "repeat": may be given several times (a list)
    #: the default is worked out from other options (the help says how): the command line shows none
    derived_default: bool = False

    @property
    def flag(self) -> str:
        """The option on the command line."""
        return "--" + self.name.replace("_", "-")

    def item(self, x: Any) -> Any:
        """One value (one occurrence of a repeatable option), checked alone."""
        if self.choices is not None:
            if not isinstance(x, str):
                raise OptionTypeError(f"{self.flag}: expected one of {', '.join(self.choices)}, got {x!r}")
            if x not in self.choices:
                raise OptionError(f"{self.flag}: invalid choice: {x!r} (choose from {', '.join(self.choices)})")
            return x
        if self.type is None:
            if not isinstance(x, str):
                raise OptionTypeError(f"{self.flag}: expected a text, got {x!r}")
            return x
        return self.type.value(x) if hasattr(self.type, "value") else _text_value(self.flag, self.type, x)


def _text(x: Any) -> str:
    if isinstance(x, (list, tuple)):
        return ",".join(_text(v) for v in x)
    return repr(x) if isinstance(x, float) else str(x)


def _text_value(flag: str, conv: Callable[[str], Any], x: Any) -> Any:
    """A text converter given a value: a list is its comma-separated form."""
    if isinstance(x, (list, tuple)):
        x = _text(x)
    if not isinstance(x, str):
        raise OptionTypeError(f"{flag}: expected a text or a list, got {x!r}")
    return conv(x)


def _disturbance(text: str) -> tuple[float, float, tuple[float, float, float], float, str]:
    """START,END,X,Y,Z[,RAMP[,FRAME]] → (start, end, field, ramp, frame)."""
    parts = [p for p in text.replace(" ", "").split(",") if p != ""]
    frame = "body"
    if parts and parts[-1] in ("body", "nav"):
        frame = parts.pop()
    if len(parts) not in (5, 6):
        raise OptionError(f"--disturbance: give START,END,X,Y,Z[,RAMP][,body|nav] (s, µT), got {text!r}")
    v = floats("--disturbance", (5, 6))(",".join(parts))
    return v[0], v[1], (v[2], v[3], v[4]), v[5] if len(v) == 6 else 0.0, frame


class _AhrsSetting:
    """A filter setting: ``NAME=VALUE`` (:func:`attitude_c.ahrs_filter.parse_setting`),
    or as a value the pair ``[NAME, VALUE]``."""

    __name__ = "setting"

    def __call__(self, text: str) -> tuple[str, Any]:
        from ..ahrs_filter import parse_setting

        return parse_setting(text, "--ahrs-setting")

    def value(self, x: Any) -> tuple[str, Any]:
        if isinstance(x, (list, tuple)) and len(x) == 2 and isinstance(x[0], str):
            x = f"{x[0]}={_text(x[1])}"
        if not isinstance(x, str):
            raise OptionTypeError(f"--ahrs-setting: give NAME=VALUE or [NAME, VALUE], got {x!r}")
        return self(x)


def _choices(t: Any) -> tuple[str, ...]:
    return tuple(get_args(t))


_PLAN = AidedPlan()

OPTIONS: tuple[Option, ...] = (
    # --- scenario ---------------------------------------------------------------------------
    Option("trajectory", "reference motion (default: paper, or csv when --trajectory-file is given; "
           "csv needs --trajectory-file)", SCENARIO, choices=TRAJECTORIES, derived_default=True),
    Option("trajectory_file", "CSV with columns time,yaw,pitch,roll (rad; *_deg for degrees) or "
           "time,q0,q1,q2,q3; implies --trajectory csv", SCENARIO, metavar="CSV"),
    Option("duration", f"simulated time (s) (default: {DEFAULT_DURATION_S:g}, or the span of the "
           "--trajectory-file, which it may not exceed)", SCENARIO, type=positive("--duration"), unit="s",
           metavar="S", derived_default=True),
    Option("period", f"gyro sample period: one angle increment per period (s) (default: the paper's "
           f"{PAPER_PERIOD_S:g}; with --board aided9 the aided firmware's {_PLAN.period_s:g})", SCENARIO,
           type=positive("--period"), unit="s", metavar="S"),
    Option("amplitude", "paper trajectory: sinusoid amplitudes (deg)", SCENARIO, "30,20,25",
           triple("--amplitude"), unit="°", metavar="Y,P,R"),
    Option("frequency", "paper trajectory: frequencies (Hz)", SCENARIO, "0.20,0.25,0.30", triple("--frequency"),
           unit="Hz", metavar="Y,P,R"),
    Option("phase", "paper trajectory: phases (deg)", SCENARIO, "0,30,60", triple("--phase"), unit="°",
           metavar="Y,P,R"),
    Option("cone_angle", "coning trajectory: half-angle (deg)", SCENARIO, 20.0, nonneg("--cone-angle"), unit="°",
           metavar="DEG"),
    Option("cone_frequency", "coning trajectory: coning frequency (Hz)", SCENARIO, 0.5,
           nonneg("--cone-frequency"), unit="Hz", metavar="HZ"),
    Option("rate", "constant-rate trajectory: body rate (deg/s; write --rate=-10,5,0 when it starts with a "
           "minus)", SCENARIO, "10,-5,20", triple("--rate"), unit="°/s", metavar="X,Y,Z"),
    Option("translation", "paper-translation trajectory: sinusoidal translation amplitudes (m, ENU)", SCENARIO,
           "5,5,1", triple("--translation"), unit="m", metavar="E,N,U"),
    Option("translation_frequency", "paper-translation trajectory: translation frequencies (Hz)", SCENARIO,
           "0.15,0.10,0.25", triple("--translation-frequency"), unit="Hz", metavar="E,N,U"),
    Option("turntable_rate", "turntable trajectory: rate about body z (deg/s; the FPGA+DSP paper's 5)", SCENARIO,
           5.0, real("--turntable-rate"), unit="°/s", metavar="DEG_S"),
    Option("turn_rate", "level-turn trajectory: peak turn rate (deg/s)", SCENARIO, 10.0, positive("--turn-rate"),
           unit="°/s", metavar="DEG_S"),
    Option("turns", "level-turn and car-roundabout trajectories: turns (negative: clockwise)", SCENARIO, 1.0,
           real("--turns"), metavar="N"),
    Option("rest", "level-turn trajectory: rest before and after the turn (s)", SCENARIO, 10.0, nonneg("--rest"),
           unit="s", metavar="S"),
    Option("speed", "vehicle trajectories: speed (m/s) (default: fixed-wing, fixed-wing-turn 60; car 15; "
           "car-brake 20; car-roundabout 8)", SCENARIO, type=positive("--speed"), unit="m/s", metavar="M_S",
           derived_default=True),
    Option("bank", "fixed-wing, fixed-wing-turn: bank of the (first) coordinated turn (deg; tan(bank) = V "
           "omega / g) (default 30)", SCENARIO, type=real("--bank", gt=0, lt=80), unit="°", metavar="DEG",
           derived_default=True),
    Option("turn_time", "fixed-wing-turn: time held at full bank (s) (default 60)", SCENARIO,
           type=positive("--turn-time"), unit="s", metavar="S", derived_default=True),
    Option("brake_g", "car, car-brake: braking deceleration (g = 9.80665 m/s²) (default 0.5)", SCENARIO,
           type=real("--brake-g", gt=0, le=1.5), unit="g", metavar="G", derived_default=True),
    Option("radius", "car, car-roundabout: radius of the roundabout (m) (default 20)", SCENARIO,
           type=positive("--radius"), unit="m", metavar="M", derived_default=True),
    # --- system -----------------------------------------------------------------------------
    Option("estimator", "integrator: the paper's strapdown integrator of the gyros (--method, --precision); "
           "ahrs: the attitude filter (docs/ahrs.md) fed the gyro rates, the accelerometer (needs --accel) and "
           "the magnetometer (--mag; six-axis without)", SYSTEM, "integrator", choices=ESTIMATORS),
    Option("ahrs_setting", "a setting of the attitude filter (attitude_c.ahrs keywords, SI units: rad, s; "
           "method by name); may be repeated; declination and gravity default to the simulated environment's",
           SYSTEM, type=_AhrsSetting(), metavar="NAME=VALUE", kind="repeat"),
    Option("ahrs_init", "ahrs start: truth (the true initial attitude, as the integrator) or align (the filter "
           "aligns itself on its first sample: tilt from the accelerometer, heading from the magnetometer, or 0 "
           "without one)", SYSTEM, "truth", choices=_choices(AhrsInit)),
    Option("method", "integrator method", SYSTEM, "rv3", choices=METHODS),
    Option("precision", "integrator arithmetic (ahrs: f64 or f32)", SYSTEM, "f64", choices=PRECISIONS),
    Option("sensors", "ideal: exact increments; quantized: perfect gyro through ADC and board; full: plus gyro "
           "noise, bias, filter, saturation", SYSTEM, "full", choices=_choices(SensorMode)),
    Option("gyro", "gyro model preset (docs/simulation.md gives the figures and sources; default cg-l53, "
           "adxrs150 with --adc ad7927)", SYSTEM, choices=tuple(GYRO_PRESETS)),
    Option("oversample", "ADC conversions per axis summed by the board per period", SYSTEM, 16,
           integer("--oversample", 1, 16), metavar="N"),
    Option("sample_at", "where in each sub-interval the board converts: mid (midpoint rule) or start (one rate "
           "sample at the start: the naive design)", SYSTEM, "mid", choices=_choices(SampleAt)),
    Option("calibration", "static zero-rate calibration before the run (s)", SYSTEM, 60.0,
           nonneg("--calibration"), unit="s", metavar="S"),
    Option("adc", "tlc2543: C driver against the device model; ad7927: the UAV thesis's board (C AD7927 driver "
           "against its model, 0-5 V, a unity-gain follower in front, ADXRS150 gyros and ADXL202 accelerometers "
           "unless --gyro/--accel say otherwise); ideal: vectorized quantizer; auto: tlc2543", SYSTEM, "auto",
           choices=_choices(AdcChoice)),
    Option("firmware", "s51: the acquisition side is the real AT89S51 firmware running in s51 (a source checkout "
           "with sdcc, s51 and socat: run it as python -m toolchain.simulate --firmware s51 ...); the motion is "
           "then the firmware's own sinusoidal body rates", SYSTEM, "none", choices=_choices(Firmware)),
    Option("link", "c: every sample through the C link sender and receiver; none: direct", SYSTEM, "c",
           choices=_choices(LinkChoice)),
    Option("ber", "bit error rate of the channel simulator", SYSTEM, 0.0, probability("BER", below=0.5)),
    Option("attempts", "link sender attempts per block before giving up", SYSTEM, 5, integer("--attempts", 1, 255)),
    # --- the aided board --------------------------------------------------------------------
    Option("board", "gyro3: the paper's AT89S51 gyro board (default); aided9: the AT89S52 board with the "
           "accelerometer and magnetometer front ends on the same TLC2543, its records over link v2 (--link c, "
           "--ber) into the filter (sets --estimator ahrs)", AIDED, "gyro3", choices=_choices(BoardKind)),
    Option("acc_every", f"aided9: an accelerometer record every N samples (default {_PLAN.acc_every}: the "
           "firmware's)", AIDED, _PLAN.acc_every, integer("--acc-every", 1, 255), metavar="N"),
    Option("mag_every", f"aided9: a magnetometer record every N samples (default {_PLAN.mag_every})", AIDED,
           _PLAN.mag_every, integer("--mag-every", 1, 255), metavar="N"),
    Option("mag_sr", "aided9: magnetometer set/reset (the firmware's FW_MAG_SR: bridge offsets cancelled)", AIDED,
           False, kind="switch"),
    Option("host_config", "aided9: the host's acc-*/mag-* conversion: calibrated (default: this run's part "
           "errors undone exactly, a perfect attitude calibrate) or nominal (the parts' typical figures: an "
           "uncalibrated board)", AIDED, _PLAN.host_config, choices=_choices(HostConfig)),
    Option("accel_frontend", f"aided9: the analog accelerometer front end (default {_PLAN.accel})", AIDED,
           _PLAN.accel, choices=tuple(ACCEL_FRONTENDS)),
    Option("mag_frontend", f"aided9: the AMR magnetometer front end (default {_PLAN.mag})", AIDED, _PLAN.mag,
           choices=tuple(MAG_FRONTENDS)),
    # --- accelerometer and magnetometer -----------------------------------------------------
    Option("accel", "accelerometer preset (default none; adxl202 with --adc ad7927)", ACCELMAG,
           choices=("none", *ACCEL_PRESETS)),
    Option("mag", "magnetometer preset", ACCELMAG, "none", choices=("none", *MAG_PRESETS)),
    Option("field", "local geomagnetic field: total intensity (µT), inclination and declination (deg) "
           "(default 50.6,46.9,-5.1: Nanjing, an assumption)", ACCELMAG, type=floats("--field", (3,)),
           metavar="F,I,D"),
    Option("gravity", "magnitude of gravity (default 9.80665)", ACCELMAG, type=positive("--gravity"),
           unit="m/s²", metavar="M_S2"),
    Option("hard_iron", "magnetometer hard iron: an offset in the body frame (µT)", ACCELMAG,
           type=triple("--hard-iron"), unit="µT", metavar="X,Y,Z"),
    Option("soft_iron", "magnetometer soft iron: 3 diagonal or 9 row-major matrix elements", ACCELMAG,
           type=floats("--soft-iron", (3, 9)), metavar="S"),
    Option("disturbance", "a field (µT) added to the magnetometer's from START to END (s), raised-cosine edges "
           "of RAMP s, in the body (default) or nav frame; may be repeated", ACCELMAG, type=_disturbance,
           metavar="START,END,X,Y,Z[,RAMP][,FRAME]", kind="repeat"),
    # --- wavelet denoising ------------------------------------------------------------------
    Option("denoise", "denoise the host's gyro rates with this wavelet before the estimator", DENOISE, "none",
           choices=_choices(Wavelet)),
    Option("denoise_levels", "decomposition levels (default: the library's, 4)", DENOISE,
           type=integer("--denoise-levels", 1, 8), metavar="L"),
    Option("denoise_mode", "thresholding (default: the library's, soft)", DENOISE, choices=_choices(DenoiseMode)),
    Option("denoise_block", "window length (default 128; the dropped window edges scale with it)", DENOISE,
           type=integer("--denoise-block", 8, 4096), metavar="N"),
    Option("denoise_timing", "aligned: post-processing (sample k stays at k); realtime: each attitude judged the "
           "denoiser's latency later", DENOISE, "aligned", choices=DENOISE_TIMINGS),
    # --- GNSS receiver -----------------------------------------------------------------------
    Option("gnss", "GNSS receiver preset (default none; neo-m8n when --gnss-log is given)", GNSS,
           choices=("none", *GNSS_PRESETS)),
    Option("gnss_log", "write the receiver's fixes as a log beside the run's files: NAME.nmea (NMEA 0183 RMC, VTG, "
           "GGA, GSA) or NAME.ubx (UBX NAV-PVT); a relative name goes into the output directory", GNSS,
           metavar="FILE"),
    Option("gnss_rate", "fix rate (Hz, 1..10) (default: the preset's)", GNSS, type=real("--gnss-rate", ge=1, le=10),
           unit="Hz", metavar="HZ"),
    Option("gnss_latency", "delay from a fix's measurement to its delivery (s) (default: the preset's)", GNSS,
           type=nonneg("--gnss-latency"), unit="s", metavar="S"),
    Option("gnss_outage", "no fix from START to END (s); may be repeated", GNSS, type=floats("--gnss-outage", (2,)),
           metavar="START,END", kind="repeat"),
    Option("gnss_quality", "a degraded fix from START to END (s): fix type (2 or 3), satellites, HDOP, PDOP; may "
           "be repeated", GNSS, type=floats("--gnss-quality", (6,)), metavar="START,END,FIX,NSAT,HDOP,PDOP",
           kind="repeat"),
    Option("gnss_bad_fix", "a velocity jump the receiver does not flag from START to END (s): DVE,DVN,DVU (m/s); "
           "may be repeated", GNSS, type=floats("--gnss-bad-fix", (5,)), metavar="START,END,DVE,DVN,DVU",
           kind="repeat"),
    Option("gnss_origin", "latitude, longitude (deg) and ellipsoidal height (m) of the ENU origin (default "
           "32.06,118.80,10: Nanjing, an assumption)", GNSS, type=floats("--gnss-origin", (3,)), metavar="LAT,LON,H"),
    # --- run --------------------------------------------------------------------------------
    Option("seed", "random seed (noise, bias, channel errors)", RUN, 0, integer("--seed", 0, 2**63 - 1)),
)


_INDEX: list[Any] = [None, {}]


def by_name() -> dict[str, Option]:
    """The table by option name (read from :data:`OPTIONS` as it is now)."""
    if _INDEX[0] is not OPTIONS:
        _INDEX[:] = [OPTIONS, {o.name: o for o in OPTIONS}]
    return dict(_INDEX[1])


def parse_value(name: str, value: Any) -> Any:
    """One option's value, typed and checked alone: text as on the command line, or a
    Python/TOML value (a number, a list; a repeatable option: one occurrence, or a list
    of them; a switch: a bool). ValueError/TypeError naming the option."""
    o = by_name().get(name)
    if o is None:
        raise OptionError(f"{name}: not an option of the simulator")
    if o.kind == "switch":
        if not isinstance(value, bool):
            raise OptionTypeError(f"{o.flag} is a switch: give true or false, got {value!r}")
        return value
    if o.kind == "repeat":
        many = isinstance(value, (list, tuple)) and all(isinstance(x, (str, list, tuple)) for x in value)
        return [o.item(x) for x in (value if many else [value])]
    return o.item(value)


def defaults() -> dict[str, Any]:
    """Every option's default, typed (None: unset, worked out from the others)."""
    return {o.name: parse_value(o.name, o.default) if isinstance(o.default, str) and o.type is not None
            else o.default for o in OPTIONS}


def parse(values: Mapping[str, Any]) -> dict[str, Any]:
    """Every option: those in ``values`` typed and checked (:func:`parse_value`), the
    others at their defaults. ``values`` keys are option names (``cone_angle``)."""
    out = defaults()
    for k, v in values.items():
        out[k] = parse_value(k, v)
    return out


def add_arguments(parser: argparse.ArgumentParser) -> dict[str, Any]:
    """Add every option of the table to ``parser`` (``--cone-angle``, one argument
    group per :data:`GROUPS` title, values checked by the table's types); returns the
    groups by title, so that a command adds its own options to them. A parsed
    namespace gives the table's typed values (:func:`from_namespace`)."""
    groups = {title: parser.add_argument_group(title) for title in GROUPS}
    for o in OPTIONS:
        g = groups[o.group]
        if o.kind == "switch":
            g.add_argument(o.flag, action="store_true", help=o.help)
            continue
        kw: dict[str, Any] = {"default": argparse.SUPPRESS if o.derived_default else o.default, "help": o.help}
        if o.kind == "repeat":
            kw["action"] = "append"
        if o.type is not None:
            kw["type"] = o.type
        if o.choices is not None:
            kw["choices"] = o.choices
        if o.metavar is not None:
            kw["metavar"] = o.metavar
        g.add_argument(o.flag, **kw)
    return groups


def from_namespace(args: argparse.Namespace) -> dict[str, Any]:
    """The table's options of a namespace parsed by a parser :func:`add_arguments`
    made: typed, as :func:`parse` gives them (an option whose default is worked out
    from the others: None when not given)."""
    return {o.name: getattr(args, o.name, None) for o in OPTIONS}
