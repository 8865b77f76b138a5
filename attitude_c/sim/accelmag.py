"""Stage 2 of the simulator, beside the gyro: the accelerometer and the magnetometer.

Both are three-axis *vector sensors* of one shape (:class:`VectorSensorModel`,
the part's figures; :class:`VectorSensor`, the stage: one part with the
errors drawn for this run). Per sample instant ``t_i`` (spaced ``dt``)::

    accelerometer   y = K f_b(t)                         + b + x(t) + n(t)
    magnetometer    y = K (S (m_b(t) + d(t)) + h)        + b + x(t) + n(t)

* ``f_b`` — the specific force, ``m_b`` — the geomagnetic field, both in the
  body frame and exact (:meth:`Trajectory.specific_force`,
  :meth:`Trajectory.mag_field`), seen through the part's first-order
  low-pass (bandwidth; 16-point Gauss–Laguerre of ``∫ u(t−s) e^{−s/τ}/τ ds``,
  as the gyro);
* ``K = diag(1 + s) M`` — scale-factor errors ``s`` and the axis
  misalignment ``M`` (unit diagonal, small off-diagonal elements: each
  sensing axis tilted towards the other two), drawn once per run;
* ``b`` — the turn-on bias, drawn once per run;
* ``x`` — a first-order Markov (Gauss–Markov) bias, the UAV thesis's
  accelerometer error model, eq. 3.54: ``x(k+1) = e^{−βT} x(k) + w(k)``,
  correlation time ``1/β`` (``markov_tau``), steady-state σ
  (``markov_sigma``; ``w`` of variance ``σ²(1 − e^{−2βT})``), started from its
  stationary distribution;
* ``n`` — white noise of density ``noise_density`` (units/√Hz, one-sided)
  through the same low-pass: an exact AR(1) sequence of variance
  ``N² · π/2 · f_c`` (without a filter: ``N²/dt``, the exactly integrated
  white noise);
* magnetometer only: ``S`` soft iron (a matrix, identity by default), ``h``
  hard iron (an offset), ``d(t)`` disturbances placed in time
  (:class:`MagDisturbance`: a field added for a window, with raised-cosine
  edges — a magnet approaching and leaving);

then clipped at ``±range`` (saturation, per axis), and either quantized to the
part's LSB (a digital part: ADIS164xx, HMR3000) or turned into volts
``null_v + scale_v · y`` (an analog part: the ADXL202, through the
conditioning and ADC stages like the gyro).

Presets (:data:`ACCEL_PRESETS`, :data:`MAG_PRESETS`) carry a source for every
figure (``sources``): ``datasheet``, ``thesis``/``paper`` (a source
document), or ``assumption``; docs/simulation.md tabulates them.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import Any, Callable, Literal, get_args

import numpy as np

from ..errors import InvalidArgument
from .trajectory import EARTH, Environment, Trajectory, to_body

__all__ = [
    "ACCEL_PRESETS",
    "G0",
    "MAG_PRESETS",
    "MagDisturbance",
    "SensorErrors",
    "VectorSensor",
    "VectorSensorModel",
    "accel_preset",
    "ar1",
    "drift",
    "filtered",
    "flicker",
    "mag_preset",
    "markov",
    "random_walk",
    "white_noise",
]

#: Standard gravity, m/s² per g.
G0 = 9.80665
_MG = G0 * 1e-3  # m/s² per milli-g
_GAUSS = 100.0  # µT per gauss
_DEG = math.pi / 180

Kind = Literal["accel", "mag"]
Output = Literal["analog", "digital"]

# Gauss–Laguerre nodes for the first-order filter y(t) = ∫ u(t−s) e^{−s/τ}/τ ds:
# 16 nodes integrate e^{−x}·(polynomial of degree 31) exactly; for rates of
# ≤ 1 Hz and τ ≤ 5 ms the remainder is far below 1e-12 rad/s.
_GLA_X, _GLA_W = np.polynomial.laguerre.laggauss(16)


def switched_off(model: Any, **off: bool) -> Any:
    """A copy of a frozen sensor model with each field named True switched off:
    ``bandwidth_hz`` to None (no filter), any other to 0 (the models' ``without``)."""
    return replace(model, **{name: None if name == "bandwidth_hz" else 0.0 for name, on in off.items() if on})


@dataclass(frozen=True)
class VectorSensorModel:
    """One three-axis accelerometer or magnetometer part (units: m/s² or µT).

    ``range`` saturation (± units per axis); ``noise_density`` white noise
    (units/√Hz); ``bandwidth_hz`` first-order low-pass −3 dB (None: none);
    ``bias_sigma`` 1σ turn-on bias per axis (units); ``scale_sigma`` 1σ
    scale-factor error (fraction); ``misalignment_sigma`` 1σ of each
    off-diagonal element of M (rad); ``markov_sigma``, ``markov_tau``
    first-order Markov bias (units, s; σ = 0: none); ``bias_instability``
    flicker bias B (units: Allan deviation floor 0.664 B) and ``random_walk``
    bias random walk K (units/√s), 0: none (docs/noise.md); ``output`` analog
    (``null_v`` + ``scale_v`` V per unit) or digital (``lsb`` units per count,
    None: not quantized); ``sources``: where each figure comes from.
    """

    name: str
    kind: Kind
    range: float
    noise_density: float
    bandwidth_hz: float | None
    bias_sigma: float
    scale_sigma: float
    misalignment_sigma: float
    markov_sigma: float = 0.0
    markov_tau: float = 100.0
    bias_instability: float = 0.0
    random_walk: float = 0.0
    output: Output = "digital"
    lsb: float | None = None
    scale_v: float = 0.0
    null_v: float = 2.5
    sources: dict[str, str] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if self.kind not in get_args(Kind):
            raise InvalidArgument(f"kind must be one of {get_args(Kind)}, got {self.kind!r}")
        if self.output not in get_args(Output):
            raise InvalidArgument(f"output must be one of {get_args(Output)}, got {self.output!r}")
        for nm in ("range", "noise_density", "bias_sigma", "scale_sigma", "misalignment_sigma",
                   "markov_sigma", "markov_tau", "bias_instability", "random_walk", "null_v", "scale_v"):
            v = getattr(self, nm)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise InvalidArgument(f"{self.name}: {nm} must be a finite number >= 0, got {v!r}")
        if self.range <= 0 or self.markov_tau <= 0:
            raise InvalidArgument(f"{self.name}: range and markov_tau must be > 0")
        if self.bandwidth_hz is not None and not (math.isfinite(self.bandwidth_hz) and self.bandwidth_hz > 0):
            raise InvalidArgument(f"{self.name}: bandwidth_hz must be > 0 Hz or None, got {self.bandwidth_hz!r}")
        if self.lsb is not None and not (math.isfinite(self.lsb) and self.lsb > 0):
            raise InvalidArgument(f"{self.name}: lsb must be > 0 or None, got {self.lsb!r}")
        if self.output == "analog" and self.scale_v <= 0:
            raise InvalidArgument(f"{self.name}: an analog part needs scale_v > 0 (V per unit)")

    @property
    def unit(self) -> str:
        return "m/s^2" if self.kind == "accel" else "uT"

    @property
    def tau(self) -> float:
        """Time constant of the output filter (s); 0 without one."""
        return 0.0 if not self.bandwidth_hz else 1.0 / (2 * math.pi * self.bandwidth_hz)

    @property
    def span_v(self) -> float:
        """Analog output swing from null to full range (V) — what the conditioning maps."""
        return self.range * self.scale_v

    @property
    def noise_sigma_filtered(self) -> float:
        """1σ of the white noise after the part's filter (units; inf without a filter)."""
        if not self.bandwidth_hz:
            return math.inf if self.noise_density else 0.0
        return self.noise_density * math.sqrt(math.pi / 2 * self.bandwidth_hz)

    def without(self, *, noise: bool = False, bias: bool = False, bandwidth: bool = False,
                scale: bool = False, misalignment: bool = False, markov: bool = False) -> VectorSensorModel:
        """A copy with the named error sources switched off."""
        return switched_off(self, noise_density=noise, bias_sigma=bias, bandwidth_hz=bandwidth,
                            scale_sigma=scale, misalignment_sigma=misalignment, markov_sigma=markov)

    def perfect(self) -> VectorSensorModel:
        """The same part (range, output, LSB) with every random error off."""
        return self.without(noise=True, bias=True, bandwidth=True, scale=True, misalignment=True, markov=True)

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["unit"] = self.unit
        return d


@dataclass(frozen=True)
class SensorErrors:
    """The errors of one part in one run: ``bias`` (3,) units, ``scale`` (3,)
    fractions, ``misalignment`` M (3, 3) with a unit diagonal."""

    bias: np.ndarray
    scale: np.ndarray
    misalignment: np.ndarray

    @classmethod
    def none(cls) -> SensorErrors:
        return cls(np.zeros(3), np.zeros(3), np.eye(3))

    @classmethod
    def draw(cls, model: VectorSensorModel, rng: np.random.Generator) -> SensorErrors:
        """Draw bias, scale and the six off-diagonal elements (always 15 normal
        draws, in that order, so that the stream does not depend on which are zero)."""
        e = rng.standard_normal(15)
        m = np.eye(3)
        m[~np.eye(3, dtype=bool)] = e[6:12] * model.misalignment_sigma
        return cls(e[0:3] * model.bias_sigma, e[3:6] * model.scale_sigma, m)

    @property
    def matrix(self) -> np.ndarray:
        """K = diag(1 + s) M."""
        return (1.0 + self.scale)[:, None] * self.misalignment

    def to_dict(self) -> dict[str, Any]:
        return {"bias": self.bias.tolist(), "scale": self.scale.tolist(),
                "misalignment": self.misalignment.tolist()}


Frame = Literal["body", "nav"]


@dataclass(frozen=True)
class MagDisturbance:
    """A magnetic field added for a window (a magnet approaching and leaving).

    ``field`` (3,) µT at full strength, in the ``frame`` "body" (carried with the
    sensor: a motor, a tool) or "nav" (fixed in the world: a magnet on the
    bench); active from ``start`` to ``end`` (s), rising over the first
    ``ramp`` s and falling over the last ``ramp`` s as raised cosines (0: a
    rectangular window). The part sees it through its filter like the
    geomagnetic field (16-point Gauss–Laguerre: within a few filter time
    constants of a rectangular edge the response is approximate)."""

    start: float
    end: float
    field: tuple[float, float, float]
    frame: Frame = "body"
    ramp: float = 0.0

    def __post_init__(self) -> None:
        vals = (self.start, self.end, self.ramp, *self.field)
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in vals) or len(self.field) != 3:
            raise InvalidArgument(f"disturbance: start, end, ramp and 3 field values must be finite, got {self!r}")
        if not (self.end > self.start and 0 <= 2 * self.ramp <= self.end - self.start):
            raise InvalidArgument(f"disturbance: need end > start and 0 <= 2·ramp <= end − start, got "
                                  f"start={self.start}, end={self.end}, ramp={self.ramp}")
        if self.frame not in get_args(Frame):
            raise InvalidArgument(f"disturbance frame must be one of {get_args(Frame)}, got {self.frame!r}")

    def weight(self, t: Any) -> np.ndarray:
        """The window's profile in [0, 1] at times t."""
        t = np.asarray(t, dtype=float)
        w = ((t >= self.start) & (t < self.end)).astype(float)
        if self.ramp > 0:
            up = np.clip((t - self.start) / self.ramp, 0.0, 1.0)
            down = np.clip((self.end - t) / self.ramp, 0.0, 1.0)
            w = w * 0.5 * (1 - np.cos(np.pi * np.minimum(up, down)))
        return w

    def body_field(self, traj: Trajectory, t: Any) -> np.ndarray:
        """The disturbance in the body frame (µT) at times t."""
        t = np.asarray(t, dtype=float)
        f = np.asarray(self.field, dtype=float)
        v = np.broadcast_to(f, t.shape + (3,)) if self.frame == "body" else to_body(traj.quat(t), f)
        return v * self.weight(t)[..., None]

    def to_dict(self) -> dict[str, Any]:
        return {"start_s": self.start, "end_s": self.end, "field_ut": list(self.field), "frame": self.frame,
                "ramp_s": self.ramp}


