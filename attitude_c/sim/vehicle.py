"""Vehicle trajectories: a fixed-wing aircraft and a car in the ENU frame.

A vehicle moves along its path: speed ``V``, track yaw ``ψ`` (the library's
yaw, counter-clockwise from north: heading = −ψ) and flight-path angle ``θ``.
The body's forward axis (body y) points along the velocity -- no angle of
attack, no sideslip (an **assumption**: a real aircraft flies a few degrees
nose up) -- so the attitude is the z-x-y Euler triple ``[ψ, θ, γ]``
(docs/conventions.md) with

* a car: ``γ = 0`` (a level road; no body roll, no pitch under braking);
* a fixed-wing aircraft: the **coordinated** bank, the one that puts the
  specific force in the body's y-z plane (no lateral specific force).

In the path frame ``P = R_z(ψ) R_x(θ)`` (x right, y along the velocity, z up
of the path) the velocity is ``V ŷ``, its acceleration
``a_P = [−V ψ̇ cos θ, V̇, V θ̇]`` and gravity's reaction ``g [0, sin θ, cos θ]``,
so the specific force is ``f_P = [−V ψ̇ cos θ, V̇ + g sin θ, V θ̇ + g cos θ]``
and the coordinated bank ``γ = atan2(f_Px, f_Pz)``; level (θ = θ̇ = 0) this is
``tan φ = V ω / g`` with ``ω = |ψ̇|``, left turns (ψ̇ > 0) left wing down
(γ < 0). ``γ̇`` follows in closed form from ``V̈``, ``ψ̈``, ``θ̈``; the body rate
from the exact Euler-rate kinematics (:func:`.trajectory.euler_rates_to_body`).

The motion is a list of :class:`Leg` s. Each leg sets the longitudinal
acceleration ``V̇``, the turn rate ``ψ̇`` and the flight-path angle ``θ`` it
holds; at its start each moves from the previous leg's value along a quintic
smoothstep ``S(x) = 10x³ − 15x⁴ + 6x⁵`` over ``ramp`` s (continuous with two
derivatives: bounded jerk, continuous body rates). ``V`` and ``ψ`` are the
integrals in closed form (``∫S = 2.5x⁴ − 3x⁵ + x⁶``); the position is the
integral of the velocity by 8-point Gauss–Legendre over pieces that never
straddle a ramp's end (exact to rounding for these smooth pieces). A leg of
duration ``D`` that ramps a rate up and the next leg that ramps it down change
its integral by exactly ``rate · D`` (each ramp contributes half): the
builders below use that to reach speeds and headings exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from ..errors import InvalidArgument
from ..reference import euler_to_quat
from .trajectory import _GL_W, _GL_X, STANDARD_GRAVITY, Trajectory, euler_rates_to_body

__all__ = ["ACCEPTANCE_CASES", "VEHICLE_PRESETS", "Leg", "VehicleTrajectory", "car", "car_brake", "car_roundabout", "coordinated_rate",
           "fixed_wing", "fixed_wing_turn", "vehicle_trajectory"]

Vehicle = Literal["fixed-wing", "car"]


@dataclass(frozen=True)
class Leg:
    """One piece of a vehicle's motion: for ``duration`` s, hold the longitudinal
    acceleration ``accel`` (m/s²), the turn rate ``turn_rate`` (rad/s, ψ̇: positive
    counter-clockwise, a left turn) and the flight-path angle ``climb`` (rad), each
    reached from the previous leg's value over the first ``ramp`` s."""

    duration: float
    accel: float = 0.0
    turn_rate: float = 0.0
    climb: float = 0.0
    ramp: float = 1.0

    def __post_init__(self) -> None:
        for nm in ("duration", "accel", "turn_rate", "climb", "ramp"):
            v = getattr(self, nm)
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise InvalidArgument(f"leg {nm} must be a finite number, got {v!r}")
        if not 0 < self.ramp <= self.duration:
            raise InvalidArgument(f"leg ramp must be in (0, duration = {self.duration:g}] s, got {self.ramp!r}")
        if abs(self.climb) >= math.radians(60):
            raise InvalidArgument(f"leg climb must be within ±60°, got {math.degrees(self.climb):g}°")


