"""The whole system in simulation: this module only composes the stages.

    trajectory → sensors → conditioning → ADC → board → link → host → estimator → outputs
    (trajectory.py, sensors.py, conditioning.py, adc.py, board.py, link.py, host.py,
     estimator.py, outputs.py: one stage each; docs/architecture.md)

``simulate(SimConfig(...))`` runs one scenario and returns a
:class:`SimResult` (time series and a JSON-ready summary); ``acquire(cfg)``
runs the acquisition side alone (everything before the estimator).

Acquisition sources. The modeled board (sensors → conditioning → ADC →
board → link) is the default source; the sensors="ideal" mode hands the
trajectory's exact increments to the estimator. Another source replaces the
acquisition side and delivers records to the same host stage: the AT89S51
firmware in s51 is one, registered from the tooling layer
(``toolchain/firmware.py``: ``python -m toolchain.simulate --firmware s51``),
never imported by this package; :func:`register_source` is how.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Callable, Literal, get_args

import numpy as np

from ..core import METHODS, PRECISIONS, Method, Precision
from ..errors import InvalidArgument
from . import aided
from .accelmag import MagDisturbance, SensorErrors, VectorSensor, VectorSensorModel
from .adc import ADC_BACKENDS, AdcModel
from .aided import AidedPlan, BoardKind
from .board import Board
from .conditioning import Conditioning
from .denoising import Denoise
from .estimator import (
    ESTIMATORS,
    AhrsFilter,
    Estimate,
    EstimatorName,
    Integrate,
    check_ahrs_settings,
)
from .gnss_model import GnssReceiver
from .host import AuxCalibration, AuxStream, Calibration, Decoded, HostDecoder
from .link import Link
from .outputs import compare
from .sensors import DEG, Gyro, GyroModel, gyro_preset
from .sources import Source, SourceOutput, register_source, source
from .trajectory import EARTH, Environment, PaperTrajectory, Trajectory

__all__ = ["PAPER_MAXIMA", "SENSOR_MODES", "Acquired", "SimConfig", "SimResult", "Source", "acquire",
           "register_source", "simulate", "source"]


#: Significant digits of the parameters a summary echoes. The values given in decimal come
#: back through unit conversions (degrees -> radians -> degrees, mg -> m/s²) with their last
#: binary digits changed (30 -> 29.999999999999996); 12 digits keep every value as typed
#: (and every derived one, such as a gain, to 1e-12) and drop that noise (float64 holds 15.9).
PARAM_DIGITS = 12
#: Decimal places of the wall times in a summary (``elapsed_s``): a millisecond, finer than
#: a run's repeatability on a shared machine.
WALL_DECIMALS = 3


def decimal_params(x: Any) -> Any:
    """``x`` (nested dicts, lists, tuples) with every float rounded to :data:`PARAM_DIGITS`
    significant digits (the parameters of a summary; results keep every digit)."""
    if isinstance(x, dict):
        return {k: decimal_params(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [decimal_params(v) for v in x]
    if isinstance(x, float) and math.isfinite(x):
        return float(f"{x:.{PARAM_DIGITS}g}")
    return x


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
    the records over directly. ``firmware``: the name of a registered
    acquisition source that replaces the modeled board (``"s51"``, from the
    tooling layer), or None.

    Beside the gyros (all optional; None: the paper's gyro-only system):
    ``accel`` and ``mag`` — the part models of an accelerometer and a
    magnetometer (:mod:`.accelmag`), read by the host directly (not over the
    link); ``environment`` — gravity and the local field they read;
    ``hard_iron`` (µT), ``soft_iron`` (3×3), ``disturbances`` — the
    magnetometer's installation and the fields placed in time;
    ``accel_channels`` — the ADC inputs of the accelerometer's three axes
    (the AD7927's VIN4–6 on the thesis's board). ``sensors`` applies to them
    too: "ideal" hands the estimator the exact period means, "quantized" a
    perfect part through its digitization. ``denoise`` — the wavelet
    denoiser stage on the gyro rates between host and estimator
    (:mod:`.denoising`, None: off).

    ``estimator``: ``"integrator"`` (the paper's system: ``method``,
    ``precision``) or ``"ahrs"`` — the attitude filter (:class:`.AhrsFilter`,
    needs ``accel``; six-axis without ``mag``) with ``ahrs_settings`` (the
    keywords of :func:`attitude_c.ahrs`; ``declination`` and ``gravity``
    default to ``environment``'s), ``precision`` f64/f32 and ``ahrs_init``
    ("truth": the true initial attitude, as the integrator; "align": the
    filter's own alignment on its first sample).

    ``gnss``: a GNSS receiver on the vehicle (:class:`.gnss_model.GnssReceiver`;
    None: none); ``gnss_log``: the name of the fix log (``*.nmea`` or ``*.ubx``)
    :func:`.report.write_run` writes beside the run's files (a relative name: in
    the output directory). The estimators do not read the fixes yet (issue 30's
    filters).
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
    accel: VectorSensorModel | None = None
    mag: VectorSensorModel | None = None
    environment: Environment = EARTH
    hard_iron: tuple[float, float, float] = (0.0, 0.0, 0.0)
    soft_iron: np.ndarray | Sequence[Sequence[float]] | None = None  # (3, 3); None: identity
    disturbances: tuple[MagDisturbance, ...] = ()
    accel_channels: tuple[int, int, int] = (4, 5, 6)
    denoise: Denoise | None = None
    estimator: EstimatorName = "integrator"
    ahrs_settings: dict[str, Any] = field(default_factory=dict)
    ahrs_init: Literal["truth", "align"] = "truth"
    board_kind: BoardKind = "gyro3"
    aided: AidedPlan = field(default_factory=AidedPlan)
    gnss: GnssReceiver | None = None
    gnss_log: str | None = None

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> SimConfig:
        """The configuration a dict of the simulator's options describes: keys are
        option names (:data:`attitude_c.sim.options.OPTIONS`, ``cone_angle``; the
        same as ``attitude simulate --cone-angle``), values as text (``"30,20,25"``)
        or as Python/TOML values (``[30, 20, 25]``); options not given take their
        defaults. ValueError/TypeError naming the option for a bad value or options
        that do not go together (:mod:`attitude_c.sim.configure`). Not validated
        as a whole: call :meth:`validate` (``simulate`` does)."""
        from .configure import keywords

        return cls(**keywords(values))

    def validate(self) -> None:
        if self.method not in METHODS:
            raise InvalidArgument(f"method must be one of {METHODS}, got {self.method!r}")
        if self.precision not in PRECISIONS:
            raise InvalidArgument(f"precision must be one of {PRECISIONS}, got {self.precision!r}")
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
        if self.adc.backend not in ADC_BACKENDS:
            raise InvalidArgument(f"adc backend must be one of {ADC_BACKENDS}, got {self.adc.backend!r}")
        if self.accel is not None and self.accel.kind != "accel":
            raise InvalidArgument(f"accel must be an accelerometer model, got a {self.accel.kind!r} model")
        if self.mag is not None and self.mag.kind != "mag":
            raise InvalidArgument(f"mag must be a magnetometer model, got a {self.mag.kind!r} model")
        if (self.disturbances or any(self.hard_iron) or self.soft_iron is not None) and self.mag is None:
            raise InvalidArgument("hard iron, soft iron and disturbances need a magnetometer (mag)")
        if sorted(set(self.accel_channels)) != sorted(self.accel_channels) or len(self.accel_channels) != 3 \
                or not all(0 <= c <= 7 for c in self.accel_channels):
            raise InvalidArgument(f"accel_channels must be 3 distinct ADC inputs 0..7, got {self.accel_channels}")
        if self.adc.backend == "ad7927" and self.accel is not None and set(self.accel_channels) & {0, 1, 2}:
            raise InvalidArgument(f"accel_channels {self.accel_channels} overlap the gyros' VIN0-2")
        self.magnetometer_install()  # shapes and values
        if self.estimator not in ESTIMATORS:
            raise InvalidArgument(f"estimator must be one of {ESTIMATORS}, got {self.estimator!r}")
        if self.estimator == "integrator" and (self.ahrs_settings or self.ahrs_init != "truth"):
            raise InvalidArgument("ahrs settings need the ahrs estimator (estimator='ahrs')")
        if self.board_kind != "gyro3":
            self._check_aided()
        if self.estimator == "ahrs":
            if self.accel is None and self.board_kind == "gyro3":
                raise InvalidArgument("the ahrs estimator needs an accelerometer: give accel (--accel PART)")
            if self.precision == "fixed":
                raise InvalidArgument("the ahrs estimator runs in f64 or f32, not fixed")
            stage = self.estimator_stage()
            assert isinstance(stage, AhrsFilter)
            check_ahrs_settings(stage.filter_settings())
        if self.firmware is not None:
            source(self.firmware).check(self)
            if self.accel is not None or self.mag is not None:
                raise InvalidArgument(f"the {self.firmware} source carries only the gyros: drop the "
                                      "accelerometer and magnetometer")

    def _check_aided(self) -> None:
        """The aided board's run: its own front ends, link v2 or none, the filter."""
        if self.board_kind != "aided9":
            raise InvalidArgument(f"board_kind must be 'gyro3' or 'aided9', got {self.board_kind!r}")
        self.aided.check()
        if self.accel is not None or self.mag is not None:
            raise InvalidArgument("the aided board carries its own front ends (aided.accel, aided.mag; "
                                  "--accel-frontend, --mag-frontend): drop accel and mag")
        if self.estimator != "ahrs":
            raise InvalidArgument("the aided board's chain ends in the filter: estimator must be 'ahrs'")
        if self.sensors == "ideal" or self.firmware is not None:
            raise InvalidArgument("the aided board runs the modeled sensors ('quantized' or 'full'), "
                                  "no firmware source")
        if self.adc.backend == "ad7927":
            raise InvalidArgument("the aided board converts with the TLC2543 (adc 'tlc2543' or 'ideal')")

    def estimator_stage(self) -> Integrate | AhrsFilter:
        """The estimator stage of the run (stage 8)."""
        if self.estimator == "ahrs":
            prec: Literal["f64", "f32"] = "f32" if self.precision == "f32" else "f64"  # validate refuses fixed
            return AhrsFilter(tuple(sorted(self.ahrs_settings.items())), prec, self.ahrs_init,
                              self.environment.declination, self.environment.gravity)
        return Integrate(self.method, self.precision)

    def magnetometer_install(self) -> tuple[np.ndarray, np.ndarray]:
        """(hard iron (3,) µT, soft iron (3, 3)) as arrays, checked."""
        h = np.asarray(self.hard_iron, dtype=float)
        soft = np.eye(3) if self.soft_iron is None else np.asarray(self.soft_iron, dtype=float)
        if h.shape != (3,) or soft.shape != (3, 3) or not (np.all(np.isfinite(h)) and np.all(np.isfinite(soft))):
            raise InvalidArgument(f"hard_iron must be 3 finite values (µT) and soft_iron a finite 3×3 "
                                  f"matrix, got {self.hard_iron!r}, {self.soft_iron!r}")
        if abs(np.linalg.det(soft)) < 1e-6:
            raise InvalidArgument(f"soft_iron must be invertible, got {soft.tolist()}")
        return h, soft

    def params(self) -> dict[str, Any]:
        """Every parameter of the run, JSON-ready, as decimal as they were given
        (:func:`decimal_params`)."""
        return decimal_params({
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
            **({} if self.board_kind == "gyro3" else
               {"board_kind": self.board_kind, "aided": self.aided.to_dict(),
                "link_protocol": "v2" if self.link == "c" else "none"}),
            **self._extra_params(),
        })

    def _extra_params(self) -> dict[str, Any]:
        """Parameters of the stages beside the paper's (only those in use: the
        default run's parameters stay what they were)."""
        out: dict[str, Any] = {}
        if self.accel is not None or self.mag is not None:
            out["environment"] = self.environment.to_dict()
        if self.accel is not None:
            out["accel"] = self.accel.to_dict()
            if self.adc.backend == "ad7927" and self.accel.output == "analog":
                out["accel"]["adc_channels"] = list(self.accel_channels)
        if self.mag is not None:
            h, soft = self.magnetometer_install()
            out["mag"] = {**self.mag.to_dict(), "hard_iron_ut": h.tolist(), "soft_iron": soft.tolist(),
                          "disturbances": [d.to_dict() for d in self.disturbances]}
        if self.conditioning.follower:
            out["conditioning_follower"] = True
        if self.estimator != "integrator":
            out["estimator"] = self.estimator
            out["ahrs_settings"] = dict(self.ahrs_settings)
            out["ahrs_init"] = self.ahrs_init
        if self.denoise is not None:
            c = self.denoise.config
            out["denoise"] = {"wavelet": c.wavelet, "levels": c.levels, "threshold": c.threshold,
                              "block": c.block, "edge_start": c.edge_start, "edge_end": c.edge_end,
                              "detrend": c.detrend, "timing": self.denoise.timing}
        return out

    def rad_per_s_per_code(self) -> float:
        """The nominal rad/s per code of one conversion through the gyro's scale,
        the conditioning gain and the ADC (what the host's calibration assumes)."""
        full = 1 << self.adc.bits
        return 1.0 / (self.gyro.volts_per_rad_s * self.conditioning.gain(self.gyro) * full / self.adc.vref)


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
    aux: dict[str, AuxStream] = field(default_factory=dict)  # "accel", "mag": one row per sample period
    period_t: np.ndarray | None = None  # (n,) start of each sample period (s)
    bias_t: np.ndarray | None = None  # (K,) times of the filter's gyro-bias estimates (s); None: no filter
    bias: np.ndarray | None = None  # (K, 3) the filter's gyro-bias estimate (rad/s, body)
    cov: np.ndarray | None = None  # (M, 3, 3) the filter's attitude covariance at t (rad², ENU); None: none

    @property
    def err_heading(self) -> np.ndarray:
        """Heading = −yaw, so its error is −(yaw error)."""
        return -self.err[:, 0]


