"""The whole system in simulation: trajectory → gyros → ADC → link → integrator.

``simulate(SimConfig(...))`` runs one scenario and returns a
:class:`SimResult` (time series and a JSON-ready summary).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Literal, get_args

import numpy as np

from ..core import Method, Precision
from ..errors import InvalidArgument
from . import _integ
from ._rot import quat_angle_between, quat_to_euler, wrap_angle
from .sensors import (
    DEG,
    AdcModel,
    Board,
    Calibration,
    Conditioning,
    GyroModel,
    filtered_rate,
    gyro_preset,
    gyro_volts,
    rate_noise,
)
from .trajectory import PaperTrajectory, Trajectory

__all__ = ["PAPER_MAXIMA", "SENSOR_MODES", "Acquired", "SimConfig", "SimResult", "acquire", "simulate"]


def _package_version() -> str:
    """attitude_c.__version__ (read at use: the package resolves it lazily)."""
    import attitude_c

    return attitude_c.__version__


# The paper's reported error extremes at a 0.08 s period (sec. 4, Fig. 8), rad.
PAPER_MAXIMA = {"heading": (-0.05, 0.12), "pitch": (-0.10, 0.15)}

SensorMode = Literal["ideal", "quantized", "full"]
SENSOR_MODES: tuple[SensorMode, ...] = get_args(SensorMode)

Progress = Callable[[str, int, int], None]


@dataclass
class SimConfig:
    """Everything that defines a run (all units SI: s, rad, V).

    ``sensors``: ``"ideal"`` feeds the exact increments of the trajectory to
    the integrator (algorithm error only); ``"quantized"`` runs the board
    chain (conditioning, ADC, oversampled increment formation, calibration)
    with a perfect gyro; ``"full"`` adds the gyro's noise, bias, filter and
    saturation. ``link``: ``"c"`` sends every sample through the C sender and
    receiver (with the channel simulator when ``ber`` > 0), ``"none"`` hands
    the words over directly.
    """

    trajectory: Trajectory = field(default_factory=PaperTrajectory)
    duration: float = 60.0
    period: float = 0.08
    method: Method = "rv3"
    precision: Precision = "f64"
    sensors: SensorMode = "full"
    gyro: GyroModel = field(default_factory=lambda: gyro_preset("cg-l53"))
    conditioning: Conditioning = field(default_factory=Conditioning)
    adc: AdcModel = field(default_factory=AdcModel)
    board: Board = field(default_factory=Board)
    calibration_s: float = 60.0
    link: Literal["c", "none"] = "c"
    ber: float = 0.0
    link_attempts: int = 5
    seed: int = 0
    firmware: str | None = None

    def validate(self) -> None:
        _integ.check_method(self.method)
        _integ.check_precision(self.precision)
        for name in ("duration", "period"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InvalidArgument(f"{name} must be a finite number > 0 s, got {v!r}")
        if self.duration < self.period:
            raise InvalidArgument(f"duration ({self.duration} s) must be at least one period "
                                  f"({self.period} s)")
        span = getattr(self.trajectory, "span", None)  # a trajectory from data ends somewhere
        if span is not None and self.duration > span * (1 + 1e-9):
            raise InvalidArgument(f"duration ({self.duration:g} s) is longer than the trajectory's data "
                                  f"({span:g} s): the run would hold the last attitude, not measure")
        if self.duration / self.period > 2_000_000:
            raise InvalidArgument("duration/period above 2e6 samples: choose a shorter run")
        if self.sensors not in SENSOR_MODES:
            raise InvalidArgument(f"sensors must be one of {SENSOR_MODES}, got {self.sensors!r}")
        if self.link not in ("c", "none"):
            raise InvalidArgument(f"link must be 'c' or 'none', got {self.link!r}")
        if not (math.isfinite(self.ber) and 0 <= self.ber < 0.5):
            raise InvalidArgument(f"ber must be in [0, 0.5), got {self.ber!r}")
        if self.ber > 0 and self.link == "none":
            raise InvalidArgument("ber > 0 needs the link (link='c')")
        if self.ber > 0 and self.sensors == "ideal":
            raise InvalidArgument("ber > 0 needs the sensor chain (sensors 'quantized' or 'full'): "
                                  "ideal increments are not sent over the link")
        if not (math.isfinite(self.calibration_s) and self.calibration_s >= 0):
            raise InvalidArgument(f"calibration_s must be >= 0, got {self.calibration_s!r}")
        self.board.check(self.adc.bits)
        if self.firmware not in (None, "s51"):
            raise InvalidArgument(f"firmware must be None or 's51', got {self.firmware!r}")
        if self.firmware == "s51":
            from .firmware import FirmwareTrajectory

            if not isinstance(self.trajectory, FirmwareTrajectory):
                raise InvalidArgument("firmware='s51' runs the firmware's own gyro model: use a "
                                      "FirmwareTrajectory (attitude simulate --firmware s51 does)")
            if self.sensors == "ideal" or self.ber > 0:
                raise InvalidArgument("firmware='s51' takes the firmware's codes: sensors must "
                                      "not be 'ideal' and ber must be 0 (the pty link is clean)")

    def params(self) -> dict[str, Any]:
        return {
            "trajectory": self.trajectory.params(),
            "duration_s": self.duration,
            "period_s": self.period,
            "method": self.method,
            "precision": self.precision,
            "sensors": self.sensors,
            "gyro": self.gyro.to_dict(),
            "conditioning": {"vref_v": self.conditioning.vref, "span": self.conditioning.span,
                             "gain": self.conditioning.gain(self.gyro)},
            "adc": {"bits": self.adc.bits, "vref_v": self.adc.vref, "backend": self.adc.backend},
            "board": {"oversample": self.board.oversample, "delay_comp": self.board.delay_comp,
                      "sample_at": self.board.sample_at},
            "calibration_s": self.calibration_s,
            "link": self.link,
            "ber": self.ber,
            "link_attempts": self.link_attempts,
            "seed": self.seed,
            "firmware": self.firmware,
        }


@dataclass
class SimResult:
    config: SimConfig
    t: np.ndarray  # (M,) time of each attitude output (s)
    q_est: np.ndarray  # (M, 4)
    q_true: np.ndarray  # (M, 4)
    euler_est: np.ndarray  # (M, 3) yaw, pitch, roll
    euler_true: np.ndarray  # (M, 3)
    err: np.ndarray  # (M, 3) wrapped est − true, yaw/pitch/roll
    err_angle: np.ndarray  # (M,) total attitude error angle
    increments: np.ndarray  # (n, 3) increments fed to the integrator
    sample_index: np.ndarray  # (n,) true sample index of each fed increment
    link_stats: dict[str, Any]
    summary: dict[str, Any]

    @property
    def err_heading(self) -> np.ndarray:
        """Heading = −yaw, so its error is −(yaw error)."""
        return -self.err[:, 0]


def _stats(e: np.ndarray) -> dict[str, float]:
    if e.size == 0:
        return {"max": 0.0, "min": 0.0, "rms": 0.0, "max_abs": 0.0}
    return {"max": float(np.max(e)), "min": float(np.min(e)),
            "rms": float(np.sqrt(np.mean(e * e))), "max_abs": float(np.max(np.abs(e)))}


def _spawn(seed: int) -> dict[str, np.random.Generator]:
    # independent streams per error source, so that switching one source off
    # (error budget) leaves the random draws of the others unchanged
    ss = np.random.SeedSequence(seed)
    names = ("bias", "noise_cal", "noise_run", "link")
    return {n: np.random.default_rng(s) for n, s in zip(names, ss.spawn(len(names)))}


def _acquire(cfg: SimConfig, gyro: GyroModel, t0: float, n: int, rngs: dict[str, np.random.Generator],
             static: bool, bias: np.ndarray, progress: Progress | None, label: str) -> np.ndarray:
    """Board output words (n, 3) for n sample periods from t0."""
    h = cfg.period
    m = cfg.board.oversample
    dt = h / m
    delay = gyro.tau if cfg.board.delay_comp else 0.0
    frac = 0.5 if cfg.board.sample_at == "mid" else 0.0
    ti = t0 + (np.arange(n * m) + frac) * dt + delay
    if static:
        rate = np.zeros((n * m, 3))
    else:
        rate = filtered_rate(cfg.trajectory, ti, gyro.tau)
    rate = rate + rate_noise(n * m, dt, gyro, rngs["noise_cal" if static else "noise_run"])
    v = gyro_volts(rate, gyro, bias)
    g = cfg.conditioning.gain(gyro)
    v_adc = cfg.conditioning.vref / 2 + g * (v - gyro.null_v)
    cb = None
    if progress is not None:
        total = n * m

        def cb(done: int) -> None:
            progress(label, done, total)
    codes = cfg.adc.convert(v_adc, cb)
    return codes.reshape(n, m, 3).sum(axis=1)


def _calibrate(cfg: SimConfig, gyro: GyroModel, rngs: dict[str, np.random.Generator],
               bias: np.ndarray, progress: Progress | None) -> Calibration:
    m = cfg.board.oversample
    full = 1 << cfg.adc.bits
    g = cfg.conditioning.gain(gyro)
    # codes per rad/s through gyro scale, conditioning gain and ADC
    codes_per_rad_s = gyro.scale_v_per_dps / DEG * g * full / cfg.adc.vref
    n_cal = round(cfg.calibration_s / cfg.period)
    if n_cal > 0:
        words = _acquire(cfg, gyro, cfg.trajectory.t_start - cfg.calibration_s, n_cal, rngs,
                         True, bias, progress, "calibration")
        zero = words.mean(axis=0)
    else:  # nominal zero: mid-scale
        zero = np.full(3, m * cfg.adc.vref / 2 * full / cfg.adc.vref)
    return Calibration(zero_sum=zero, rad_per_s_per_code=1.0 / codes_per_rad_s, oversample=m)


@dataclass
class Acquired:
    """Increments as the host's integrator receives them, and their origin."""

    increments: np.ndarray  # (m, 3) rad
    sample_index: np.ndarray  # (m,) true sample index of each increment
    link_stats: dict[str, Any]
    calibration: Calibration | None
    backends: dict[str, Any]
    samples: int