def filtered(fn: Callable[[np.ndarray], np.ndarray], t: np.ndarray, tau: float) -> np.ndarray:
    """``fn`` (…, 3) seen through a first-order low-pass of time constant tau."""
    if tau <= 0:
        return fn(np.asarray(t, dtype=float))
    tt = np.asarray(t, dtype=float)[..., None] - tau * _GLA_X
    return np.einsum("j,...jk->...k", _GLA_W, fn(tt))


def ar1(e: np.ndarray, a: float, b: float, x0: np.ndarray) -> np.ndarray:
    """x[0] = x0 (row), x[i] = a x[i−1] + b e[i]: (n, 3)."""
    out = np.empty_like(e)
    if len(e) == 0:
        return out
    x = np.asarray(x0, dtype=float)
    out[0] = x
    for i in range(1, len(e)):  # a plain loop: at most a few 10^5 rows
        x = a * x + b * e[i]
        out[i] = x
    return out


def white_noise(n: int, dt: float, density: float, bandwidth_hz: float | None,
                rng: np.random.Generator) -> np.ndarray:
    """(n, 3) samples spaced dt of white noise of one-sided density ``density``
    through a first-order low-pass (an exact AR(1), stationary start), or without
    a filter the mean of the white noise over each dt (σ = density/√dt)."""
    e = rng.standard_normal((n, 3))
    if density == 0 or n == 0:
        return np.zeros((n, 3))
    if not bandwidth_hz:
        return e * density / math.sqrt(dt)
    sigma = density * math.sqrt(math.pi / 2 * bandwidth_hz)
    a = math.exp(-dt * 2 * math.pi * bandwidth_hz)
    return ar1(e, a, sigma * math.sqrt(1 - a * a), e[0] * sigma)