# ---------------------------------------------------------------------------
# the modeled acquisition: sensors → conditioning → ADC → board → link
# ---------------------------------------------------------------------------

def _spawn(seed: int) -> dict[str, np.random.Generator]:
    # independent streams per error source, so that switching one source off
    # (error budget) leaves the random draws of the others unchanged
    # (the first four streams are those of the gyro-only chain: adding streams
    # after them leaves its draws, and so the default run, unchanged)
    ss = np.random.SeedSequence(seed)
    names = ("bias", "noise_cal", "noise_run", "link", "accel_errors", "accel_noise", "mag_errors", "mag_noise",
             "afe_errors", "afe_noise")
    return {n: np.random.default_rng(s) for n, s in zip(names, ss.spawn(len(names)))}


def _words(cfg: SimConfig, gyro: Gyro, t0: float, n: int, rng: np.random.Generator, static: bool,
           progress: Progress | None, label: str) -> np.ndarray:
    """The board's words (n, 3) of n periods from t0: gyro → conditioning → ADC → board sums."""
    board = cfg.board
    ti = board.instants(t0, n, cfg.period, gyro.model.tau)
    volts = gyro.volts(cfg.trajectory, ti, cfg.period / board.oversample, rng, static)
    v_adc = cfg.conditioning.apply(volts, gyro.model)
    cb = None
    if progress is not None:
        total = len(ti)

        def cb(done: int) -> None:
            progress(label, done, total)
    return board.sums(cfg.adc.convert(v_adc, cb))


