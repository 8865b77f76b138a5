"""The simulator's truth: trajectories, body rates and exact increments.

These tests need no compiled code: they check the reference motions the
whole-system simulation judges the chain against.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from attitude_c.errors import InvalidArgument, NonFiniteError
from attitude_c.reference import euler_to_quat, quat_conj, quat_to_euler, rotvec_to_quat
from attitude_c.reference import quat_angle as quat_angle_between
from attitude_c.reference import quat_multiply as quat_mul
from attitude_c.sim.catalog import make_trajectory
from attitude_c.sim.trajectory import (
    ConingTrajectory,
    ConstantRateTrajectory,
    CsvTrajectory,
    PaperTrajectory,
    StaticTrajectory,
    euler_rates_to_body,
)


def _dcm(q: np.ndarray) -> np.ndarray:
    l, a, b, c = q
    return np.array([
        [l*l + a*a - b*b - c*c, 2*(a*b - l*c), 2*(a*c + l*b)],
        [2*(a*b + l*c), l*l - a*a + b*b - c*c, 2*(b*c - l*a)],
        [2*(a*c - l*b), 2*(b*c + l*a), l*l - a*a - b*b + c*c]])


def test_euler_quat_follow_conventions() -> None:
    # yaw 90° about up: body y (forward) points west in ENU
    q = euler_to_quat(np.array([math.pi / 2, 0.0, 0.0]))
    assert np.allclose(_dcm(q) @ [0, 1, 0], [-1, 0, 0], atol=1e-15)
    # pitch 90° (nose up): body forward points up
    q = euler_to_quat(np.array([0.0, math.pi / 2, 0.0]))
    assert np.allclose(_dcm(q) @ [0, 1, 0], [0, 0, 1], atol=1e-15)
    rng = np.random.default_rng(1)
    e = np.column_stack([rng.uniform(-3, 3, 100), rng.uniform(-1.5, 1.5, 100), rng.uniform(-3, 3, 100)])
    # round trip to rounding (1e-12: a few ulps through atan2/asin)
    assert np.allclose(quat_to_euler(euler_to_quat(e)), e, atol=1e-12)


def test_body_rates_match_the_matrix_derivative() -> None:
    """[ω×] = Cᵀ Ċ, with Ċ by central differences (error O(δ²) ≈ 1e-10)."""
    tr = PaperTrajectory()
    d = 1e-5
    for t in (0.3, 1.7, 12.9, 44.4):
        c = _dcm(tr.quat(t))
        cdot = (_dcm(tr.quat(t + d)) - _dcm(tr.quat(t - d))) / (2 * d)
        w = c.T @ cdot
        skew = np.array([w[2, 1], w[0, 2], w[1, 0]])
        assert np.allclose(skew, tr.omega(t), atol=1e-8)
        # and the kinematic formula itself on the given Euler rates
        assert np.allclose(euler_rates_to_body(tr.euler(t), tr.euler_dot(t)), tr.omega(t), atol=0)


def _rk4_attitude(tr, t_end: float, h: float) -> np.ndarray:
    q = tr.quat(tr.t_start)

    def f(q: np.ndarray, t: float) -> np.ndarray:
        return 0.5 * quat_mul(q, np.concatenate([[0.0], tr.omega(t)]))

    t = tr.t_start
    for _ in range(round((t_end - tr.t_start) / h)):
        k1 = f(q, t)
        k2 = f(q + h / 2 * k1, t + h / 2)
        k3 = f(q + h / 2 * k2, t + h / 2)
        k4 = f(q + h * k3, t + h)
        q = q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        q = q / np.linalg.norm(q)
        t += h
    return q


@pytest.mark.parametrize("tr", [PaperTrajectory(), ConingTrajectory(), ConstantRateTrajectory()],
                         ids=lambda t: t.name)
def test_rates_integrated_at_high_rate_reproduce_the_trajectory(tr) -> None:
    """RK4 at 200 Hz on dQ/dt = ½ Q ⊗ ω: its local error O(h⁵) gives ~1e-13 rad
    after 6 s on these ≤ 1.3 rad/s motions, so the 1e-9 bound tests the
    kinematics, not the integrator."""
    q = _rk4_attitude(tr, 6.0, 0.005)
    assert quat_angle_between(q, tr.quat(6.0)) < 1e-9


@pytest.mark.parametrize("tr", [PaperTrajectory(), ConingTrajectory(), ConstantRateTrajectory()],
                         ids=lambda t: t.name)
def test_exact_increments_are_the_integral_of_the_rate(tr) -> None:
    """Increments over 0.08 s against composite Simpson on 2000 sub-steps
    (error ~ h⁴·ω⁗ ≈ 1e-16 rad)."""
    inc = tr.increments(0.0, 0.08, 20)
    for k in (0, 7, 19):
        tt = np.linspace(k * 0.08, (k + 1) * 0.08, 2001)
        w = tr.omega(tt)
        simpson = (0.08 / 2000 / 3) * (w[0] + w[-1] + 4 * w[1:-1:2].sum(0) + 2 * w[2:-1:2].sum(0))
        assert np.allclose(inc[k], simpson, atol=1e-14)


def test_coning_closed_form() -> None:
    tr = ConingTrajectory(half_angle=math.radians(10), frequency=2.0)
    t = np.linspace(0, 3, 50)
    q = tr.quat(t)
    # the body z axis stays at the cone half-angle from up
    z_up = np.array([_dcm(qq)[2, 2] for qq in q])
    assert np.allclose(z_up, math.cos(math.radians(10)), atol=1e-15)
    # known classical result: |ω| is constant, ω_z = Ω(cos α − 1)
    w = tr.omega(t)
    assert np.allclose(w[:, 2], 4 * math.pi * (math.cos(math.radians(10)) - 1), atol=1e-15)


def test_csv_trajectory_is_exact_between_rows(tmp_path) -> None:
    src = PaperTrajectory()
    t = np.arange(0, 5.0001, 0.04)
    e = src.euler(t)
    p = tmp_path / "traj.csv"
    np.savetxt(p, np.column_stack([t, np.degrees(e)]), delimiter=",",
               header="time,yaw_deg,pitch_deg,roll_deg", comments="", fmt="%.15g")
    tr = CsvTrajectory(p)
    assert tr.t_start == 0.0 and tr.t_end == pytest.approx(5.0)
    # rows reproduced (savetxt keeps 15 digits: 1e-12)
    assert np.max(quat_angle_between(tr.quat(t), src.quat(t))) < 1e-12
    # the increments over one row spacing rotate row k into row k+1 exactly
    inc = tr.increments(0.0, 0.04, len(t) - 1)
    q_next = quat_mul(tr.q[:-1], rotvec_to_quat(inc))
    assert np.max(quat_angle_between(q_next, tr.q[1:])) < 1e-12
    # quaternion columns are accepted too
    p2 = tmp_path / "q.csv"
    np.savetxt(p2, np.column_stack([t, src.quat(t)]), delimiter=",", header="time,q0,q1,q2,q3",
               comments="", fmt="%.15g")
    tr2 = CsvTrajectory(p2)
    assert np.max(quat_angle_between(tr2.quat(t), src.quat(t))) < 1e-12
    d = quat_mul(quat_conj(tr2.quat(2.02)), src.quat(2.02))
    assert abs(d[0]) > 1 - 1e-6  # slerp midpoint close to the smooth truth


@pytest.mark.parametrize("text, match", [
    ("time,yaw,pitch\n0,0,0\n1,0,0\n", "time,yaw,pitch,roll"),
    ("time,yaw,pitch,roll\n0,0,0,0\n0,1,0,0\n", "strictly increasing"),
    ("time,yaw,pitch,roll\n0,0,0,0\n1,nan,0,0\n", "non-finite"),
    ("time,yaw,pitch,roll\n0,0,0,0\n1,x,0,0\n", "non-numeric"),
    ("yaw,pitch,roll\n0,0,0\n1,0,0\n", "no 'time' column"),
    ("time,q0,q1,q2,q3\n0,1,0,0,0\n1,2,0,0,0\n", "norm"),
])
def test_csv_trajectory_bad_files(tmp_path, text: str, match: str) -> None:
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(InvalidArgument, match=match):
        CsvTrajectory(p)
    with pytest.raises(InvalidArgument, match="cannot read"):
        CsvTrajectory(tmp_path / "missing.csv")


def test_trajectory_argument_errors() -> None:
    with pytest.raises(InvalidArgument, match="pitch"):
        PaperTrajectory(amplitude=(0.5, 1.6, 0.5))
    with pytest.raises(NonFiniteError, match="amplitude"):
        PaperTrajectory(amplitude=(0.5, float("nan"), 0.5))
    with pytest.raises(InvalidArgument, match="amplitude"):
        PaperTrajectory(amplitude=(0.5, 0.5))
    with pytest.raises(InvalidArgument, match="trajectory must be"):
        make_trajectory("spiral")
    with pytest.raises(InvalidArgument, match="half_angle"):
        ConingTrajectory(half_angle=-1.0)
    s = StaticTrajectory()
    assert np.all(s.increments(0, 0.1, 4) == 0)


def test_firmware_trajectory_truth() -> None:
    """The --firmware s51 motion: its closed form (no integrator) against RK4 on the
    rates at 200 Hz (RK4's error ~(ωdt)^4/120 per step: ~1e-12 rad over 6 s), its
    closed-form increments against the base class's Gauss-Legendre quadrature,
    and the gyro parameters it accepts."""
    from attitude_c.sim.trajectory import Trajectory
    from toolchain import firmware as tool
    from toolchain.firmware import FirmwareTrajectory

    tr = FirmwareTrajectory(period=0.08, rad_per_s_per_code=8.5e-4, duration=7.0)
    assert quat_angle_between(_rk4_attitude(tr, 6.0, 0.005), tr.quat(6.0)) < 1e-9
    assert quat_angle_between(_rk4_attitude(tr, 2.5, 0.005), tr.quat(2.5)) < 1e-9
    np.testing.assert_allclose(tr.increments(0.3, 0.08, 50), Trajectory.increments(tr, 0.3, 0.08, 50),
                               atol=1e-15)  # 8-node Gauss-Legendre is exact to rounding here
    # the model's sample k is the rate at the midpoint of period k
    k = 17
    want = [4096 * tool.Gyro(*g).fraction(k) - 2048 for g in tr.gyros]
    np.testing.assert_allclose(tr.omega((k + 0.5) * 0.08) / 8.5e-4, want, atol=1e-9)
    with pytest.raises(InvalidArgument, match="quadrature pair"):
        FirmwareTrajectory(gyros=((32768, 2, 0, 4), (32768, 2, 64, 5), (32768, 2, 128, 6)))
