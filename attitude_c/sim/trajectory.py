"""Stage 1 of the simulator (docs/architecture.md): the truth.

Reference motions with exact truth: attitude, body rates and angle increments.
Every trajectory gives, for any time ``t`` (s):

* ``quat(t)`` — the true attitude Q (scalar first, body → ENU);
* ``euler(t)`` — ``[yaw, pitch, roll]`` of that attitude (z-x-y, rad);
* ``omega(t)`` — the true body angular rate (rad/s, body axes [x, y, z]), the
  one that satisfies ``dQ/dt = ½ Q ⊗ [0, ω]`` (so ``Q(k+1) = Q(k) ⊗ q(h)``);
* ``increments(t0, h, n)`` — the exact angle increments
  ``Δθ_k = ∫ ω dt`` over ``[t0 + k h, t0 + (k+1) h]``, shape ``(n, 3)``: what a
  perfect integrating gyro would deliver.

and, for the accelerometer and the magnetometer, in closed form from the
same attitude:

* ``accel_nav(t)`` — the linear acceleration of the body (m/s², ENU; zero
  unless the trajectory translates);
* ``specific_force(t, env)`` — what a perfect accelerometer reads,
  ``f_b = Cᵀ (a_n − g_n)`` with ``g_n = [0, 0, −g]`` (at rest, level: +g on
  body z);
* ``mag_field(t, env)`` — the local geomagnetic field in the body frame,
  ``m_b = Cᵀ m_n`` with ``m_n`` from the :class:`Environment`'s total
  intensity, inclination and declination;
* ``period_means(fn, t0, h, n)`` — the exact mean of such a quantity over
  each sample period (what a perfect averaging sensor delivers).

Trajectories: ``paper`` (sinusoidal Euler angles, rates from the exact z-x-y
Euler-rate kinematics; optionally a sinusoidal translation,
``paper-translation``), ``coning`` (classical coning, closed form),
``static`` (the MEMS AHRS paper's 30-minute test), ``turntable`` (the
FPGA+DSP paper's z-axis turntable, 5 °/s for 360 s), ``level-turn`` (a level
360° turn between two rests: the heading-repeatability test),
``constant-rate`` and ``csv`` (user data, slerp between rows).

The sensor stages (:mod:`attitude_c.sim.sensors`) read ``omega``,
``specific_force`` and ``mag_field``. The truth's rotation math is the NumPy
reference (:mod:`attitude_c.reference`), never the C library the chain tests.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, get_args

import numpy as np

from ..errors import InvalidArgument, NonFiniteError

# truth-side rotation math: the NumPy reference, independent of the C library the chain tests
from ..reference import (
    euler_to_quat,
    quat_conj,
    quat_multiply,
    quat_to_dcm,
    quat_to_euler,
    quat_to_rotvec,
    rotvec_to_quat,
)

__all__ = [
    "EARTH",
    "STANDARD_GRAVITY",
    "TRAJECTORIES",
    "ConingTrajectory",
    "ConstantRateTrajectory",
    "CsvTrajectory",
    "Environment",
    "LevelTurnTrajectory",
    "PaperTrajectory",
    "StaticTrajectory",
    "Trajectory",
    "TurntableTrajectory",
    "euler_rates_to_body",
    "make_trajectory",
    "to_body",
]

# Gauss–Legendre nodes used to integrate smooth rates over one interval: 8
# nodes are exact for polynomials of degree 15; for rates of a few rad/s at
# frequencies below ~10 Hz over h ≤ 0.1 s the remainder is below 1e-16 rad.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)


def _vec3(value: Any, name: str) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.shape == ():
        a = np.full(3, float(a))
    if a.shape != (3,):
        raise InvalidArgument(f"{name} must be a scalar or 3 values, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} must be finite, got {a.tolist()}")
    return a


#: Standard gravity (m/s², CGPM 1901): the default magnitude of g.
STANDARD_GRAVITY = 9.80665


@dataclass(frozen=True)
class Environment:
    """Gravity and the local geomagnetic field (the truth the accelerometer and
    the magnetometer read).

    ``gravity`` (m/s², magnitude; g_n = [0, 0, −g] in ENU); ``field_ut`` total
    intensity F (µT); ``inclination`` I (rad, positive when the field points
    down: northern hemisphere); ``declination`` D (rad, magnetic north east of
    true north positive). The field in ENU is
    ``m_n = [F cos I sin D, F cos I cos D, −F sin I]``.

    Defaults (:data:`EARTH`): standard gravity; F = 50.6 µT, I = 46.9°,
    D = −5.1° — an **assumption**: values of the order a geomagnetic model
    gives for Nanjing (the UAV thesis's site) around 2010, rounded; any other
    site is one ``Environment`` (``attitude simulate --field F,I,D``) away.
    """

    gravity: float = STANDARD_GRAVITY
    field_ut: float = 50.6
    inclination: float = math.radians(46.9)
    declination: float = math.radians(-5.1)

    def __post_init__(self) -> None:
        for name in ("gravity", "field_ut", "inclination", "declination"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise InvalidArgument(f"{name} must be a finite number, got {v!r}")
        if self.gravity < 0 or self.field_ut < 0:
            raise InvalidArgument(f"gravity and field_ut must be >= 0, got {self.gravity!r}, {self.field_ut!r}")
        if abs(self.inclination) > math.pi / 2:
            raise InvalidArgument(f"inclination must be in [-90°, 90°], got {math.degrees(self.inclination):g}°")

    @property
    def gravity_nav(self) -> np.ndarray:
        """g_n (m/s², ENU)."""
        return np.array([0.0, 0.0, -self.gravity])

    @property
    def field_nav(self) -> np.ndarray:
        """m_n (µT, ENU)."""
        h = self.field_ut * math.cos(self.inclination)
        return np.array([h * math.sin(self.declination), h * math.cos(self.declination),
                         -self.field_ut * math.sin(self.inclination)])

    def to_dict(self) -> dict[str, float]:
        return {"gravity_m_s2": self.gravity, "field_ut": self.field_ut,
                "inclination_deg": math.degrees(self.inclination),
                "declination_deg": math.degrees(self.declination)}


#: The default environment (see :class:`Environment`).
EARTH = Environment()


def to_body(q: np.ndarray, v_nav: np.ndarray) -> np.ndarray:
    """Navigation-frame vectors → body frame: ``v_b = Cᵀ v_n`` with ``C`` the
    attitude matrix of ``q`` (the NumPy reference's, docs/conventions.md)."""
    c = quat_to_dcm(q)
    return np.einsum("...ji,...j->...i", c, np.broadcast_to(v_nav, c.shape[:-1]))


def euler_rates_to_body(euler: np.ndarray, euler_dot: np.ndarray) -> np.ndarray:
    """Exact z-x-y kinematics: ``[ψ̇, θ̇, γ̇]`` at ``[ψ, θ, γ]`` → body rate ω.

    With ``C = R_z(ψ) R_x(θ) R_y(γ)`` and ``[ω×] = Cᵀ Ċ``:
    ``ω = R_yᵀ R_xᵀ [0, 0, ψ̇] + R_yᵀ [θ̇, 0, 0] + [0, γ̇, 0]``, i.e.
    ``ωx = θ̇ cos γ − ψ̇ sin γ cos θ``, ``ωy = γ̇ + ψ̇ sin θ``,
    ``ωz = θ̇ sin γ + ψ̇ cos γ cos θ``.
    """
    e = np.asarray(euler, dtype=float)
    d = np.asarray(euler_dot, dtype=float)
    th, ga = e[..., 1], e[..., 2]
    yd, td, gd = d[..., 0], d[..., 1], d[..., 2]
    wx = td * np.cos(ga) - yd * np.sin(ga) * np.cos(th)
    wy = gd + yd * np.sin(th)
    wz = td * np.sin(ga) + yd * np.cos(ga) * np.cos(th)
    return np.stack([wx, wy, wz], axis=-1)


@dataclass
class Trajectory:
    """Base class. Subclasses define ``quat`` and ``omega`` (and may override
    ``increments`` with a closed form)."""

    name: str = field(default="", init=False)
    t_start: float = field(default=0.0, init=False)

    def quat(self, t: Any) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def omega(self, t: Any) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def euler(self, t: Any) -> np.ndarray:
        return quat_to_euler(self.quat(t))

    def increments(self, t0: float, h: float, n: int) -> np.ndarray:
        """Exact ∫ω dt over n consecutive intervals of length h from t0."""
        k = np.arange(n, dtype=float)
        mid = t0 + (k + 0.5) * h
        tt = mid[:, None] + 0.5 * h * _GL_X[None, :]
        w = self.omega(tt)  # (n, 8, 3)
        return 0.5 * h * np.einsum("j,njk->nk", _GL_W, w)

    def accel_nav(self, t: Any) -> np.ndarray:
        """Linear acceleration of the body (m/s², ENU): zero unless the trajectory translates."""
        t = np.asarray(t, dtype=float)
        return np.zeros(t.shape + (3,))

    def position(self, t: Any) -> np.ndarray:
        """Position of the body (m, ENU): the origin unless the trajectory translates."""
        return np.zeros(np.shape(t) + (3,))

    def velocity(self, t: Any) -> np.ndarray:
        """Velocity of the body (m/s, ENU): zero unless the trajectory translates."""
        return np.zeros(np.shape(t) + (3,))

    def specific_force(self, t: Any, env: Environment = EARTH) -> np.ndarray:
        """What a perfect accelerometer reads (m/s², body axes): ``Cᵀ (a_n − g_n)``."""
        return to_body(self.quat(t), self.accel_nav(t) - env.gravity_nav)

    def mag_field(self, t: Any, env: Environment = EARTH) -> np.ndarray:
        """The geomagnetic field in the body frame (µT): ``Cᵀ m_n``."""
        return to_body(self.quat(t), env.field_nav)

    def period_means(self, fn: Any, t0: float, h: float, n: int) -> np.ndarray:
        """The mean of ``fn(t)`` (…, 3) over n consecutive periods h from t0, (n, 3):
        8-point Gauss–Legendre per period (the truth of a perfect averaging sensor;
        exact to rounding for the smooth motions here, like :meth:`increments`)."""
        k = np.arange(n, dtype=float)
        mid = t0 + (k + 0.5) * h
        tt = mid[:, None] + 0.5 * h * _GL_X[None, :]
        return 0.5 * np.einsum("j,njk->nk", _GL_W, fn(tt))

    @property
    def default_duration(self) -> float | None:
        """The test's own length (s) when the motion defines one (None: the caller's default)."""
        return None

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name}


@dataclass
class PaperTrajectory(Trajectory):
    """The paper's test (sec. 4): each Euler angle a sinusoid.

    ``angle_i(t) = offset_i + amplitude_i · sin(2π f_i t + phase_i)`` for
    ``i`` = yaw, pitch, roll. Defaults (rad, Hz): yaw 30°/0.20 Hz, pitch
    20°/0.25 Hz, roll 25°/0.30 Hz, phases 0°, 30°, 60°: at least 20° and
    0.2 Hz on every axis as the project asks, pitch far from ±90°, and three
    incommensurate-looking frequencies so that the motion is not a rotation
    about a fixed axis (the non-commutativity the rotation-vector methods
    compensate). The paper gives no numbers for its sinusoids.

    Translation (``paper-translation``): the body's position in ENU is
    ``p_i(t) = translation_i · sin(2π g_i t + ψ_i)`` (m), so
    ``a_n = −translation · (2π g)² · sin(2π g t + ψ)``; the accelerometer then
    reads the motion as well as gravity. Defaults of ``paper-translation``:
    5, 5, 1 m at 0.15, 0.10, 0.25 Hz (peaks 4.4, 2.0, 2.5 m/s²: a specific
    force up to 1.3 g, inside an ADXL202's ±2 g), phases 0.
    """

    amplitude: Any = (math.radians(30.0), math.radians(20.0), math.radians(25.0))
    frequency: Any = (0.20, 0.25, 0.30)
    phase: Any = (0.0, math.radians(30.0), math.radians(60.0))
    offset: Any = (0.0, 0.0, 0.0)
    translation: Any = (0.0, 0.0, 0.0)
    translation_frequency: Any = (0.15, 0.10, 0.25)
    translation_phase: Any = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        self.amplitude = _vec3(self.amplitude, "amplitude")
        self.frequency = _vec3(self.frequency, "frequency")
        self.phase = _vec3(self.phase, "phase")
        self.offset = _vec3(self.offset, "offset")
        self.translation = _vec3(self.translation, "translation")
        self.translation_frequency = _vec3(self.translation_frequency, "translation_frequency")
        self.translation_phase = _vec3(self.translation_phase, "translation_phase")
        self.name = "paper-translation" if np.any(self.translation != 0) else "paper"
        if np.any(self.frequency < 0) or np.any(self.translation_frequency < 0):
            raise InvalidArgument(f"frequencies must be >= 0 Hz, got {self.frequency.tolist()}, "
                                  f"{self.translation_frequency.tolist()}")
        worst = abs(self.offset[1]) + abs(self.amplitude[1])
        if worst >= math.pi / 2 - 1e-3:
            raise InvalidArgument(
                f"pitch offset+amplitude must stay below 90° (got {math.degrees(worst):.1f}°): "
                "the z-x-y Euler angles are singular at ±90° pitch")

    def _arg(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)[..., None]
        return 2 * np.pi * self.frequency * t + self.phase

    def euler(self, t: Any) -> np.ndarray:
        return self.offset + self.amplitude * np.sin(self._arg(t))

    def euler_dot(self, t: Any) -> np.ndarray:
        return self.amplitude * 2 * np.pi * self.frequency * np.cos(self._arg(t))

    def quat(self, t: Any) -> np.ndarray:
        return euler_to_quat(self.euler(t))

    def omega(self, t: Any) -> np.ndarray:
        return euler_rates_to_body(self.euler(t), self.euler_dot(t))

    def _targ(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)[..., None]
        return 2 * np.pi * self.translation_frequency * t + self.translation_phase

    def position(self, t: Any) -> np.ndarray:
        """Position of the body (m, ENU)."""
        return self.translation * np.sin(self._targ(t))

    def velocity(self, t: Any) -> np.ndarray:
        """Velocity of the body (m/s, ENU)."""
        return self.translation * 2 * np.pi * self.translation_frequency * np.cos(self._targ(t))

    def accel_nav(self, t: Any) -> np.ndarray:
        w = 2 * np.pi * self.translation_frequency
        return -self.translation * w * w * np.sin(self._targ(t))

    def params(self) -> dict[str, Any]:
        out = {
            "trajectory": self.name,
            "amplitude_deg": np.degrees(self.amplitude).tolist(),
            "frequency_hz": self.frequency.tolist(),
            "phase_deg": np.degrees(self.phase).tolist(),
            "offset_deg": np.degrees(self.offset).tolist(),
        }
        if np.any(self.translation != 0):
            out.update(translation_m=self.translation.tolist(),
                       translation_frequency_hz=self.translation_frequency.tolist(),
                       translation_phase_deg=np.degrees(self.translation_phase).tolist())
        return out


@dataclass
class ConingTrajectory(Trajectory):
    """Classical coning: the body z axis sweeps a cone of half-angle α at Ω.

    Closed form: ``Q(t) = [cos(α/2), sin(α/2) cos Ωt, sin(α/2) sin Ωt, 0]``
    (a rotation by α about the horizontal axis ``[cos Ωt, sin Ωt, 0]``), body
    rate ``ω = Ω [−sin α sin Ωt, sin α cos Ωt, cos α − 1]`` and exact
    increments ``Δθ = [sin α (cos Ωt₁ − cos Ωt₀), sin α (sin Ωt₁ − sin Ωt₀),
    Ω (cos α − 1)(t₁ − t₀)]`` (Savage, *Strapdown Analytics*, sec. 7.1.1.1).
    Defaults: α = 20°, 0.5 Hz.
    """

    half_angle: float = math.radians(20.0)
    frequency: float = 0.5

    def __post_init__(self) -> None:
        self.name = "coning"
        if not (math.isfinite(self.half_angle) and 0 <= self.half_angle < math.pi):
            raise InvalidArgument(f"half_angle must be in [0, π) rad, got {self.half_angle!r}")
        if not (math.isfinite(self.frequency) and self.frequency >= 0):
            raise InvalidArgument(f"frequency must be >= 0 Hz, got {self.frequency!r}")

    @property
    def rate(self) -> float:
        return 2 * math.pi * self.frequency

    def quat(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        a = self.half_angle
        wt = self.rate * t
        return np.stack([np.full_like(wt, math.cos(a / 2)), math.sin(a / 2) * np.cos(wt),
                         math.sin(a / 2) * np.sin(wt), np.zeros_like(wt)], axis=-1)

    def omega(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        a, w = self.half_angle, self.rate
        wt = w * t
        return np.stack([-w * math.sin(a) * np.sin(wt), w * math.sin(a) * np.cos(wt),
                         np.full_like(wt, w * (math.cos(a) - 1))], axis=-1)

    def increments(self, t0: float, h: float, n: int) -> np.ndarray:
        k = np.arange(n + 1, dtype=float)
        t = t0 + k * h
        a, w = self.half_angle, self.rate
        c, s = np.cos(w * t), np.sin(w * t)
        return np.stack([math.sin(a) * np.diff(c), math.sin(a) * np.diff(s),
                         np.full(n, w * (math.cos(a) - 1) * h)], axis=-1)

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name, "half_angle_deg": math.degrees(self.half_angle),
                "frequency_hz": self.frequency}


@dataclass
class ConstantRateTrajectory(Trajectory):
    """Rotation at a constant body rate from an initial attitude:
    ``Q(t) = Q₀ ⊗ q(ω t)``. Defaults: ω = [10, −5, 20] °/s from level north."""

    rate: Any = (math.radians(10.0), math.radians(-5.0), math.radians(20.0))
    euler0: Any = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        self.name = "constant-rate"
        self.rate = _vec3(self.rate, "rate")
        self.euler0 = _vec3(self.euler0, "euler0")
        self._q0 = euler_to_quat(self.euler0)

    def quat(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)[..., None]
        return quat_multiply(np.broadcast_to(self._q0, t.shape[:-1] + (4,)), rotvec_to_quat(self.rate * t))

    def omega(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        return np.broadcast_to(self.rate, t.shape + (3,)).copy()

    def increments(self, t0: float, h: float, n: int) -> np.ndarray:
        return np.tile(self.rate * h, (n, 1))

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name, "rate_dps": np.degrees(self.rate).tolist(),
                "euler0_deg": np.degrees(self.euler0).tolist()}


@dataclass
class StaticTrajectory(ConstantRateTrajectory):
    """No motion: a constant attitude (default level, facing north)."""

    rate: Any = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        self.name = "static"
        if np.any(self.rate != 0):
            raise InvalidArgument("a static trajectory has zero rate")

    @property
    def default_duration(self) -> float | None:
        """30 minutes: the MEMS AHRS paper's static test (sec. 4, Fig. 6–8)."""
        return 1800.0

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name, "euler0_deg": np.degrees(self.euler0).tolist()}


@dataclass
class TurntableTrajectory(ConstantRateTrajectory):
    """A single-axis turntable turning about the body z axis at a constant
    rate, from level north: the FPGA+DSP paper's test (sec. 4.2: z axis,
    5 °/s, 360 s; its default duration)."""

    rate: Any = (0.0, 0.0, math.radians(5.0))

    def __post_init__(self) -> None:
        super().__post_init__()
        self.name = "turntable"
        if self.rate[0] != 0 or self.rate[1] != 0:
            raise InvalidArgument(f"a turntable turns about body z only, got rate {self.rate.tolist()} rad/s")

    @property
    def default_duration(self) -> float | None:
        return 360.0

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name, "rate_dps": math.degrees(float(self.rate[2])),
                "euler0_deg": np.degrees(self.euler0).tolist()}