def _vector_sensor(cfg: SimConfig, name: str, rngs: dict[str, np.random.Generator]) -> VectorSensor | None:
    """The accelerometer or magnetometer stage of the run, errors drawn (None: absent)."""
    model = cfg.accel if name == "accel" else cfg.mag
    if model is None:
        return None
    errors = SensorErrors.draw(model, rngs[f"{name}_errors"])  # drawn even when switched off: same streams
    if cfg.sensors != "full":
        model, errors = model.perfect(), SensorErrors.none()
    if name == "accel":
        return VectorSensor(model, errors, cfg.environment)
    h, soft = cfg.magnetometer_install()
    return VectorSensor(model, errors, cfg.environment, h, soft, tuple(cfg.disturbances))


def aux_stream(cfg: SimConfig, sensor: VectorSensor, name: str, n: int, rng: np.random.Generator,
               progress: Progress | None = None) -> AuxStream:
    """One accelerometer or magnetometer stream of n periods, as the host reads it.

    The part is sampled at the board's conversion instants (``oversample`` per
    period, delayed by the part's own filter delay when the board compensates);
    an analog part goes through the conditioning, the ADC (its own inputs:
    ``accel_channels`` on the AD7927) and the board's per-period sums, and the
    host converts the sums with the C converter and the part's nominal zero and
    scale; a digital part's readings are averaged per period. With
    ``sensors="ideal"`` the stream is the exact period mean."""
    traj, h, board = cfg.trajectory, cfg.period, cfg.board
    model = sensor.model
    t0 = traj.t_start
    m = board.oversample
    truth = traj.period_means(lambda t: sensor.truth(traj, t), t0, h, n)
    dist = (traj.period_means(lambda t: sensor.disturbance(traj, t), t0, h, n) if model.kind == "mag"
            else np.zeros((n, 3)))
    if cfg.sensors == "ideal":
        if model.kind == "mag":
            values = (truth + dist) @ sensor.soft_iron.T + sensor.hard_iron
        else:
            values = truth.copy()
        return AuxStream(name, model.name, model.unit, values, truth, dist, np.zeros(n, dtype=bool),
                         errors=sensor.errors.to_dict())
    ti = board.instants(t0, n, h, model.tau)
    readings = sensor.measure(traj, ti, h / m, rng)
    saturated = np.asarray(sensor.saturated(readings).reshape(n, m).any(axis=1), dtype=bool)
    if model.output == "digital":
        return AuxStream(name, model.name, model.unit, readings.reshape(n, m, 3).mean(axis=1), truth, dist,
                         saturated, errors=sensor.errors.to_dict())
    v_adc = cfg.conditioning.apply(sensor.volts(readings), model)
    cb = None
    if progress is not None:
        total = len(ti)

        def cb(done: int) -> None:
            progress(f"adc ({name})", done, total)
    chans = cfg.accel_channels if name == "accel" else None
    words = board.sums(cfg.adc.convert(v_adc, cb, channels=chans))
    full = 1 << cfg.adc.bits
    upc = 1.0 / (model.scale_v * cfg.conditioning.gain(model) * full / cfg.adc.vref)
    calib = AuxCalibration(np.full(3, cfg.adc.nominal_code(cfg.conditioning.null_at_adc(model))), upc)
    return AuxStream(name, model.name, model.unit, calib.convert(words, m), truth, dist, saturated, calib,
                     sensor.errors.to_dict())


