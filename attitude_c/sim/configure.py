"""The simulator's options (:mod:`.options`) as a run's configuration.

:func:`keywords` is what :meth:`SimConfig.from_dict
<attitude_c.sim.chain.SimConfig.from_dict>` builds the configuration with:
each option typed and checked alone (:func:`.options.parse`), then what the
options mean together -- the trajectory they describe, the presets they
name, the stages they switch on -- with a ValueError naming the options
that do not go together.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from .accelmag import MagDisturbance, accel_preset, mag_preset
from .adc import AdcBackend, AdcModel
from .aided import AidedPlan
from .board import Board
from .conditioning import Conditioning
from .denoising import Denoise
from .options import DEFAULT_DURATION_S, PAPER_PERIOD_S, parse
from .sensors import gyro_preset
from .sources import source
from .catalog import make_trajectory
from .trajectory import EARTH, Environment

__all__ = ["build", "keywords"]


def keywords(values: Mapping[str, Any]) -> dict[str, Any]:
    """The keywords of :class:`~attitude_c.sim.chain.SimConfig` for a dict of option
    values (names as in :data:`.options.OPTIONS`; the others at their defaults)."""
    return build(parse(values))


def build(o: Mapping[str, Any]) -> dict[str, Any]:
    """:func:`keywords` for every option already typed and checked alone
    (:func:`.options.parse`, or a command line parsed with the table's types)."""
    thesis_board = o["adc"] == "ad7927"
    gyro_name = o["gyro"] or ("adxrs150" if thesis_board else "cg-l53")
    aided = _aided(o)
    period = o["period"] if o["period"] is not None else aided["aided"].period_s if aided else PAPER_PERIOD_S
    traj, duration = _trajectory(o, period, gyro_name)
    adc: AdcBackend = "tlc2543" if o["adc"] == "auto" else o["adc"]
    accel_name = o["accel"] if o["accel"] is not None else ("adxl202" if thesis_board else "none")
    extra: dict[str, Any] = _magnetometer(o)
    if accel_name != "none":
        extra["accel"] = accel_preset(accel_name)
    extra.update(aided or _estimator(o, has_accel=accel_name != "none"))
    return dict(trajectory=traj, duration=duration, period=period, method=o["method"], precision=o["precision"],
                sensors=o["sensors"], gyro=gyro_preset(gyro_name), adc=AdcModel(backend=adc),
                conditioning=Conditioning(follower=thesis_board),
                board=Board(oversample=o["oversample"], sample_at=o["sample_at"]), calibration_s=o["calibration"],
                link=o["link"], ber=o["ber"], link_attempts=o["attempts"], seed=o["seed"],
                firmware=None if o["firmware"] == "none" else o["firmware"], denoise=_denoise(o), **_gnss(o),
                **extra)


def _trajectory(o: Mapping[str, Any], period: float, gyro_name: str) -> tuple[Any, float]:
    """The reference motion the options describe, and the simulated time."""
    given, path = o["trajectory"], o["trajectory_file"]
    kind: Any = given or ("csv" if path else "paper")  # one of TRAJECTORIES (the table's choices)
    duration: float | None = o["duration"]
    if o["firmware"] != "none":
        if given or path:
            raise ValueError(f"--firmware {o['firmware']} uses the firmware's own motion: drop --trajectory")
        # a source registered by the tooling layer (toolchain/firmware.py): its own motion
        traj: Any = source(o["firmware"]).trajectory(period, gyro_preset(gyro_name), Conditioning(),
                                                     duration or DEFAULT_DURATION_S)
    elif kind == "csv":
        traj = _csv_trajectory(path, duration)
        duration = traj.span if duration is None else duration  # the whole file, not a minute of it held still
    elif path:
        raise ValueError("--trajectory-file is only used with --trajectory csv")
    else:
        traj = make_trajectory(kind, **_shape(kind, o))
    if duration is None:
        duration = getattr(traj, "default_duration", None) or DEFAULT_DURATION_S
    return traj, duration


def _csv_trajectory(path: str | None, duration: float | None) -> Any:
    if not path:
        raise ValueError("--trajectory csv needs --trajectory-file CSV")
    traj: Any = make_trajectory("csv", path=path)  # a CsvTrajectory: span, t_start, t_end
    if duration is not None and duration > traj.span * (1 + 1e-9):
        raise ValueError(f"--duration {duration:g} s is longer than the trajectory file {path} ({traj.span:g} s, "
                         f"t = {traj.t_start:g} .. {traj.t_end:g} s): give at most {traj.span:g} s, or leave "
                         "--duration out to run the whole file")
    return traj


def _shape(kind: str, o: Mapping[str, Any]) -> dict[str, Any]:
    """make_trajectory's keywords for a trajectory of ``kind`` (angles in rad)."""
    if kind in _VEHICLE_OPTIONS:
        return _vehicle(kind, o)
    given = [n for n in _VEHICLE_KEYS if o[n] is not None]
    if given:
        raise ValueError(f"--{given[0].replace('_', '-')} is an option of the vehicle trajectories "
                         f"({', '.join(_VEHICLE_OPTIONS)})")
    if kind in ("paper", "paper-translation"):
        kw: dict[str, Any] = {"amplitude": [math.radians(v) for v in o["amplitude"]],
                              "frequency": list(o["frequency"]), "phase": [math.radians(v) for v in o["phase"]]}
        if kind == "paper-translation":
            kw.update(translation=list(o["translation"]), translation_frequency=list(o["translation_frequency"]))
        return kw
    if kind == "coning":
        return {"half_angle": math.radians(o["cone_angle"]), "frequency": o["cone_frequency"]}
    if kind == "constant-rate":
        return {"rate": [math.radians(v) for v in o["rate"]]}
    if kind == "turntable":
        return {"rate": [0.0, 0.0, math.radians(o["turntable_rate"])]}
    if kind == "level-turn":
        return {"peak_rate": math.radians(o["turn_rate"]), "turns": o["turns"], "rest": o["rest"]}
    return {}


#: The options each vehicle trajectory takes (the others do not apply to it).
_VEHICLE_OPTIONS = {"fixed-wing": ("speed", "bank"), "fixed-wing-turn": ("speed", "bank", "turn_time"),
                    "car": ("speed", "radius", "brake_g"), "car-brake": ("speed", "brake_g"),
                    "car-roundabout": ("speed", "radius", "turns")}
_VEHICLE_KEYS = ("speed", "bank", "turn_time", "brake_g", "radius")


def _vehicle(kind: str, o: Mapping[str, Any]) -> dict[str, Any]:
    """make_trajectory's keywords for a vehicle: the options given, and the environment's g."""
    allowed = _VEHICLE_OPTIONS[kind]
    wrong = [n for n in _VEHICLE_KEYS if o[n] is not None and n not in allowed]
    if wrong:
        raise ValueError(f"--{wrong[0].replace('_', '-')} does not apply to --trajectory {kind} (it takes "
                         f"{', '.join('--' + n.replace('_', '-') for n in allowed)})")
    kw = {n: o[n] for n in allowed if n != "turns" and o[n] is not None}
    if kind == "car-roundabout":
        kw["turns"] = o["turns"]
    if o["gravity"] is not None:
        kw["gravity"] = o["gravity"]
    return kw


def _gnss(o: Mapping[str, Any]) -> dict[str, Any]:
    """The GNSS options as SimConfig keywords ({}: no receiver)."""
    from .gnss_log import log_format
    from .gnss_model import BadFix, GnssReceiver, Quality, gnss_preset

    name = o["gnss"] or ("neo-m8n" if o["gnss_log"] else "none")
    extras = [k for k in ("gnss_rate", "gnss_latency", "gnss_outage", "gnss_quality", "gnss_bad_fix", "gnss_origin")
              if o[k]]
    if name == "none":
        if extras or o["gnss_log"]:
            raise ValueError(f"--{extras[0].replace('_', '-') if extras else 'gnss-log'} needs a GNSS receiver: "
                             "give --gnss PRESET")
        return {}
    model = gnss_preset(name)
    if o["gnss_log"]:
        log_format(o["gnss_log"])  # a wrong name fails before the run
    if o["gnss_rate"] is not None or o["gnss_latency"] is not None:
        model = replace(model, rate_hz=o["gnss_rate"] or model.rate_hz,
                        latency_s=model.latency_s if o["gnss_latency"] is None else o["gnss_latency"])
    kw: dict[str, Any] = {"model": model, "outages": tuple(tuple(w) for w in o["gnss_outage"] or ()),
                          "quality": tuple(Quality(a, b, int(f), int(n), h, p)
                                           for a, b, f, n, h, p in o["gnss_quality"] or ()),
                          "bad_fixes": tuple(BadFix(a, b, (e, n, u)) for a, b, e, n, u in o["gnss_bad_fix"] or ())}
    if o["gnss_origin"] is not None:
        kw["origin"] = tuple(o["gnss_origin"])
    return {"gnss": GnssReceiver(**kw), "gnss_log": o["gnss_log"]}


def _settings(o: Mapping[str, Any]) -> dict[str, Any]:
    return {"ahrs_settings": dict(o["ahrs_setting"] or ()), "ahrs_init": o["ahrs_init"]}


def _aided(o: Mapping[str, Any]) -> dict[str, Any]:
    """The aided board's options as SimConfig keywords ({}: the gyro board)."""
    plan = AidedPlan(acc_every=o["acc_every"], mag_every=o["mag_every"], mag_sr=o["mag_sr"],
                     host_config=o["host_config"], accel=o["accel_frontend"], mag=o["mag_frontend"])
    if o["board"] == "gyro3":
        if plan != AidedPlan():
            raise ValueError("--acc-every, --mag-every, --mag-sr, --host-config, --accel-frontend and --mag-frontend "
                             "need --board aided9")
        return {}
    if o["accel"] not in (None, "none") or o["mag"] != "none":
        raise ValueError("--board aided9 carries its own front ends (--accel-frontend, --mag-frontend): "
                         "drop --accel and --mag")
    if o["firmware"] != "none" or o["adc"] == "ad7927":
        raise ValueError("--board aided9 runs the modeled TLC2543 board: drop --firmware, --adc ad7927, --budget")
    if o["precision"] == "fixed":
        raise ValueError("--board aided9 ends in the filter: --precision f64 or f32, not fixed")
    return {"board_kind": "aided9", "aided": plan, "estimator": "ahrs", **_settings(o)}


def _denoise(o: Mapping[str, Any]) -> Denoise | None:
    """The denoising options as a Denoise stage (None: off)."""
    if o["denoise"] == "none":
        if any(o[k] is not None for k in ("denoise_levels", "denoise_mode", "denoise_block")):
            raise ValueError("--denoise-levels/-mode/-block need --denoise WAVELET")
        return None
    from ..denoise import DenoiseConfig

    kw: dict[str, Any] = {"wavelet": o["denoise"]}
    if o["denoise_levels"] is not None:
        kw["levels"] = o["denoise_levels"]
    if o["denoise_mode"] is not None:
        kw["threshold"] = o["denoise_mode"]
    if o["denoise_block"] is not None:
        d = DenoiseConfig()
        n = o["denoise_block"]
        kw.update(block=n, edge_start=round(d.edge_start * n / d.block), edge_end=round(d.edge_end * n / d.block))
    return Denoise(DenoiseConfig(**kw), timing=o["denoise_timing"])


def _environment(o: Mapping[str, Any]) -> Environment:
    if o["field"] is None and o["gravity"] is None:
        return EARTH
    f, i, d = o["field"] if o["field"] is not None else (EARTH.field_ut, math.degrees(EARTH.inclination),
                                                         math.degrees(EARTH.declination))
    return Environment(gravity=o["gravity"] if o["gravity"] is not None else EARTH.gravity, field_ut=f,
                       inclination=math.radians(i), declination=math.radians(d))


def _magnetometer(o: Mapping[str, Any]) -> dict[str, Any]:
    kw: dict[str, Any] = {"environment": _environment(o)}
    if o["mag"] != "none":
        kw["mag"] = mag_preset(o["mag"])
    if o["hard_iron"] is not None:
        kw["hard_iron"] = tuple(o["hard_iron"])
    if o["soft_iron"] is not None:
        v = o["soft_iron"]
        kw["soft_iron"] = [[v[0], 0, 0], [0, v[1], 0], [0, 0, v[2]]] if len(v) == 3 else \
            [list(v[0:3]), list(v[3:6]), list(v[6:9])]
    if o["disturbance"]:
        kw["disturbances"] = tuple(MagDisturbance(a, b, f, frame, ramp) for a, b, f, ramp, frame in o["disturbance"])
    if o["mag"] == "none" and ("hard_iron" in kw or "soft_iron" in kw or "disturbances" in kw):
        raise ValueError("--hard-iron, --soft-iron and --disturbance need a magnetometer: give --mag PART")
    return kw


def _estimator(o: Mapping[str, Any], has_accel: bool) -> dict[str, Any]:
    """The estimator options as SimConfig keywords."""
    if o["estimator"] == "integrator":
        if o["ahrs_setting"] or o["ahrs_init"] != "truth":
            raise ValueError("--ahrs-setting and --ahrs-init need --estimator ahrs")
        return {}
    if not has_accel:
        raise ValueError("--estimator ahrs needs an accelerometer: give --accel PART (e.g. --accel adis16405)")
    if o["precision"] == "fixed":
        raise ValueError("--estimator ahrs runs in --precision f64 or f32, not fixed")
    return {"estimator": "ahrs", **_settings(o)}