def flicker(n: int, dt: float, b: float, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) flicker (1/f) noise of bias-instability coefficient ``b`` (units)
    sampled every dt: two-sided PSD ``S(f) = b²/(2π f)`` (IEEE Std 952, annex C),
    whose Allan deviation is flat at ``b·√(2 ln 2/π) = 0.664 b``. Spectral
    synthesis over 4n samples (Gaussian Fourier coefficients of variance
    ``S(f_k)·M/dt``, no DC), of which the first n are kept: the lowest
    frequency 1/(4 n dt) keeps the plateau within 1.4 % up to τ = n·dt/4."""
    if b == 0 or n == 0:
        return np.zeros((n, 3))
    m = 1 << max(2, (4 * n - 1).bit_length())
    f = np.fft.rfftfreq(m, dt)[1:]
    amp = np.sqrt(b * b / (2 * math.pi * f) * m / dt / 2)
    w = np.zeros((m // 2 + 1, 3), dtype=complex)
    w[1:] = (rng.standard_normal((len(f), 3)) + 1j * rng.standard_normal((len(f), 3))) * amp[:, None]
    w[-1] = w[-1].real * math.sqrt(2)  # the Nyquist coefficient is real, of variance S·M/dt
    return np.fft.irfft(w, n=m, axis=0)[:n]


def random_walk(n: int, dt: float, k: float, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) random walk of density ``k`` (units/√s, a rate random walk for a
    gyro) sampled every dt, from 0: steps of σ ``k·√dt``; its Allan deviation
    is ``k·√(τ/3)``."""
    if k == 0 or n == 0:
        return np.zeros((n, 3))
    steps = rng.standard_normal((n, 3)) * (k * math.sqrt(dt))
    steps[0] = 0.0
    return np.cumsum(steps, axis=0)