def _aux(cfg: SimConfig, n: int, rngs: dict[str, np.random.Generator],
         progress: Progress | None) -> dict[str, AuxStream]:
    out: dict[str, AuxStream] = {}
    for name in ("accel", "mag"):
        sensor = _vector_sensor(cfg, name, rngs)
        if sensor is not None:
            out[name] = aux_stream(cfg, sensor, name, n, rngs[f"{name}_noise"], progress)
    return out


def _gyro_words(cfg: SimConfig, n: int, rngs: dict[str, np.random.Generator],
                progress: Progress | None) -> tuple[Calibration, np.ndarray]:
    """The host's gyro calibration and the board's gyro words (n, 3) of the run."""
    model = cfg.gyro if cfg.sensors == "full" else cfg.gyro.without(
        noise=True, bias=True, bandwidth=True, scale=True)
    gyro = Gyro(model, rngs["bias"].standard_normal(3) * model.bias_dps * DEG)
    m = cfg.board.oversample
    k = cfg.rad_per_s_per_code()  # nominal: the error sources switched off keep range and scale
    # host calibration: the gyros sit still for calibration_s before the run
    n_cal = round(cfg.calibration_s / cfg.period)
    t0 = cfg.trajectory.t_start
    if n_cal > 0:
        calib = Calibration.from_static(_words(cfg, gyro, t0 - cfg.calibration_s, n_cal, rngs["noise_cal"], True,
                                               progress, "calibration"), m, k)
    else:  # nominal zero: the conditioned null's code
        calib = Calibration(np.full(3, cfg.adc.nominal_code(cfg.conditioning.null_at_adc(cfg.gyro))), k, m)
    return calib, _words(cfg, gyro, t0, n, rngs["noise_run"], False, progress, "adc")