def acquire(cfg: SimConfig, progress: Progress | None = None) -> Acquired:
    """The sensor side of the chain: trajectory → gyros → ADC → board → link →
    calibrated increments (everything before the integrator)."""
    cfg.validate()
    h = cfg.period
    n = math.floor(cfg.duration / h + 1e-9)
    t0 = cfg.trajectory.t_start
    rngs = _spawn(cfg.seed)
    backends: dict[str, Any] = {}
    link_stats: dict[str, Any] = {"link": "none"}
    calib = None
    if cfg.firmware == "s51":
        from .firmware import run_firmware

        codes, idx, link_stats = run_firmware(n, h, cfg.trajectory,  # type: ignore[arg-type]
                                              cfg.link_attempts, progress)
        # one truncating conversion per period (the in-image model: code = v >> 4)
        calib = Calibration(zero_sum=np.full(3, 2047.5),
                            rad_per_s_per_code=cfg.trajectory.rad_per_s_per_code,  # type: ignore[attr-defined]
                            oversample=1)
        inc = calib.increments(codes, h)
        backends["sensors"] = "AT89S51 firmware in s51 (TLC2543 + gyro model in the image)"
        backends["link"] = "firmware link sender → pty → C receiver"
    elif cfg.sensors == "ideal":
        inc = cfg.trajectory.increments(t0, h, n)
        idx = np.arange(n)
        backends["sensors"] = "exact increments"
    else:
        gyro = cfg.gyro if cfg.sensors == "full" else cfg.gyro.without(
            noise=True, bias=True, bandwidth=True, scale=True)
        bias = rngs["bias"].standard_normal(3) * gyro.bias_dps * DEG
        calib = _calibrate(cfg, gyro, rngs, bias, progress)
        words = _acquire(cfg, gyro, t0, n, rngs, False, bias, progress, "adc")
        backends["adc"] = cfg.adc.backend
        if cfg.link == "c":
            from ._link import send_words

            delivered, idx, link_stats = send_words(
                words, ber=cfg.ber, rng=rngs["link"], attempts=cfg.link_attempts,
                period=h, progress=progress)
            backends["link"] = link_stats.get("backend", "c")
        else:
            delivered, idx = words, np.arange(n)
            link_stats = {"link": "none", "sent": n, "delivered": n, "lost": 0, "duplicated": 0,
                          "corrupted_undetected": 0}
        inc = calib.increments(delivered, h)
    return Acquired(inc, idx, link_stats, calib, backends, n)