def drift(n: int, dt: float, b: float, k: float, rng: np.random.Generator) -> np.ndarray:
    """The in-run bias of a part: :func:`flicker` (``b``) plus :func:`random_walk`
    (``k``), each drawn only when non-zero (the noise stream of a part without
    them is unchanged)."""
    return flicker(n, dt, b, rng) + random_walk(n, dt, k, rng)


def markov(n: int, dt: float, sigma: float, tau: float, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) first-order Markov process (thesis eq. 3.54) sampled every dt:
    ``x(k+1) = e^{−dt/τ} x(k) + w(k)``, stationary σ, started stationary."""
    e = rng.standard_normal((n, 3))
    if sigma == 0 or n == 0:
        return np.zeros((n, 3))
    a = math.exp(-dt / tau)
    return ar1(e, a, sigma * math.sqrt(1 - a * a), e[0] * sigma)


@dataclass(frozen=True)
class VectorSensor:
    """The stage: one part (``model``) with its run's ``errors``, in its
    ``env``; magnetometer installation: ``hard_iron`` (3,) µT, ``soft_iron``
    (3, 3), ``disturbances``.

    :meth:`measure` takes the sample instants (s, (k,), spaced ``dt``) and a
    noise stream and returns the part's readings (k, 3) in units (saturated,
    quantized for a digital part); :meth:`volts` the analog output of those
    readings; :meth:`truth` the exact body-frame quantity."""

    model: VectorSensorModel
    errors: SensorErrors = field(default_factory=SensorErrors.none)
    env: Environment = EARTH
    hard_iron: np.ndarray = field(default_factory=lambda: np.zeros(3))
    soft_iron: np.ndarray = field(default_factory=lambda: np.eye(3))
    disturbances: tuple[MagDisturbance, ...] = ()

    def __post_init__(self) -> None:
        h = np.asarray(self.hard_iron, dtype=float)
        s = np.asarray(self.soft_iron, dtype=float)
        if h.shape != (3,) or s.shape != (3, 3) or not (np.all(np.isfinite(h)) and np.all(np.isfinite(s))):
            raise InvalidArgument(f"hard_iron must be 3 finite values and soft_iron a finite 3×3 matrix, "
                                  f"got shapes {h.shape}, {s.shape}")
        if self.model.kind == "accel" and (np.any(h != 0) or np.any(s != np.eye(3)) or self.disturbances):
            raise InvalidArgument("hard/soft iron and disturbances are magnetometer errors")
        object.__setattr__(self, "hard_iron", h)
        object.__setattr__(self, "soft_iron", s)

    def truth(self, traj: Trajectory, t: Any) -> np.ndarray:
        """The exact quantity the part measures, body frame: specific force (m/s²)
        or the geomagnetic field (µT), without disturbances."""
        if self.model.kind == "accel":
            return traj.specific_force(t, self.env)
        return traj.mag_field(t, self.env)

    def disturbance(self, traj: Trajectory, t: Any) -> np.ndarray:
        """The sum of the disturbances in the body frame (µT) at times t."""
        t = np.asarray(t, dtype=float)
        out = np.zeros(t.shape + (3,))
        for d in self.disturbances:
            out = out + d.body_field(traj, t)
        return out

    def measure(self, traj: Trajectory, instants: np.ndarray, dt: float, rng: np.random.Generator,
                static: bool = False) -> np.ndarray:
        """Readings (k, 3) at the instants. ``static``: the truth of the body at
        rest in its attitude at the first instant (unused by the chain today)."""
        m = self.model
        t = np.asarray(instants, dtype=float)
        k = len(t)
        if static and k:
            u = np.broadcast_to(self.truth(traj, t[:1]), (k, 3)).copy()
        else:
            u = filtered(lambda tt: self.truth(traj, tt), t, m.tau)
        if m.kind == "mag":
            if self.disturbances:
                u = u + filtered(lambda tt: self.disturbance(traj, tt), t, m.tau)
            u = u @ self.soft_iron.T + self.hard_iron
        y = u @ self.errors.matrix.T + self.errors.bias
        y = y + markov(k, dt, m.markov_sigma, m.markov_tau, rng)
        y = y + drift(k, dt, m.bias_instability, m.random_walk, rng)
        y = y + white_noise(k, dt, m.noise_density, m.bandwidth_hz, rng)
        y = np.clip(y, -m.range, m.range)
        if m.output == "digital" and m.lsb is not None:
            y = np.round(y / m.lsb) * m.lsb
        return y

    def volts(self, readings: np.ndarray) -> np.ndarray:
        """An analog part's output voltages for its readings (k, 3)."""
        m = self.model
        if m.output != "analog":
            raise InvalidArgument(f"{m.name} is a digital part: it has no analog output")
        return m.null_v + m.scale_v * np.asarray(readings, dtype=float)

    def saturated(self, readings: np.ndarray) -> np.ndarray:
        """Per reading (k,): whether any axis sits at the range."""
        return np.asarray(np.any(np.abs(readings) >= self.model.range * (1 - 1e-12), axis=-1), dtype=bool)

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"model": self.model.to_dict(), "errors": self.errors.to_dict()}
        if self.model.kind == "mag":
            d.update(hard_iron_ut=self.hard_iron.tolist(), soft_iron=self.soft_iron.tolist(),
                     disturbances=[x.to_dict() for x in self.disturbances], environment=self.env.to_dict())
        else:
            d["environment"] = self.env.to_dict()
        return d