def _model(cfg: SimConfig, n: int, rngs: dict[str, np.random.Generator],
           progress: Progress | None) -> SourceOutput:
    calib, words = _gyro_words(cfg, n, rngs, progress)
    stream = cfg.board.stream(words, cfg.period)
    delivered = Link(cfg.link, cfg.ber, cfg.link_attempts).carry(stream, rngs["link"], cfg.period)
    backends: dict[str, Any] = {"adc": cfg.adc.backend}
    if cfg.link == "c":
        backends["link"] = delivered.stats.get("backend", "c")
    return SourceOutput(delivered, calib, backends, stream.sample, _aux(cfg, n, rngs, progress))


@dataclass
class Acquired:
    """Increments as the host's estimator receives them, and their origin."""

    increments: np.ndarray  # (m, 3) rad
    sample_index: np.ndarray  # (m,) true sample index of each increment
    link_stats: dict[str, Any]
    calibration: Calibration | None
    backends: dict[str, Any]
    samples: int
    decoded: Decoded | None = None
    aux: dict[str, AuxStream] = field(default_factory=dict)


def acquire(cfg: SimConfig, progress: Progress | None = None) -> Acquired:
    """The acquisition side: a source (the modeled board and link, or a registered
    one) → the host's decoding; or the exact increments with ``sensors="ideal"``."""
    cfg.validate()
    n = math.floor(cfg.duration / cfg.period + 1e-9)
    if cfg.sensors == "ideal" and cfg.firmware is None:
        inc = cfg.trajectory.increments(cfg.trajectory.t_start, cfg.period, n)
        idx = np.arange(n)
        aux = _aux(cfg, n, _spawn(cfg.seed), progress)
        return Acquired(inc, idx, {"link": "none"}, None, {"sensors": "exact increments"}, n,
                        Decoded(inc, idx, np.zeros((n, 3), dtype=np.int64),
                                aux={k: v.values[idx] for k, v in aux.items()}), aux)
    if cfg.board_kind == "aided9":
        return _aided(cfg, n, _spawn(cfg.seed), progress)
    if cfg.firmware is not None:
        out = source(cfg.firmware).acquire(cfg, n, progress)
    else:
        out = _model(cfg, n, _spawn(cfg.seed), progress)
    dec = HostDecoder(out.calibration, cfg.period).decode(out.delivered, out.stream_sample)
    keep = dec.sample_index < n  # a source may deliver past the run (the firmware stops on blocks)
    dec = Decoded(dec.increments[keep], dec.sample_index[keep], dec.words[keep],
                  [k for k in dec.held if k < n], dec.reports,
                  {k: v.values[dec.sample_index[keep]] for k, v in out.aux.items()})
    stats = dict(out.delivered.stats)
    if out.stream_sample is None:  # the stream's own numbering: count what it says
        good = len(dec.sample_index) - len(dec.held)
        stats.update(delivered=good, delivered_ok=good, lost=n - good, held=dec.held, reports=dec.reports)
    return Acquired(dec.increments, dec.sample_index, stats, out.calibration, out.backends, n, dec, out.aux)