def _smooth(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """S, S', S'' and ∫S of the quintic smoothstep at x clipped to [0, 1] (∫ continues linearly past 1)."""
    c = np.clip(x, 0.0, 1.0)
    inside = (x > 0) & (x < 1)
    s = c ** 3 * (10 - 15 * c + 6 * c * c)
    ds = np.where(inside, 30 * c * c * (1 - c) ** 2, 0.0)
    dds = np.where(inside, 60 * c * (1 - c) * (1 - 2 * c), 0.0)
    integral = c ** 4 * (2.5 - 3 * c + c * c) + np.maximum(x - 1, 0.0)
    return s, ds, dds, integral


class _Channel:
    """One control of the legs (values held from each leg's start, smoothstep ramps):
    value, first and second derivative, and the integral from t = 0, at any t
    (before 0: the initial value; after the last leg: its value)."""

    def __init__(self, starts: np.ndarray, ramps: np.ndarray, values: np.ndarray, initial: float) -> None:
        self.starts, self.ramps = starts, ramps
        self.prev = np.concatenate([[initial], values[:-1]])
        self.values = values
        self.initial = initial
        # the integral at each leg's start
        lengths = np.diff(np.append(starts, np.inf))[:-1]
        pieces = [self._piece(k, lengths[k])[3] for k in range(len(starts) - 1)]
        self.cum = np.concatenate([[0.0], np.cumsum(pieces)])

    def _piece(self, k: Any, tau: np.ndarray) -> tuple[np.ndarray, ...]:
        r = self.ramps[k]
        s, ds, dds, integral = _smooth(tau / r)
        d = self.values[k] - self.prev[k]
        return (self.prev[k] + d * s, d * ds / r, d * dds / (r * r), self.prev[k] * tau + d * r * integral)

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        k = np.clip(np.searchsorted(self.starts, t, side="right") - 1, 0, len(self.starts) - 1)
        tau = t - self.starts[k]
        before = tau < 0
        v, dv, ddv, integral = self._piece(k, np.maximum(tau, 0.0))
        return (np.where(before, self.initial, v), np.where(before, 0.0, dv), np.where(before, 0.0, ddv),
                np.where(before, self.initial * tau, self.cum[k] + integral))


class VehicleTrajectory(Trajectory):
    """A vehicle (module doc) driven by ``legs`` from speed ``speed0`` (m/s), track yaw
    ``yaw0`` (rad), flight-path angle ``climb0`` (rad) and position ``position0``
    (m, ENU). ``vehicle``: ``"fixed-wing"`` (coordinated bank) or ``"car"``
    (level). ``gravity`` (m/s²): the g of the coordinated bank (keep it the
    environment's). The default duration is the legs' total."""

    def __init__(self, name: str, legs: list[Leg] | tuple[Leg, ...], vehicle: Vehicle = "fixed-wing",
                 speed0: float = 0.0, yaw0: float = 0.0, climb0: float = 0.0,
                 position0: Any = (0.0, 0.0, 0.0), gravity: float = STANDARD_GRAVITY,
                 params: dict[str, Any] | None = None) -> None:
        if vehicle not in ("fixed-wing", "car"):
            raise InvalidArgument(f"vehicle must be fixed-wing or car, got {vehicle!r}")
        if not legs or not all(isinstance(leg, Leg) for leg in legs):
            raise InvalidArgument("legs must be a non-empty list of Leg")
        if not (math.isfinite(speed0) and speed0 >= 0 and math.isfinite(gravity) and gravity > 0):
            raise InvalidArgument(f"speed0 must be >= 0 m/s and gravity > 0, got {speed0!r}, {gravity!r}")
        if vehicle == "car" and (climb0 != 0 or any(leg.climb != 0 for leg in legs)):
            raise InvalidArgument("a car drives on a level road: climb must be 0")
        self.name = name
        self.vehicle = vehicle
        self.legs = tuple(legs)
        self.speed0, self.yaw0, self.gravity = float(speed0), float(yaw0), float(gravity)
        self.position0 = np.asarray(position0, dtype=float).reshape(3)
        self._extra = dict(params or {})
        starts = np.concatenate([[0.0], np.cumsum([leg.duration for leg in legs])[:-1]])
        ramps = np.array([leg.ramp for leg in legs])
        self._accel = _Channel(starts, ramps, np.array([leg.accel for leg in legs]), 0.0)
        self._rate = _Channel(starts, ramps, np.array([leg.turn_rate for leg in legs]), 0.0)
        self._climb = _Channel(starts, ramps, np.array([leg.climb for leg in legs]), float(climb0))
        self.total = float(sum(leg.duration for leg in legs))
        # position knots: every leg start and ramp end, then at most 1 s apart
        edges = np.unique(np.concatenate([starts, starts + ramps, [self.total]]))
        self._knots = np.unique(np.concatenate([np.linspace(a, b, math.ceil((b - a) / 1.0) + 1)
                                                for a, b in zip(edges[:-1], edges[1:])]))
        self._pos_knots = self.position0 + np.concatenate(
            [np.zeros((1, 3)), np.cumsum(self._gl(self._knots[:-1], self._knots[1:]), axis=0)])
        lowest = float(np.min(self.speed(np.append(self._knots, self._knots[-1] + 1.0))))
        if lowest < -1e-9:
            raise InvalidArgument(f"{name}: the legs take the speed below zero ({lowest:.3g} m/s)")

    # --- the path ---------------------------------------------------------------------------
    def speed(self, t: Any) -> np.ndarray:
        """V (m/s)."""
        return self.speed0 + self._accel(np.asarray(t, dtype=float))[3]

    def _path(self, t: Any) -> dict[str, np.ndarray]:
        t = np.asarray(t, dtype=float)
        a, da, _, ia = self._accel(t)
        r, dr, _, ir = self._rate(t)
        th, dth, ddth, _ = self._climb(t)
        return {"v": self.speed0 + ia, "dv": a, "ddv": da, "psi": self.yaw0 + ir, "dpsi": r, "ddpsi": dr,
                "th": th, "dth": dth, "ddth": ddth}

    def _bank(self, p: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """γ and γ̇ (rad, rad/s): the coordinated bank (fixed-wing) or 0 (car)."""
        if self.vehicle == "car":
            z = np.zeros_like(p["v"])
            return z, z
        v, dv, psi_d, th, th_d = p["v"], p["dv"], p["dpsi"], p["th"], p["dth"]
        g = self.gravity
        fx = -v * psi_d * np.cos(th)
        fz = v * th_d + g * np.cos(th)
        dfx = -(dv * psi_d * np.cos(th) + v * p["ddpsi"] * np.cos(th) - v * psi_d * th_d * np.sin(th))
        dfz = dv * th_d + v * p["ddth"] - g * th_d * np.sin(th)
        return np.arctan2(fx, fz), (fz * dfx - fx * dfz) / (fx * fx + fz * fz)

    def euler(self, t: Any) -> np.ndarray:
        p = self._path(t)
        bank, _ = self._bank(p)
        yaw = np.mod(p["psi"] + np.pi, 2 * np.pi) - np.pi
        return np.stack([np.where(yaw == -np.pi, np.pi, yaw), p["th"], bank], axis=-1)

    def quat(self, t: Any) -> np.ndarray:
        return euler_to_quat(self.euler(t))

    def omega(self, t: Any) -> np.ndarray:
        p = self._path(t)
        bank, bank_d = self._bank(p)
        e = np.stack([p["psi"], p["th"], bank], axis=-1)
        return euler_rates_to_body(e, np.stack([p["dpsi"], p["dth"], bank_d], axis=-1))

    def velocity(self, t: Any) -> np.ndarray:
        """Velocity (m/s, ENU): ``V [−sin ψ cos θ, cos ψ cos θ, sin θ]``."""
        p = self._path(t)
        return p["v"][..., None] * _along(p["psi"], p["th"])

    def accel_nav(self, t: Any) -> np.ndarray:
        """Acceleration (m/s², ENU): the path frame's ``a_P`` rotated into ENU."""
        p = self._path(t)
        v = p["v"]
        a_path = np.stack([-v * p["dpsi"] * np.cos(p["th"]), p["dv"], v * p["dth"]], axis=-1)
        c = _path_matrix(p["psi"], p["th"])
        return np.einsum("...ij,...j->...i", c, a_path)

    def _gl(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """∫ velocity dt from a to b (…, 3): 8-point Gauss–Legendre."""
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        mid, half = 0.5 * (a + b), 0.5 * (b - a)
        v = self.velocity(mid[..., None] + half[..., None] * _GL_X)
        return half[..., None] * np.einsum("j,...jk->...k", _GL_W, v)

    def position(self, t: Any) -> np.ndarray:
        """Position (m, ENU) from ``position0``."""
        t = np.asarray(t, dtype=float)
        k = np.clip(np.searchsorted(self._knots, t, side="right") - 1, 0, len(self._knots) - 1)
        return self._pos_knots[k] + self._gl(self._knots[k], t)

    @property
    def default_duration(self) -> float | None:
        return self.total

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name, "vehicle": self.vehicle, "duration_s": self.total,
                "speed0_m_s": self.speed0, **self._extra}


def _along(psi: np.ndarray, th: np.ndarray) -> np.ndarray:
    """The body's forward axis in ENU: ``R_z(ψ) R_x(θ) ŷ``."""
    return np.stack([-np.sin(psi) * np.cos(th), np.cos(psi) * np.cos(th), np.sin(th)], axis=-1)


def _path_matrix(psi: np.ndarray, th: np.ndarray) -> np.ndarray:
    """``R_z(ψ) R_x(θ)`` (…, 3, 3)."""
    cz, sz, cx, sx = np.cos(psi), np.sin(psi), np.cos(th), np.sin(th)
    z = np.zeros_like(cz)
    return np.stack([np.stack([cz, -sz * cx, sz * sx], -1), np.stack([sz, cz * cx, -cz * sx], -1),
                     np.stack([z, sx, cx], -1)], -2)


def coordinated_rate(bank: float, speed: float, gravity: float = STANDARD_GRAVITY) -> float:
    """The turn rate ω (rad/s) of a level coordinated turn at ``bank`` (rad) and
    ``speed`` (m/s): ``ω = g tan φ / V``."""
    if not (speed > 0 and abs(bank) < math.pi / 2):
        raise InvalidArgument(f"a coordinated turn needs speed > 0 and |bank| < 90°, got {speed!r}, {bank!r}")
    return gravity * math.tan(bank) / speed


def _speed_change(dv: float, accel: float, ramp: float, **kw: Any) -> Leg:
    """The leg that changes the speed by exactly ``dv`` at ``|accel|`` (the next leg ramps it out)."""
    if dv == 0 or accel == 0:
        raise InvalidArgument(f"a speed change needs dv != 0 and accel != 0, got {dv!r}, {accel!r}")
    d = max(abs(dv / accel), ramp)
    return Leg(duration=d, accel=dv / d, ramp=ramp, **kw)


def _turn(angle: float, rate: float, ramp: float) -> Leg:
    """The leg that turns by exactly ``angle`` (rad; positive: left) at ``|rate|``."""
    d = abs(angle / rate)
    return Leg(duration=d, turn_rate=angle / d, ramp=min(ramp, d))


#: Presets and their parameters (every figure an ASSUMPTION of a plausible light
#: aircraft or car; the issue's acceptance cases are fixed-wing-turn, car-brake and
#: car-roundabout). Units: m/s, m/s², deg, s, m, g (9.80665 m/s²).
VEHICLE_PRESETS: dict[str, dict[str, float]] = {
    "fixed-wing": {"speed": 60.0, "bank": 30.0, "bank2": 45.0},
    "fixed-wing-turn": {"speed": 60.0, "bank": 30.0, "turn_time": 60.0, "lead": 10.0},
    "car": {"speed": 15.0, "radius": 20.0, "brake_g": 0.5},
    "car-brake": {"speed": 20.0, "brake_g": 0.5, "lead": 5.0},
    "car-roundabout": {"speed": 8.0, "radius": 20.0, "turns": 1.0, "lead": 5.0},
}


def fixed_wing(speed: float = 60.0, bank: float = 30.0, bank2: float = 45.0,
               gravity: float = STANDARD_GRAVITY) -> VehicleTrajectory:
    """A whole flight: 5 s at rest, take-off roll at 2.5 m/s² to 30 m/s, climb at 6°
    accelerating to 45 m/s, level-off and acceleration to ``speed``, a 360° left
    coordinated turn at ``bank`` (deg), 10 s level, a 360° right turn at ``bank2``,
    10 s level, a 40 s descent at −4° slowing to 45 m/s, 10 s level."""
    ramp, climb, desc = 2.0, math.radians(6.0), math.radians(-4.0)
    w1, w2 = (coordinated_rate(math.radians(b), speed, gravity) for b in (bank, bank2))
    legs = [Leg(5.0), _speed_change(30.0, 2.5, ramp),
            _speed_change(15.0, 1.0, ramp, climb=climb), Leg(30.0, climb=climb, ramp=ramp),
            _speed_change(speed - 45.0, 1.0, ramp), Leg(10.0, ramp=ramp),
            _turn(2 * math.pi, w1, 3.0), Leg(10.0, ramp=3.0), _turn(-2 * math.pi, w2, 3.0), Leg(10.0, ramp=3.0),
            Leg(40.0, accel=(45.0 - speed) / 40.0, climb=desc, ramp=ramp), Leg(10.0, ramp=ramp)]
    return VehicleTrajectory("fixed-wing", legs, "fixed-wing", gravity=gravity,
                             params={"speed_m_s": speed, "bank_deg": bank, "bank2_deg": bank2})


def fixed_wing_turn(speed: float = 60.0, bank: float = 30.0, turn_time: float = 60.0, lead: float = 10.0,
                    altitude: float = 300.0, gravity: float = STANDARD_GRAVITY) -> VehicleTrajectory:
    """Level flight at ``speed`` (m/s) and ``altitude`` (m) for ``lead`` s, a left
    coordinated turn held at ``bank`` (deg) for ``turn_time`` s (3 s roll-in and
    roll-out), ``lead`` s level: issue 30's 60 s turn at 30° and 60 m/s."""
    ramp = 3.0
    w = coordinated_rate(math.radians(bank), speed, gravity)
    legs = [Leg(max(lead, ramp), ramp=ramp), Leg(turn_time + ramp, turn_rate=w, ramp=ramp),
            Leg(max(lead, ramp), ramp=ramp)]
    return VehicleTrajectory("fixed-wing-turn", legs, "fixed-wing", speed0=speed, position0=(0, 0, altitude),
                             gravity=gravity, params={"speed_m_s": speed, "bank_deg": bank,
                                                      "turn_time_s": turn_time, "turn_rate_dps": math.degrees(w)})


def car_brake(speed: float = 20.0, brake_g: float = 0.5, lead: float = 5.0,
              gravity: float = STANDARD_GRAVITY) -> VehicleTrajectory:
    """At rest ``lead`` s, accelerate at 0.2 g to ``speed`` (m/s), cruise ``lead`` s,
    brake at ``brake_g`` (g; 0.3 s jerk ramps) to a stop, rest ``lead`` s: issue 30's
    braking at 0.5 g."""
    ramp = 0.3
    legs = [Leg(max(lead, ramp), ramp=ramp), _speed_change(speed, 0.2 * gravity, ramp),
            Leg(max(lead, ramp), ramp=ramp), _speed_change(-speed, brake_g * gravity, ramp),
            Leg(max(lead, ramp), ramp=ramp)]
    return VehicleTrajectory("car-brake", legs, "car", gravity=gravity,
                             params={"speed_m_s": speed, "brake_g": brake_g})


def car_roundabout(speed: float = 8.0, radius: float = 20.0, turns: float = 1.0, lead: float = 5.0,
                   gravity: float = STANDARD_GRAVITY) -> VehicleTrajectory:
    """Straight at ``speed`` (m/s) for ``lead`` s, ``turns`` × 360° counter-clockwise
    round a circle of ``radius`` (m) at constant speed (1 s steering ramps; lateral
    acceleration V²/R), straight ``lead`` s: issue 30's roundabout."""
    if not (radius > 0 and speed > 0):
        raise InvalidArgument(f"a roundabout needs radius > 0 m and speed > 0 m/s, got {radius!r}, {speed!r}")
    legs = [Leg(max(lead, 1.0)), _turn(2 * math.pi * turns, speed / radius, 1.0), Leg(max(lead, 1.0))]
    return VehicleTrajectory("car-roundabout", legs, "car", speed0=speed, gravity=gravity,
                             params={"speed_m_s": speed, "radius_m": radius, "turns": turns,
                                     "lateral_g": speed * speed / radius / gravity})


def car(speed: float = 15.0, radius: float = 20.0, brake_g: float = 0.5,
        gravity: float = STANDARD_GRAVITY) -> VehicleTrajectory:
    """A drive: 5 s at rest, accelerate at 0.25 g to ``speed``, 5 s straight, a
    roundabout (a full circle of ``radius`` m), 5 s straight, brake at ``brake_g`` to a
    stop, 5 s at rest."""
    ramp = 0.3
    legs = [Leg(5.0, ramp=ramp), _speed_change(speed, 0.25 * gravity, ramp), Leg(5.0, ramp=ramp),
            _turn(2 * math.pi, speed / radius, 1.0), Leg(5.0, ramp=1.0),
            _speed_change(-speed, brake_g * gravity, ramp), Leg(5.0, ramp=ramp)]
    return VehicleTrajectory("car", legs, "car", gravity=gravity,
                             params={"speed_m_s": speed, "radius_m": radius, "brake_g": brake_g})


#: Issue 30's acceptance cases as the simulator's options (``SimConfig.from_dict(case)``;
#: on the command line ``--trajectory fixed-wing-turn --gnss neo-m8n ...``): the 60 s
#: coordinated turn at 30° bank and 60 m/s, braking at 0.5 g, a roundabout, and a 30 s
#: GNSS outage in a turn (a 90 s turn held from 13 s to 103 s, no fix from 40 s to 70 s:
#: 33 s of turn left after the fix returns for the 10 s recovery).
ACCEPTANCE_CASES: dict[str, dict[str, Any]] = {
    "turn": {"trajectory": "fixed-wing-turn", "speed": 60.0, "bank": 30.0, "turn_time": 60.0, "gnss": "neo-m8n"},
    "brake": {"trajectory": "car-brake", "brake_g": 0.5, "gnss": "neo-m8n"},
    "roundabout": {"trajectory": "car-roundabout", "gnss": "neo-m8n"},
    "outage-in-turn": {"trajectory": "fixed-wing-turn", "speed": 60.0, "bank": 30.0, "turn_time": 90.0,
                       "gnss": "neo-m8n", "gnss_outage": [[40.0, 70.0]]},
}

_BUILDERS = {"fixed-wing": fixed_wing, "fixed-wing-turn": fixed_wing_turn, "car": car, "car-brake": car_brake,
             "car-roundabout": car_roundabout}


def vehicle_trajectory(kind: str, **kw: Any) -> VehicleTrajectory:
    """The preset ``kind`` (:data:`VEHICLE_PRESETS`) with its parameters overridden by ``kw``."""
    if kind not in _BUILDERS:
        raise InvalidArgument(f"vehicle trajectory must be one of {sorted(_BUILDERS)}, got {kind!r}")
    return _BUILDERS[kind](**kw)  # type: ignore[operator]