@dataclass
class LevelTurnTrajectory(Trajectory):
    """A level turn through ``turns`` · 360° between two rests: the MEMS AHRS
    paper's heading-repeatability test (a manual turntable turned through a
    full circle, sec. 4, Fig. 9).

    At rest for ``rest`` s, then a turn about the vertical whose rate rises and
    falls as a raised cosine, ``ψ̇(τ) = Ω (1 − cos 2πτ/T) / 2`` for ``τ`` in
    ``[0, T]`` (peak ``Ω = peak_rate``; ``T = 2 · 2π|turns| / Ω`` so that
    the turn covers the whole angle), then at rest again for ``rest`` s.
    Closed forms: ``ψ(τ) = ψ₀ ± (Ω/2)(τ − T/(2π) sin 2πτ/T)``, body rate
    ``[0, 0, ψ̇]`` (level), increments the differences of ψ. Defaults: 10 s
    rests, Ω = 10 °/s (T = 72 s), one counter-clockwise turn from north;
    92 s in all (the default duration). The start and the end heading are the
    same: what a magnetometer-aided heading must repeat.
    """

    rest: float = 10.0
    peak_rate: float = math.radians(10.0)
    turns: float = 1.0
    yaw0: float = 0.0

    def __post_init__(self) -> None:
        self.name = "level-turn"
        for nm in ("rest", "peak_rate", "turns", "yaw0"):
            v = getattr(self, nm)
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise InvalidArgument(f"{nm} must be a finite number, got {v!r}")
        if self.rest < 0 or self.peak_rate <= 0 or self.turns == 0:
            raise InvalidArgument("level-turn needs rest >= 0 s, peak_rate > 0 rad/s and turns != 0")

    @property
    def turn_time(self) -> float:
        """T (s): how long the turn lasts."""
        return 2 * 2 * math.pi * abs(self.turns) / self.peak_rate

    @property
    def default_duration(self) -> float | None:
        return 2 * self.rest + self.turn_time

    def yaw(self, t: Any) -> np.ndarray:
        """ψ(t) (rad, not wrapped)."""
        big_t = self.turn_time
        tau = np.clip(np.asarray(t, dtype=float) - self.rest, 0.0, big_t)
        sign = 1.0 if self.turns > 0 else -1.0
        return self.yaw0 + sign * 0.5 * self.peak_rate * (tau - big_t / (2 * np.pi) * np.sin(2 * np.pi * tau / big_t))

    def yaw_rate(self, t: Any) -> np.ndarray:
        big_t = self.turn_time
        tau = np.asarray(t, dtype=float) - self.rest
        inside = (tau >= 0) & (tau <= big_t)
        sign = 1.0 if self.turns > 0 else -1.0
        return np.where(inside, sign * 0.5 * self.peak_rate * (1 - np.cos(2 * np.pi * tau / big_t)), 0.0)

    def quat(self, t: Any) -> np.ndarray:
        y = self.yaw(t)
        return euler_to_quat(np.stack([y, np.zeros_like(y), np.zeros_like(y)], axis=-1))

    def omega(self, t: Any) -> np.ndarray:
        r = self.yaw_rate(t)
        return np.stack([np.zeros_like(r), np.zeros_like(r), r], axis=-1)

    def increments(self, t0: float, h: float, n: int) -> np.ndarray:
        d = np.diff(self.yaw(t0 + np.arange(n + 1) * h))
        return np.stack([np.zeros(n), np.zeros(n), d], axis=-1)

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name, "rest_s": self.rest, "peak_rate_dps": math.degrees(self.peak_rate),
                "turns": self.turns, "yaw0_deg": math.degrees(self.yaw0), "turn_s": self.turn_time}


