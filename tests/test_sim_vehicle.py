"""Vehicle trajectories (attitude_c/sim/vehicle.py): attitude, rates, acceleration,
velocity and position consistent, checked by integrating them back; the coordinated
turn and the car's manoeuvres against their closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from attitude_c.reference import quat_conj, quat_multiply, quat_to_rotvec, rotvec_to_quat
from attitude_c.sim import SimConfig
from attitude_c.sim.catalog import make_trajectory
from attitude_c.sim.trajectory import STANDARD_GRAVITY
from attitude_c.sim.vehicle import VEHICLE_PRESETS, Leg, VehicleTrajectory, coordinated_rate

G = STANDARD_GRAVITY
KINDS = tuple(VEHICLE_PRESETS)


def _simpson(f, t: np.ndarray) -> np.ndarray:
    """Cumulative Simpson's rule of f (…, 3) over pairs of steps of t (every other node)."""
    h = t[1] - t[0]
    y = f(t)
    pair = h / 3 * (y[0:-2:2] + 4 * y[1:-1:2] + y[2::2])
    return np.concatenate([np.zeros((1, 3)), np.cumsum(pair, axis=0)])


@pytest.mark.parametrize("kind", KINDS)
def test_rates_integrated_back_reproduce_the_attitude(kind: str) -> None:
    tr = make_trajectory(kind)
    h = 0.01
    t = np.arange(0.0, tr.total + h / 2, h)
    q = tr.quat(t[0])
    # RK4 of dQ/dt = ½ Q ⊗ [0, ω] written as one rotation per step from the midpoint-rule
    # rotation vector with the 4th-order (Simpson) mean rate: the error per step is O(h⁵)
    w = tr.omega(np.stack([t[:-1], t[:-1] + h / 2, t[1:]], axis=-1))
    worst = 0.0
    for k in range(len(t) - 1):
        phi = h / 6 * (w[k, 0] + 4 * w[k, 1] + w[k, 2]) + h * h / 12 * np.cross(w[k, 0], w[k, 2])
        q = quat_multiply(q, rotvec_to_quat(phi))
        if k % 500 == 0 or k == len(t) - 2:
            worst = max(worst, float(np.linalg.norm(quat_to_rotvec(quat_multiply(quat_conj(tr.quat(t[k + 1])), q)))))
    # rates up to 0.16 rad/s over 10^4 steps of 10 ms: the Bortz/coning remainder is
    # ~ h³|ω|³/12 per step -> < 1e-9 rad in all
    assert worst < 1e-8


@pytest.mark.parametrize("kind", KINDS)
def test_acceleration_and_velocity_integrate_to_velocity_and_position(kind: str) -> None:
    tr = make_trajectory(kind)
    t = np.linspace(0.0, tr.total, 80001)
    dv = _simpson(tr.accel_nav, t)
    dp = _simpson(tr.velocity, t)
    v, p = tr.velocity(t[::2]), tr.position(t[::2])
    # Simpson with h <= 3.3 ms: where a ramp ends (a jump in the jerk's derivative) its
    # error is O(h³) per ramp, ~1e-8 m/s over the ~20 ramps; 1e-6 leaves room for rounding
    np.testing.assert_allclose(v - v[0], dv, atol=1e-6)
    np.testing.assert_allclose(p - p[0], dp, atol=1e-6)


@pytest.mark.parametrize(("kind", "bank", "kw"), [("fixed-wing-turn", 30.0, {}), ("fixed-wing-turn", 45.0, {}),
                                                  ("fixed-wing", 45.0, {"bank2": 45.0})])
def test_coordinated_turn_closed_form(kind: str, bank: float, kw: dict) -> None:
    tr = make_trajectory(kind, bank=bank, **kw)
    t = np.linspace(0.0, tr.total, 4001)
    f = tr.specific_force(t)
    # no lateral specific force anywhere (no sideslip): rounding of g-sized terms
    assert np.max(np.abs(f[:, 0])) < 1e-12 * G
    # at full bank (turn rate at its held value): tan φ = V ω / g, |f| = g / cos φ
    rate = np.abs(tr._path(t)["dpsi"])  # ψ̇
    full = np.abs(rate - rate.max()) < 1e-12
    assert full.sum() > 100
    v = tr.speed(t[full])
    expect = np.arctan(v * rate[full] / G)
    roll = tr.euler(t[full])[:, 2]
    np.testing.assert_allclose(np.abs(roll), expect, atol=1e-12)
    np.testing.assert_allclose(np.abs(roll), math.radians(bank), atol=1e-12)
    # a left turn (ψ̇ > 0) lowers the left wing: roll (right wing down positive) < 0
    np.testing.assert_array_equal(np.sign(roll), -np.sign(tr._path(t[full])["dpsi"]))
    np.testing.assert_allclose(np.linalg.norm(f[full], axis=1), G / math.cos(math.radians(bank)), rtol=1e-12)