def simulate(cfg: SimConfig, progress: Progress | None = None,
             acquired: Acquired | None = None) -> SimResult:
    """Run one scenario end to end. ``progress(stage, done, total)`` is called
    during the long stages (ADC conversions, link blocks). ``acquired``
    reuses the sensor side of an earlier run (same sensors, link and seed)."""
    t_wall = time.perf_counter()
    cfg.validate()
    acq = acquired if acquired is not None else acquire(cfg, progress)
    h = cfg.period
    t0 = cfg.trajectory.t_start
    n = acq.samples
    inc, idx, link_stats, calib = acq.increments, acq.sample_index, acq.link_stats, acq.calibration
    backends = dict(acq.backends)
    backends["integrator"] = f"attitude_c.integrate ({cfg.precision})"
    first = int(idx[0]) if len(idx) else 0

    def q0_at(offset: float) -> np.ndarray:
        return cfg.trajectory.quat(t0 + (first + offset) * h)

    q_est, last, offset = _integ.run_integrator(inc, cfg.method, q0_at, cfg.precision, h)
    sample_idx = idx[last] if len(last) else np.zeros(0, dtype=int)
    t_out = t0 + (sample_idx + offset) * h
    q_true = cfg.trajectory.quat(t_out)
    e_est = quat_to_euler(q_est) if len(q_est) else np.zeros((0, 3))
    e_true = cfg.trajectory.euler(t_out) if len(t_out) else np.zeros((0, 3))
    err = wrap_angle(e_est - e_true)
    err_angle = quat_angle_between(q_true, q_est) if len(q_est) else np.zeros(0)
    summary: dict[str, Any] = {
        "attitude_c_version": _package_version(),
        "parameters": cfg.params(),
        "updates": len(t_out),
        "samples": int(n),
        "errors_rad": {
            "heading": _stats(-err[:, 0]),
            "yaw": _stats(err[:, 0]),
            "pitch": _stats(err[:, 1]),
            "roll": _stats(err[:, 2]),
            "attitude_angle": _stats(err_angle),
        },
        "paper_maxima_rad": {"heading": PAPER_MAXIMA["heading"][1], "pitch": PAPER_MAXIMA["pitch"][1]},
        "link": link_stats,
        "backends": backends,
    }
    eh = summary["errors_rad"]
    summary["times_better_than_paper"] = {
        "heading": PAPER_MAXIMA["heading"][1] / max(eh["heading"]["max_abs"], 1e-300),
        "pitch": PAPER_MAXIMA["pitch"][1] / max(eh["pitch"]["max_abs"], 1e-300),
    }
    if calib is not None:
        summary["calibration"] = calib.to_dict()
    summary["elapsed_s"] = time.perf_counter() - t_wall
    return SimResult(config=cfg, t=t_out, q_est=q_est, q_true=q_true, euler_est=e_est,
                     euler_true=e_true, err=err, err_angle=err_angle, increments=inc,
                     sample_index=idx, link_stats=link_stats, summary=summary)
