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

Trajectories: ``paper`` (sinusoidal Euler angles, rates from the exact z-x-y
Euler-rate kinematics), ``coning`` (classical coning, closed form),
``static``, ``constant-rate`` and ``csv`` (user data, slerp between rows).

The sensor stage (:mod:`attitude_c.sim.sensors`) reads ``omega``; sensors of
other quantities read further truth methods added here beside it (a
trajectory then also gives, e.g., the specific force and the Earth's field
in the body frame). The truth's rotation math is the NumPy reference
(:mod:`attitude_c.reference`), never the C library the chain tests.
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
    quat_to_euler,
    quat_to_rotvec,
    rotvec_to_quat,
)

__all__ = [
    "TRAJECTORIES",
    "ConingTrajectory",
    "ConstantRateTrajectory",
    "CsvTrajectory",
    "PaperTrajectory",
    "StaticTrajectory",
    "Trajectory",
    "euler_rates_to_body",
    "make_trajectory",
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
    """

    amplitude: Any = (math.radians(30.0), math.radians(20.0), math.radians(25.0))
    frequency: Any = (0.20, 0.25, 0.30)
    phase: Any = (0.0, math.radians(30.0), math.radians(60.0))
    offset: Any = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        self.name = "paper"
        self.amplitude = _vec3(self.amplitude, "amplitude")
        self.frequency = _vec3(self.frequency, "frequency")
        self.phase = _vec3(self.phase, "phase")
        self.offset = _vec3(self.offset, "offset")
        if np.any(self.frequency < 0):
            raise InvalidArgument(f"frequency must be >= 0 Hz, got {self.frequency.tolist()}")
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

    def params(self) -> dict[str, Any]:
        return {
            "trajectory": self.name,
            "amplitude_deg": np.degrees(self.amplitude).tolist(),
            "frequency_hz": self.frequency.tolist(),
            "phase_deg": np.degrees(self.phase).tolist(),
            "offset_deg": np.degrees(self.offset).tolist(),
        }


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

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name, "euler0_deg": np.degrees(self.euler0).tolist()}


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


TrajectoryKind = Literal["paper", "coning", "static", "constant-rate", "csv"]
TRAJECTORIES: tuple[TrajectoryKind, ...] = get_args(TrajectoryKind)


def make_trajectory(kind: TrajectoryKind, **kw: Any) -> Trajectory:
    """Build a trajectory by name (``paper``, ``coning``, ``static``,
    ``constant-rate``, ``csv`` with ``path=``)."""
    if kind == "paper":
        return PaperTrajectory(**kw)
    if kind == "coning":
        return ConingTrajectory(**kw)
    if kind == "static":
        return StaticTrajectory(**kw)
    if kind == "constant-rate":
        return ConstantRateTrajectory(**kw)
    if kind == "csv":
        if "path" not in kw:
            raise InvalidArgument("the csv trajectory needs path=")
        return CsvTrajectory(kw["path"])
    raise InvalidArgument(f"trajectory must be one of {TRAJECTORIES}, got {kind!r}")