def _aided(cfg: SimConfig, n: int, rngs: dict[str, np.random.Generator], progress: Progress | None) -> Acquired:
    """The aided board's acquisition (:mod:`.aided`): nine channels, its groups, link v2, the host."""
    calib, gyro = _gyro_words(cfg, n, rngs, progress)
    m = cfg.board.oversample
    # the front ends convert at the gyros' instants (one scan of the nine inputs), unfiltered delay
    instants = cfg.board.instants(cfg.trajectory.t_start, n, cfg.period, 0.0)
    streams, configs = aided.frontend_words(cfg, n, rngs, instants, m)
    head, groups = aided.aided_records(gyro, streams["accel"].values.astype(np.int64),
                                       streams["mag"].values.astype(np.int64), cfg.aided, m, cfg.period)
    sent = [r for g in groups for r in g]
    if cfg.link == "c":
        seed = int(rngs["link"].integers(1, 2**31 - 1))
        got, stats = aided.carry_v2(head, groups, cfg.aided, cfg.period, cfg.ber, seed)
    else:
        got, stats = head + sent, {"link": "none"}
    dec, count = aided.aided_decode(got, calib, configs, cfg.period)
    keep = dec.sample_index < n
    dec = Decoded(dec.increments[keep], dec.sample_index[keep], dec.words[keep], [k for k in dec.held if k < n],
                  dec.reports, {k: v[keep] for k, v in dec.aux.items()})
    for name, part in (("accel", "acc"), ("mag", "mag")):  # the truth beside the host's readings
        st = streams[name]
        st.values = np.full((n, 3), np.nan)
        st.values[dec.sample_index] = dec.aux[name]
        st.calibration = None
        st.errors = {"config": configs[name].lines()}
    good = len(dec.sample_index) - len(dec.held)
    groups_sent = {"gyr": n, "acc": len(range(0, n, cfg.aided.acc_every)),
                   "mag": len(range(0, n, cfg.aided.mag_every))}
    stats.update(sent=n, delivered=good, delivered_ok=good, lost=n - good, held=dec.held, reports=dec.reports,
                 records_sent=groups_sent, records_received=count)
    backends = {"adc": cfg.adc.backend, "board": "aided9 (modeled AT89S52 firmware groups)",
                "link": stats.get("backend", "none"), "sensor": "att_sensor (nominal acc-*/mag-* config)"}
    return Acquired(dec.increments, dec.sample_index, stats, calib, backends, n, dec, streams)