class CsvTrajectory(Trajectory):
    """A trajectory from a user's CSV file.

    Columns (header names, case-insensitive): ``time, yaw, pitch, roll``
    (radians; add ``_deg`` to a name for degrees: ``yaw_deg``) or
    ``time, q0, q1, q2, q3`` (scalar first). Times strictly increasing, in
    seconds. Between two rows the attitude moves at the constant body rate
    that takes one row to the next (spherical linear interpolation), so the
    truth, the body rates and the increments are exactly consistent. Before
    the first row the body is at rest (the static calibration); a run may
    not go past the last row (``SimConfig.validate`` checks the duration
    against :attr:`span`).
    """

    def __init__(self, path: str | Path) -> None:
        self.name = "csv"
        self.path = str(path)
        try:
            with open(path, newline="") as fh:
                rows = list(csv.reader(fh))
        except OSError as exc:
            raise InvalidArgument(f"trajectory CSV {path!s}: cannot read ({exc.strerror})") from exc
        rows = [r for r in rows if r and not r[0].lstrip().startswith("#")]
        if len(rows) < 3:
            raise InvalidArgument(f"trajectory CSV {path!s}: need a header and at least 2 rows")
        header = [h.strip().lower() for h in rows[0]]
        try:
            data = np.array([[float(x) for x in r] for r in rows[1:]], dtype=float)
        except ValueError as exc:
            raise InvalidArgument(f"trajectory CSV {path!s}: non-numeric value ({exc})") from exc
        if data.ndim != 2 or data.shape[1] != len(header):
            raise InvalidArgument(f"trajectory CSV {path!s}: every row needs {len(header)} values")
        bad = np.argwhere(~np.isfinite(data))
        if bad.size:
            raise NonFiniteError(f"trajectory CSV {path!s}: non-finite value in data row {bad[0][0] + 1}",
                                 index=int(bad[0][0]))

        def col(*names: str) -> np.ndarray | None:
            for n in names:
                if n in header:
                    return data[:, header.index(n)]
            return None

        t = col("time", "t", "time_s")
        if t is None:
            raise InvalidArgument(f"trajectory CSV {path!s}: no 'time' column (header {header})")
        if np.any(np.diff(t) <= 0):
            i = int(np.argmax(np.diff(t) <= 0))
            raise InvalidArgument(f"trajectory CSV {path!s}: time not strictly increasing at data row {i + 2}")
        q_cols = [col(n) for n in ("q0", "q1", "q2", "q3")]
        if all(c is not None for c in q_cols):
            q = np.stack(q_cols, axis=-1)  # type: ignore[arg-type]
            norm = np.linalg.norm(q, axis=-1)
            if np.any(np.abs(norm - 1) > 1e-3):
                i = int(np.argmax(np.abs(norm - 1)))
                raise InvalidArgument(f"trajectory CSV {path!s}: quaternion in data row {i + 1} "
                                      f"has norm {norm[i]:.6f}, expected 1")
            q = q / norm[:, None]
        else:
            eul = []
            for n in ("yaw", "pitch", "roll"):
                c = col(n)
                if c is None:
                    c = col(n + "_deg")
                    if c is None:
                        raise InvalidArgument(
                            f"trajectory CSV {path!s}: need columns time,yaw,pitch,roll "
                            f"(rad, or *_deg) or time,q0,q1,q2,q3; got {header}")
                    c = np.radians(c)
                eul.append(c)
            q = euler_to_quat(np.stack(eul, axis=-1))
        # make consecutive quaternions take the short way
        for i in range(1, len(q)):
            if np.dot(q[i], q[i - 1]) < 0:
                q[i] = -q[i]
        self.t = t
        self.q = q
        self.t_start = float(t[0])
        self.t_end = float(t[-1])
        dt = np.diff(t)
        rv = quat_to_rotvec(quat_multiply(quat_conj(q[:-1]), q[1:]))
        self.rates = rv / dt[:, None]  # body rate of each segment
        # cumulative integral of ω at the rows (piecewise linear in between)
        self._cum = np.vstack([np.zeros(3), np.cumsum(rv, axis=0)])

    @property
    def span(self) -> float:
        """Seconds the file covers (first to last row): the longest run it can drive."""
        return self.t_end - self.t_start

    def _seg(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        tc = np.clip(t, self.t[0], self.t[-1])
        i = np.clip(np.searchsorted(self.t, tc, side="right") - 1, 0, len(self.t) - 2)
        return tc, i, tc - self.t[i]

    def quat(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        _, i, tau = self._seg(t)
        return quat_multiply(self.q[i], rotvec_to_quat(self.rates[i] * tau[..., None]))

    def omega(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        _, i, _ = self._seg(t)
        w = self.rates[i]
        inside = (t >= self.t[0]) & (t < self.t[-1])
        return np.where(inside[..., None], w, 0.0)

    def _cumulative(self, t: np.ndarray) -> np.ndarray:
        _, i, tau = self._seg(t)
        return self._cum[i] + self.rates[i] * tau[..., None]

    def increments(self, t0: float, h: float, n: int) -> np.ndarray:
        # the body-frame integral of a piecewise-constant rate (exact)
        tt = t0 + np.arange(n + 1) * h
        return np.diff(self._cumulative(tt), axis=0)

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name, "path": self.path, "rows": len(self.t),
                "t_start": self.t_start, "t_end": self.t_end}


TrajectoryKind = Literal["paper", "paper-translation", "coning", "static", "turntable", "level-turn",
                         "constant-rate", "csv", "fixed-wing", "fixed-wing-turn", "car", "car-brake",
                         "car-roundabout"]
TRAJECTORIES: tuple[TrajectoryKind, ...] = get_args(TrajectoryKind)

#: The translation of ``paper-translation`` when none is given (m, ENU).
PAPER_TRANSLATION_M = (5.0, 5.0, 1.0)