# ---------------------------------------------------------------------------
# presets
# ---------------------------------------------------------------------------
# Source tags: "datasheet" — a figure of the part's data sheet seen in a copy of it
# while writing this; "datasheet†" — a data-sheet figure quoted from memory of the
# data sheet and not checked against a copy (check before relying on it);
# "thesis"/"paper" — a source document of the project (../shared/papers);
# "assumption" — ours, with the reason.

ACCEL_PRESETS: dict[str, VectorSensorModel] = {
    "adxl202": VectorSensorModel(
        "adxl202", "accel", range=2 * G0, noise_density=0.5 * _MG, bandwidth_hz=100.0,
        bias_sigma=20 * _MG, scale_sigma=0.01, misalignment_sigma=1.0 * _DEG,
        markov_sigma=2 * _MG, markov_tau=100.0, output="analog", scale_v=0.312 / G0, null_v=2.5,
        sources={
            "range": "datasheet: ±2 g (ADXL202/ADXL210 Rev. B); thesis sec. 4.3.4",
            "noise_density": "datasheet: 500 µg/√Hz typical noise floor; thesis Table 4.2 (6.1 mg rms at "
                             "100 Hz) agrees",
            "bandwidth_hz": "thesis: Cx = Cy = 47 nF, eq. 4.2 and Table 4.2 → ≈ 100 Hz",
            "scale_v": "datasheet†: 312 mV/g at XFILT/YFILT, VDD = 5 V (the thesis's Table 4.3 implies "
                       "≈ 0.57 V/g through its own front end)",
            "null_v": "datasheet: 0 g = 50 % duty cycle (VDD/2 at XFILT); thesis Table 4.3: 2.49 V level",
            "bias_sigma": "assumption: 20 mg, the order of the thesis's 0.01 V level offset (Table 4.3)",
            "scale_sigma": "assumption: 1 % left after a host calibration",
            "misalignment_sigma": "datasheet†: ±1° alignment error, taken as 1σ",
            "markov": "assumption: 2 mg, 100 s (the thesis's eq. 3.54 has the model, not the figures)",
        }),
    "adis16405": VectorSensorModel(
        "adis16405", "accel", range=18 * G0, noise_density=0.5 * _MG, bandwidth_hz=330.0,
        bias_sigma=50 * _MG, scale_sigma=0.003, misalignment_sigma=0.2 * _DEG,
        markov_sigma=0.2 * _MG, markov_tau=100.0, output="digital", lsb=3.33 * _MG,
        sources={
            "range": "datasheet: ±18 g (ADIS1640x family)",
            "noise_density": "datasheet: 0.5 mg/√Hz (ADIS1640x family)",
            "bandwidth_hz": "datasheet: 330 Hz (ADIS1640x family)",
            "lsb": "datasheet: 3.33 mg/LSB (14 bits)",
            "bias_sigma": "datasheet†: initial bias error 50 mg (1σ)",
            "markov": "datasheet†: in-run bias stability 0.2 mg (1σ) as the Markov σ; τ = 100 s assumption",
            "scale_sigma": "assumption: 0.3 % (factory calibrated)",
            "misalignment_sigma": "datasheet†: axis-to-axis ±0.2°, taken as 1σ",
        }),
    "adis16488": VectorSensorModel(
        "adis16488", "accel", range=18 * G0, noise_density=0.063 * _MG, bandwidth_hz=330.0,
        bias_sigma=16 * _MG, scale_sigma=0.005, misalignment_sigma=0.035 * _DEG,
        markov_sigma=0.1 * _MG, markov_tau=100.0, output="digital", lsb=0.8 * _MG,
        sources={
            "range": "datasheet: ±18 g (ADIS16488A)",
            "noise_density": "datasheet†: 0.063 mg/√Hz",
            "bandwidth_hz": "datasheet†: 330 Hz",
            "lsb": "datasheet†: 0.8 mg/LSB (16-bit output)",
            "bias_sigma": "datasheet†: bias repeatability 16 mg (1σ)",
            "markov": "datasheet†: in-run bias stability 0.1 mg (1σ) as the Markov σ; τ = 100 s assumption",
            "scale_sigma": "datasheet†: sensitivity repeatability 0.5 %",
            "misalignment_sigma": "datasheet†: axis-to-axis 0.035°",
        }),
    "ideal": VectorSensorModel(
        "ideal", "accel", range=50 * G0, noise_density=0.0, bandwidth_hz=None, bias_sigma=0.0,
        scale_sigma=0.0, misalignment_sigma=0.0, output="digital", lsb=None,
        sources={"all": "a perfect accelerometer (±50 g) for algorithm studies"}),
}

