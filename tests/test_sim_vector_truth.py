"""The simulator's truth for the accelerometer and the magnetometer (issue 14):
specific force and the geomagnetic field in the body frame, and the new test
motions (static, turntable, level turn, the paper's motion with translation).

No compiled code: every check is against an independent path — the attitude
matrix written out from docs/conventions.md, finite differences, the
kinematics of a vector fixed in the navigation frame (``ṁ_b = −ω × m_b``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from attitude_c.errors import InvalidArgument
from attitude_c.reference import quat_angle
from attitude_c.reference import quat_multiply as quat_mul
from attitude_c.sim.catalog import make_trajectory
from attitude_c.sim.trajectory import (
    EARTH,
    ConingTrajectory,
    Environment,
    LevelTurnTrajectory,
    PaperTrajectory,
    StaticTrajectory,
    TurntableTrajectory,
)

G = 9.80665


def _dcm(q: np.ndarray) -> np.ndarray:
    """C_b^n written out from docs/conventions.md (not the reference's function)."""
    l, a, b, c = q
    return np.array([
        [l*l + a*a - b*b - c*c, 2*(a*b - l*c), 2*(a*c + l*b)],
        [2*(a*b + l*c), l*l - a*a + b*b - c*c, 2*(b*c - l*a)],
        [2*(a*c - l*b), 2*(b*c + l*a), l*l - a*a - b*b + c*c]])


TRAJ = [PaperTrajectory(), make_trajectory("paper-translation"), ConingTrajectory(), TurntableTrajectory(),
        LevelTurnTrajectory(), StaticTrajectory(euler0=(0.3, -0.2, 0.5))]


def test_environment_field_from_intensity_inclination_declination() -> None:
    env = Environment(field_ut=50.0, inclination=math.radians(60.0), declination=math.radians(10.0))
    m = env.field_nav
    assert np.isclose(np.linalg.norm(m), 50.0, rtol=1e-15)
    # inclination: the angle below the horizon (down = −z in ENU)
    assert np.isclose(math.degrees(math.atan2(-m[2], math.hypot(m[0], m[1]))), 60.0, rtol=1e-13)
    # declination: east of true north
    assert np.isclose(math.degrees(math.atan2(m[0], m[1])), 10.0, rtol=1e-13)
    np.testing.assert_array_equal(env.gravity_nav, [0.0, 0.0, -G])
    with pytest.raises(InvalidArgument):
        Environment(inclination=math.radians(91))
    with pytest.raises(InvalidArgument):
        Environment(field_ut=float("nan"))


def test_at_rest_the_accelerometer_reads_g_up_and_the_field_rotates_with_the_body() -> None:
    tr = StaticTrajectory()
    np.testing.assert_allclose(tr.specific_force(5.0), [0.0, 0.0, G], atol=1e-15)
    np.testing.assert_allclose(tr.mag_field(5.0), EARTH.field_nav, atol=1e-14)
    # nose up 90°: body forward is up, so +g on body y; roll 90° (right wing down):
    # body x points down, −g on body x
    up = StaticTrajectory(euler0=(0.0, math.pi / 2, 0.0))
    np.testing.assert_allclose(up.specific_force(0.0), [0.0, G, 0.0], atol=1e-14)
    rolled = StaticTrajectory(euler0=(0.0, 0.0, math.pi / 2))
    np.testing.assert_allclose(rolled.specific_force(0.0), [-G, 0.0, 0.0], atol=1e-14)


@pytest.mark.parametrize("tr", TRAJ, ids=lambda t: t.name)
def test_vectors_are_the_nav_vectors_in_the_body_frame(tr) -> None:
    """f_b = Cᵀ (a_n − g_n), m_b = Cᵀ m_n with C written out independently
    (agreement to rounding: 1e-13 of ~50 units)."""
    t = np.array([0.0, 0.37, 3.3, 11.9, 47.25])
    f, m = tr.specific_force(t), tr.mag_field(t)
    a = tr.accel_nav(t)
    for k, tk in enumerate(t):
        c = _dcm(tr.quat(tk))
        np.testing.assert_allclose(f[k], c.T @ (a[k] - EARTH.gravity_nav), atol=1e-13)
        np.testing.assert_allclose(m[k], c.T @ EARTH.field_nav, atol=1e-12)
        assert np.isclose(np.linalg.norm(m[k]), EARTH.field_ut, rtol=1e-14)


@pytest.mark.parametrize("tr", TRAJ, ids=lambda t: t.name)
def test_body_field_obeys_the_kinematics_of_a_fixed_vector(tr) -> None:
    """A vector fixed in the navigation frame seen from the body: ṁ_b = −ω × m_b.
    Central differences, δ = 1e-5 s: truncation δ²·|m⃛| ≈ 1e-10·50, rounding
    ≈ 1e-14·50/δ = 5e-8 µT/s; bound 1e-6 µT/s."""
    d = 1e-5
    for t in (0.5, 2.25, 9.7, 41.0):
        m = tr.mag_field(t)
        mdot = (tr.mag_field(t + d) - tr.mag_field(t - d)) / (2 * d)
        np.testing.assert_allclose(mdot, -np.cross(tr.omega(t), m), atol=1e-6)


def test_translation_is_consistent_with_position() -> None:
    """a_n is the second derivative of the position (central differences,
    δ = 1e-3 s: truncation δ²/12·|p⁗| ≈ 1e-7·9, rounding 1e-15·5/δ² = 5e-9; bound 1e-6)."""
    tr = make_trajectory("paper-translation")
    assert tr.name == "paper-translation"
    d = 1e-3
    for t in (0.2, 3.1, 17.0):
        acc = (tr.position(t + d) - 2 * tr.position(t) + tr.position(t - d)) / d ** 2
        np.testing.assert_allclose(acc, tr.accel_nav(t), atol=1e-6)
        vel = (tr.position(t + d) - tr.position(t - d)) / (2 * d)
        np.testing.assert_allclose(vel, tr.velocity(t), atol=1e-5)
    # the attitude part is the paper's motion, unchanged
    t = np.linspace(0, 20, 101)
    np.testing.assert_array_equal(tr.quat(t), PaperTrajectory().quat(t))
    # peak specific force within an ADXL202's ±2 g (the preset the translation is sized for)
    tt = np.linspace(0, 60, 6001)
    assert np.abs(tr.specific_force(tt)).max() < 2 * G


def test_period_means_are_the_mean_over_each_period() -> None:
    """Against composite Simpson on 2000 sub-steps (error ~1e-15 of the value)."""
    tr = make_trajectory("paper-translation")
    h = 0.08
    means = tr.period_means(tr.specific_force, 1.0, h, 10)
    for k in (0, 4, 9):
        tt = np.linspace(1.0 + k * h, 1.0 + (k + 1) * h, 2001)
        f = tr.specific_force(tt)
        simpson = (1 / 2000 / 3) * (f[0] + f[-1] + 4 * f[1:-1:2].sum(0) + 2 * f[2:-1:2].sum(0))
        np.testing.assert_allclose(means[k], simpson, atol=1e-13)


def test_level_turn_closed_form() -> None:
    tr = LevelTurnTrajectory()
    assert tr.turn_time == pytest.approx(72.0, rel=1e-15)  # 2 · 360° / (10 °/s)
    assert tr.default_duration == pytest.approx(92.0, rel=1e-15)
    # at rest before and after, same attitude at both ends (one full turn)
    np.testing.assert_array_equal(tr.omega(np.array([0.0, 9.99, 82.01, 92.0])), np.zeros((4, 3)))
    assert quat_angle(tr.quat(0.0), tr.quat(92.0)) < 1e-12
    assert tr.yaw(92.0) == pytest.approx(2 * math.pi, rel=1e-15)
    # peak rate at mid-turn; rate is the derivative of yaw (δ = 1e-5: error ~1e-10 rad/s)
    assert tr.omega(46.0)[2] == pytest.approx(math.radians(10.0), rel=1e-14)
    for t in (12.0, 30.0, 71.3):
        d = 1e-5
        assert (tr.yaw(t + d) - tr.yaw(t - d)) / (2 * d) == pytest.approx(tr.omega(t)[2], abs=1e-9)
    # exact increments add up to the whole turn; level all along
    inc = tr.increments(0.0, 0.08, 1150)
    assert inc[:, 2].sum() == pytest.approx(2 * math.pi, rel=1e-14)
    np.testing.assert_array_equal(inc[:, :2], 0.0)
    # the magnetic heading (from the field alone, level: atan2(−m_x, m_y) + D) is the true heading −ψ
    t = np.linspace(0, 92, 47)
    m = tr.mag_field(t)
    hdg = np.mod(np.arctan2(-m[:, 0], m[:, 1]) + EARTH.declination, 2 * math.pi)
    want = np.mod(-tr.yaw(t), 2 * math.pi)
    err = np.angle(np.exp(1j * (hdg - want)))
    assert np.abs(err).max() < 1e-13
    # clockwise, with RK4 at 100 Hz reproducing the attitude from the rates (kinematics)
    cw = LevelTurnTrajectory(turns=-0.5, rest=1.0, peak_rate=math.radians(30.0))
    q = cw.quat(0.0)
    h = 0.01
    for i in range(round(cw.default_duration / h)):
        t0 = i * h

        def f(q: np.ndarray, t: float) -> np.ndarray:
            return 0.5 * quat_mul(q, np.concatenate([[0.0], cw.omega(t)]))
        k1 = f(q, t0)
        k2 = f(q + h / 2 * k1, t0 + h / 2)
        k3 = f(q + h / 2 * k2, t0 + h / 2)
        k4 = f(q + h * k3, t0 + h)
        q = q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        q = q / np.linalg.norm(q)
    # RK4 local error O(h⁵ω⁽⁵⁾) on a 0.5 rad/s profile: ~1e-12 rad; bound 1e-9
    assert quat_angle(q, cw.quat(cw.default_duration)) < 1e-9
    assert cw.yaw(cw.default_duration) == pytest.approx(-math.pi, rel=1e-15)


def test_turntable_and_static_are_the_papers_tests() -> None:
    tt = TurntableTrajectory()
    assert tt.name == "turntable" and tt.default_duration == 360.0
    np.testing.assert_allclose(tt.omega(100.0), [0.0, 0.0, math.radians(5.0)], rtol=1e-15)
    # 360 s at 5 °/s: five full turns, back to the start attitude
    assert quat_angle(tt.quat(0.0), tt.quat(360.0)) < 1e-12
    np.testing.assert_allclose(tt.specific_force(123.0), [0.0, 0.0, G], atol=1e-14)
    assert StaticTrajectory().default_duration == 1800.0  # the MEMS AHRS paper's 30 minutes
    assert PaperTrajectory().default_duration is None
    with pytest.raises(InvalidArgument, match="body z"):
        TurntableTrajectory(rate=(0.1, 0.0, 0.1))
    with pytest.raises(InvalidArgument):
        LevelTurnTrajectory(turns=0)
    with pytest.raises(InvalidArgument, match="non-zero translation"):
        make_trajectory("paper-translation", translation=(0, 0, 0))