def test_turn_preset_is_the_issues_case() -> None:
    tr = make_trajectory("fixed-wing-turn")
    t = np.linspace(0.0, tr.total, 8301)
    bank = -np.degrees(tr.euler(t)[:, 2])
    held = t[np.abs(bank - 30.0) < 1e-9]
    # 60 s held at 30° bank and 60 m/s (grid step 0.01 s)
    assert held[-1] - held[0] == pytest.approx(60.0, abs=0.011)
    np.testing.assert_allclose(tr.speed(t), 60.0, atol=1e-12)
    assert coordinated_rate(math.radians(30), 60.0) == pytest.approx(G * math.tan(math.radians(30)) / 60.0)


def test_car_braking_holds_the_deceleration_and_stops() -> None:
    tr = make_trajectory("car-brake", brake_g=0.5, speed=20.0)
    t = np.linspace(0.0, tr.total, 30001)
    a_along = np.einsum("ij,ij->i", tr.accel_nav(t), tr.velocity(t)) / np.maximum(tr.speed(t), 1e-9)
    assert np.min(a_along) == pytest.approx(-0.5 * G, rel=1e-12)
    assert tr.speed(tr.total) == pytest.approx(0.0, abs=1e-9)
    assert np.min(tr.speed(t)) > -1e-9
    # the car stays level: the specific force has no component the road's normal lacks
    np.testing.assert_allclose(tr.euler(t)[:, 1:], 0.0, atol=0)


def test_roundabout_is_a_constant_speed_circle() -> None:
    tr = make_trajectory("car-roundabout", speed=8.0, radius=20.0)
    t = np.linspace(0.0, tr.total, 5001)
    rate = tr._path(t)["dpsi"]
    full = np.abs(rate - 8.0 / 20.0) < 1e-12
    p = tr.position(t[full])[:, :2]
    # centre: 20 m left of the track at the first full-rate point
    yaw = tr.euler(t[full][0])[0]
    centre = p[0] + 20.0 * np.array([-math.cos(yaw), -math.sin(yaw)])
    np.testing.assert_allclose(np.linalg.norm(p - centre, axis=1), 20.0, atol=1e-6)  # quadrature: 1e-6 m
    f = tr.specific_force(t[full])
    np.testing.assert_allclose(f[:, 0], -8.0 ** 2 / 20.0, rtol=1e-12)  # V²/R to the left (−x)
    np.testing.assert_allclose(f[:, 2], G, rtol=1e-12)


def test_legs_are_checked() -> None:
    with pytest.raises(ValueError, match="ramp"):
        Leg(1.0, ramp=2.0)
    with pytest.raises(ValueError, match="below zero"):
        VehicleTrajectory("x", [Leg(5.0, accel=-1.0)], speed0=1.0)
    with pytest.raises(ValueError, match="level road"):
        VehicleTrajectory("x", [Leg(5.0, climb=0.1)], vehicle="car")


def test_options_build_the_vehicles() -> None:
    cfg = SimConfig.from_dict({"trajectory": "fixed-wing-turn", "bank": 45, "turn_time": 30})
    assert cfg.trajectory.params()["bank_deg"] == 45
    assert cfg.duration == pytest.approx(cfg.trajectory.total)
    with pytest.raises(ValueError, match="--bank does not apply"):
        SimConfig.from_dict({"trajectory": "car-brake", "bank": 30})
    with pytest.raises(ValueError, match="vehicle trajectories"):
        SimConfig.from_dict({"trajectory": "paper", "speed": 30})


def test_vehicle_figure(tmp_path) -> None:
    import matplotlib.image as mpimg

    from attitude_c.sim.report import draw_vehicle

    draw_vehicle(make_trajectory("car-roundabout"), tmp_path / "v.png", "roundabout")
    img = mpimg.imread(tmp_path / "v.png")
    assert img.shape[0] > 200 and img.shape[1] > 500 and img.std() > 0.05  # a drawn figure, not a blank page


@pytest.mark.parametrize("case", ["turn", "brake", "roundabout", "outage-in-turn"])
def test_acceptance_cases_build(case: str) -> None:
    from attitude_c.sim.vehicle import ACCEPTANCE_CASES

    cfg = SimConfig.from_dict(ACCEPTANCE_CASES[case])
    assert cfg.gnss is not None and cfg.gnss.model.name == "neo-m8n"
    tr = cfg.trajectory
    if case == "outage-in-turn":
        (a, b), = cfg.gnss.outages
        assert b - a == 30.0
        # the whole outage and the 10 s after it lie at full 30° bank
        t = np.linspace(a, b + 10.0, 401)
        np.testing.assert_allclose(tr.euler(t)[:, 2], -math.radians(30.0), atol=1e-12)


def test_help_gives_the_units() -> None:
    import argparse

    from attitude_c.sim.options import add_arguments

    p = argparse.ArgumentParser()
    add_arguments(p)
    text = " ".join(p.format_help().split())
    for phrase in ("speed (m/s)", "coordinated turn (deg", "full bank (s)", "deceleration (g = 9.80665 m/s²)",
                   "roundabout (m)", "fix rate (Hz, 1..10)", "delivery (s)", "DVE,DVN,DVU (m/s)"):
        assert phrase in text, phrase