def simulate(cfg: SimConfig, progress: Progress | None = None,
             acquired: Acquired | None = None) -> SimResult:
    """Run one scenario end to end. ``progress(stage, done, total)`` is called
    during the long stages (ADC conversions, link blocks). ``acquired``
    reuses the acquisition side of an earlier run (same sensors, link and seed)."""
    t_wall = time.perf_counter()
    cfg.validate()
    acq = acquired if acquired is not None else acquire(cfg, progress)
    estimator = cfg.estimator_stage()
    dec = acq.decoded if acq.decoded is not None else Decoded(acq.increments, acq.sample_index,
                                                              np.zeros((len(acq.increments), 3), dtype=np.int64))
    denoise_summary: dict[str, Any] | None = None
    if cfg.denoise is not None:  # the stage between host and estimator
        dec, denoise_summary = cfg.denoise.run(dec, cfg.period)
    est = estimator.run(dec, cfg.trajectory.quat, cfg.trajectory.t_start, cfg.period)
    if cfg.denoise is not None and cfg.denoise.delay(cfg.period) > 0:  # real time: judged when available
        est = Estimate(est.t + cfg.denoise.delay(cfg.period), est.q)
    res = compare(est, cfg.trajectory)
    backends = dict(acq.backends)
    backends["integrator" if cfg.estimator == "integrator" else "estimator"] = estimator.backend
    errors = res.summary()
    summary: dict[str, Any] = {
        "attitude_c_version": _package_version(),
        "parameters": cfg.params(),
        "updates": len(res.t),
        "samples": int(acq.samples),
        "errors_rad": errors,
        "paper_maxima_rad": {"heading": PAPER_MAXIMA["heading"][1], "pitch": PAPER_MAXIMA["pitch"][1]},
        "link": acq.link_stats,
        "backends": backends,
    }
    summary["times_better_than_paper"] = {
        "heading": PAPER_MAXIMA["heading"][1] / max(errors["heading"]["max_abs"], 1e-300),
        "pitch": PAPER_MAXIMA["pitch"][1] / max(errors["pitch"]["max_abs"], 1e-300),
    }
    if acq.calibration is not None:
        summary["calibration"] = acq.calibration.to_dict()
    if acq.aux:
        summary["sensors"] = {k: v.summary() for k, v in acq.aux.items()}
    if denoise_summary is not None:
        summary["denoise"] = denoise_summary
    if est.info:
        summary["estimator"] = _estimator_summary(est, dec, cfg)
    summary["elapsed_s"] = round(time.perf_counter() - t_wall, WALL_DECIMALS)
    period_t = cfg.trajectory.t_start + np.arange(acq.samples) * cfg.period
    return SimResult(config=cfg, t=res.t, q_est=res.q_est, q_true=res.q_true, euler_est=res.euler_est,
                     euler_true=res.euler_true, err=res.err, err_angle=res.err_angle,
                     increments=dec.increments, sample_index=dec.sample_index, link_stats=acq.link_stats,
                     summary=summary, aux=acq.aux, period_t=period_t, bias_t=est.bias_t, bias=est.bias,
                     cov=est.cov)


def residual_bias(dec: Decoded, cfg: SimConfig) -> np.ndarray:
    """The gyro bias the estimator actually sees (rad/s, body, (3,)): the mean
    over the run of the host's rates minus the exact period-mean rates (what
    the host's calibration left, plus the drift and the noise's mean)."""
    if len(dec.increments) == 0:
        return np.zeros(3)
    h = cfg.period
    n = int(dec.sample_index.max()) + 1
    true = cfg.trajectory.increments(cfg.trajectory.t_start, h, n)[dec.sample_index] / h
    return np.asarray(np.mean(dec.increments / h - true, axis=0), dtype=float)


def _estimator_summary(est: Estimate, dec: Decoded, cfg: SimConfig) -> dict[str, Any]:
    """The filter's own figures for the summary: its settings, the final gyro-bias
    estimate beside the residual bias of the host's rates (rad/s), flags."""
    out = dict(est.info)
    out["bias_residual_rad_s"] = residual_bias(dec, cfg).tolist()
    return out