MAG_PRESETS: dict[str, VectorSensorModel] = {
    "hmr3000": VectorSensorModel(
        "hmr3000", "mag", range=1.0 * _GAUSS, noise_density=0.015, bandwidth_hz=10.0,
        bias_sigma=0.5, scale_sigma=0.005, misalignment_sigma=0.5 * _DEG, output="digital", lsb=0.01,
        sources={
            "range": "datasheet†: ±1 gauss",
            "heading": "thesis sec. 4.3.1: heading accuracy 0.5°, pitch/roll 0.4°, resolution 0.1°, "
                       "tilt-compensated to 40° (the compass's figures, not the field sensor's)",
            "noise_density": "assumption: 0.015 µT/√Hz, a 0.06 µT (1σ) reading at 10 Hz: 0.1° of heading "
                             "on the default 34.6 µT horizontal field (the 0.1° resolution)",
            "bandwidth_hz": "assumption: 10 Hz (the compass's update rates are up to 20 Hz)",
            "lsb": "assumption: 0.01 µT",
            "bias_sigma": "assumption: 0.5 µT",
            "scale_sigma": "assumption: 0.5 %",
            "misalignment_sigma": "assumption: 0.5° (of the order of its 0.5° heading accuracy)",
        }),
    "adis16405": VectorSensorModel(
        "adis16405", "mag", range=2.5 * _GAUSS, noise_density=0.125 / math.sqrt(math.pi / 2 * 1540.0),
        bandwidth_hz=1540.0, bias_sigma=0.4, scale_sigma=0.005, misalignment_sigma=0.25 * _DEG,
        output="digital", lsb=0.05,
        sources={
            "range": "datasheet: ±2.5 gauss (ADIS1640x family)",
            "noise_density": "datasheet†: output noise 1.25 mgauss rms over a 1540 Hz bandwidth, "
                             "as a density (0.0025 µT/√Hz)",
            "bandwidth_hz": "datasheet†: 1540 Hz",
            "lsb": "datasheet†: 0.5 mgauss/LSB",
            "bias_sigma": "datasheet†: initial bias error 4 mgauss",
            "scale_sigma": "assumption: 0.5 %",
            "misalignment_sigma": "assumption: 0.25°",
        }),
    "adis16488": VectorSensorModel(
        "adis16488", "mag", range=2.5 * _GAUSS, noise_density=0.045 / math.sqrt(math.pi / 2 * 330.0),
        bandwidth_hz=330.0, bias_sigma=1.5, scale_sigma=0.005, misalignment_sigma=0.25 * _DEG,
        output="digital", lsb=0.01,
        sources={
            "range": "datasheet: ±2.5 gauss (ADIS16488A)",
            "noise_density": "datasheet†: output noise 0.45 mgauss rms; over an assumed 330 Hz bandwidth "
                             "as a density (0.0020 µT/√Hz)",
            "bandwidth_hz": "assumption: 330 Hz (the inertial sensors' bandwidth)",
            "lsb": "datasheet†: 0.1 mgauss/LSB",
            "bias_sigma": "datasheet†: initial bias error 15 mgauss",
            "scale_sigma": "assumption: 0.5 %",
            "misalignment_sigma": "datasheet†: 0.25°",
        }),
    "ideal": VectorSensorModel(
        "ideal", "mag", range=10 * _GAUSS, noise_density=0.0, bandwidth_hz=None, bias_sigma=0.0,
        scale_sigma=0.0, misalignment_sigma=0.0, output="digital", lsb=None,
        sources={"all": "a perfect magnetometer (±10 gauss) for algorithm studies"}),
}


def accel_preset(name: str) -> VectorSensorModel:
    try:
        return ACCEL_PRESETS[name]
    except KeyError:
        raise InvalidArgument(f"accel must be one of {sorted(ACCEL_PRESETS)}, got {name!r}") from None


def mag_preset(name: str) -> VectorSensorModel:
    try:
        return MAG_PRESETS[name]
    except KeyError:
        raise InvalidArgument(f"mag must be one of {sorted(MAG_PRESETS)}, got {name!r}") from None
