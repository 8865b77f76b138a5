"""Rotation math: the C library (f64, f32) against the independent NumPy
reference, and the conventions of docs/conventions.md."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import attitude_c as ac
from attitude_c import reference as ref
from attitude_c.errors import InvalidArgument, InvalidType, NonFiniteError

PI = np.pi
# f64: results are a handful of roundings of O(1) values: 1e-12 leaves ~1e4 ulp of slack.
TOL64 = 1e-12
# f32: inputs are rounded to float32 (rel. 6e-8) and each result takes ~10-20
# float operations; 2e-6 is ~30 float32 ulps of an O(1) result.
TOL32 = 2e-6

finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
quats = arrays(np.float64, (4,), elements=st.floats(-2, 2, allow_nan=False)).filter(
    lambda q: np.linalg.norm(q) > 1e-3)
eulers = st.tuples(st.floats(-PI, PI), st.floats(-PI / 2, PI / 2), st.floats(-PI, PI)).map(np.array)
rotvecs = st.one_of(
    arrays(np.float64, (3,), elements=st.floats(-1e-6, 1e-6)),    # tiny
    arrays(np.float64, (3,), elements=st.floats(-0.3, 0.3)),      # around the series switch
    arrays(np.float64, (3,), elements=st.floats(-10, 10)),        # large, several turns
)
SETTINGS = settings(max_examples=60, deadline=None)


def same_attitude(a: np.ndarray, b: np.ndarray, tol: float) -> None:
    """q and -q are the same attitude."""
    a, b = np.asarray(a), np.asarray(b)
    d = np.minimum(np.abs(a - b).max(axis=-1), np.abs(a + b).max(axis=-1))
    assert np.all(d <= tol), d.max()


@SETTINGS
@given(quats, quats)
def test_multiply_conj_normalize(a: np.ndarray, b: np.ndarray) -> None:
    np.testing.assert_allclose(ac.quat_multiply(a, b), ref.quat_multiply(a, b), atol=TOL64 * 8)
    np.testing.assert_allclose(ac.quat_normalize(a), ref.quat_normalize(a), atol=TOL64)
    np.testing.assert_array_equal(ac.quat_conj(a), ref.quat_conj(a))
    np.testing.assert_allclose(ac.quat_multiply(a, b, precision="f32"), ref.quat_multiply(a, b),
                               atol=TOL32 * 8)  # |a|,|b| ≤ 4: products up to ~16 → scaled


@SETTINGS
@given(quats)
def test_quat_dcm_euler_against_reference(q: np.ndarray) -> None:
    C = ref.quat_to_dcm(q)
    np.testing.assert_allclose(ac.quat_to_dcm(q), C, atol=TOL64)
    same_attitude(ac.dcm_to_quat(C), ref.dcm_to_quat(C), TOL64)
    assert ac.dcm_to_quat(C)[0] >= 0
    e_ref = ref.quat_to_euler(q)
    e = ac.quat_to_euler(q)
    # ψ and γ divide matrix elements (rounding ~1e-16) by cos θ: the two
    # independent routes agree to ~1e-16/cos θ; 1e-12 + 1e-14/cos θ bounds it
    ct = float(np.hypot(C[0, 1], C[1, 1]))
    tol = 1e-12 + (1e-14 / ct if ct > ref.GIMBAL_COS["f64"] else 0.0)
    # angles compare modulo 2π (ψ, γ near ±π)
    np.testing.assert_allclose(np.angle(np.exp(1j * (e - e_ref))), 0, atol=tol)
    np.testing.assert_allclose(np.angle(np.exp(1j * (ac.dcm_to_euler(C) - e))), 0, atol=tol)
    np.testing.assert_allclose(np.angle(np.exp(1j * (ac.heading(q) - ref.heading(q)))), 0, atol=tol)
    np.testing.assert_allclose(ac.quat_to_dcm(q, precision="f32"), C, atol=TOL32)
    same_attitude(ac.dcm_to_quat(C, precision="f32"), ref.dcm_to_quat(C), TOL32)


@SETTINGS
@given(eulers)
def test_euler_against_reference(e: np.ndarray) -> None:
    np.testing.assert_allclose(ac.euler_to_dcm(e), ref.euler_to_dcm(e), atol=TOL64)
    np.testing.assert_allclose(ac.euler_to_quat(e), ref.euler_to_quat(e), atol=TOL64)
    np.testing.assert_allclose(ac.euler_to_dcm(e, precision="f32"), ref.euler_to_dcm(e), atol=TOL32)
    # round trip away from gimbal lock: asin-like conditioning of θ costs
    # 1/cos θ, so compare the matrices, which are always well conditioned
    C = ac.euler_to_dcm(e)
    np.testing.assert_allclose(ac.euler_to_dcm(ac.dcm_to_euler(C)), C, atol=1e-7)
    if abs(np.cos(e[1])) > 1e-3:
        back = ac.dcm_to_euler(C)
        np.testing.assert_allclose(np.angle(np.exp(1j * (back - e))), 0,
                                   atol=TOL64 / abs(np.cos(e[1])) * 1e3)
    h = ac.heading(C)
    assert 0 <= h < 2 * PI
    # same matrix on both sides: only atan2 rounding differs (and 0 vs 2π wrap)
    np.testing.assert_allclose(np.angle(np.exp(1j * (h - ref.heading(C)))), 0, atol=1e-12)


@SETTINGS
@given(rotvecs)
def test_rotvec_against_reference(phi: np.ndarray) -> None:
    np.testing.assert_allclose(ac.rotvec_to_quat(phi), ref.rotvec_to_quat(phi), atol=TOL64,
                               rtol=1e-14)
    q = ac.rotvec_to_quat(phi)
    np.testing.assert_allclose(ac.quat_to_rotvec(q), ref.quat_to_rotvec(q), atol=TOL64 * 10)
    # float32 q(Φ): argument rounding (rel. 6e-8 of |Φ| ≤ 17) plus ~10 operations
    np.testing.assert_allclose(ac.rotvec_to_quat(phi, precision="f32"), ref.rotvec_to_quat(phi),
                               atol=TOL32 * max(1.0, float(np.linalg.norm(phi))))


def test_tiny_rotation_vectors_keep_relative_accuracy() -> None:
    phi = np.array([1e-200, -3e-200, 2e-200])
    q = ac.rotvec_to_quat(phi)
    np.testing.assert_allclose(q[1:], phi / 2, rtol=1e-15)
    np.testing.assert_allclose(ac.quat_to_rotvec(q), phi, rtol=1e-15)
    assert q[0] == 1.0


def test_hand_written_matrices() -> None:
    # yaw +90° (counter-clockwise about up): body x (right) points north,
    # body y (forward) points west; heading = 270°.
    C = ac.euler_to_dcm([PI / 2, 0, 0])
    np.testing.assert_allclose(C, [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-16)
    assert ac.heading(C) == pytest.approx(3 * PI / 2, abs=1e-15)
    # pitch +30° (nose up): body y (forward) goes up
    c, s = np.cos(PI / 6), np.sin(PI / 6)
    np.testing.assert_allclose(ac.euler_to_dcm([0, PI / 6, 0]), [[1, 0, 0], [0, c, -s], [0, s, c]],
                               atol=1e-16)
    # roll +30° (right wing down): body x (right) goes down
    np.testing.assert_allclose(ac.euler_to_dcm([0, 0, PI / 6]), [[c, 0, s], [0, 1, 0], [-s, 0, c]],
                               atol=1e-16)
    # eq. (1) element by element for one quaternion
    q = np.array([0.5, 0.5, 0.5, 0.5])
    lam, p1, p2, p3 = q
    eq1 = [[lam**2 + p1**2 - p2**2 - p3**2, 2 * (p1 * p2 - lam * p3), 2 * (p1 * p3 + lam * p2)],
           [2 * (p1 * p2 + lam * p3), lam**2 - p1**2 + p2**2 - p3**2, 2 * (p2 * p3 - lam * p1)],
           [2 * (p1 * p3 - lam * p2), 2 * (p2 * p3 + lam * p1), lam**2 - p1**2 - p2**2 + p3**2]]
    np.testing.assert_allclose(ac.quat_to_dcm(q), eq1, atol=1e-16)
    # the quaternion rotates body vectors into the navigation frame
    v_b = np.array([0.3, -0.2, 0.9])
    v_n = ref.quat_multiply(ref.quat_multiply(q, np.r_[0, v_b]), ref.quat_conj(q))[1:]
    np.testing.assert_allclose(ac.quat_to_dcm(q) @ v_b, v_n, atol=1e-15)


@pytest.mark.parametrize("precision,tol", [("f64", TOL64), ("f32", TOL32)])
def test_identity_and_180_degree_rotations(precision: str, tol: float) -> None:
    qs = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1],
                   [0, 1 / np.sqrt(2), 1 / np.sqrt(2), 0], [0, 0.6, 0, 0.8]], dtype=float)
    C = ac.quat_to_dcm(qs, precision=precision)
    np.testing.assert_allclose(C, ref.quat_to_dcm(qs), atol=tol)
    same_attitude(ac.dcm_to_quat(C, precision=precision), qs, 4 * tol)
    phi = ac.quat_to_rotvec(qs[1:])
    np.testing.assert_allclose(np.linalg.norm(phi, axis=1), PI, atol=1e-12)


@pytest.mark.parametrize("pitch", [PI / 2, -PI / 2])
@pytest.mark.parametrize("precision", ["f64", "f32"])
def test_gimbal_lock_answer(pitch: float, precision: str) -> None:
    e = np.array([0.4, pitch, 0.3])
    C = ac.euler_to_dcm(e, precision=precision)
    got = ac.dcm_to_euler(C, precision=precision)
    assert np.all(np.isfinite(got))
    assert got[2] == 0.0  # documented: roll 0
    # yaw carries ψ + γ (θ = +90°) or ψ − γ (θ = −90°)
    want_yaw = 0.7 if pitch > 0 else 0.1
    tol = TOL32 * 10 if precision == "f32" else 1e-12
    assert got[0] == pytest.approx(want_yaw, abs=tol)
    assert got[1] == pytest.approx(pitch, abs=tol)
    np.testing.assert_allclose(ac.euler_to_dcm(got), C, atol=tol)
    np.testing.assert_allclose(got, ref.dcm_to_euler(C, precision), atol=tol)
    q = ac.euler_to_quat(e)
    np.testing.assert_allclose(ac.quat_to_euler(q), ref.quat_to_euler(q), atol=1e-12)
    assert np.isfinite(ac.heading(q))


def test_vectorized_shapes() -> None:
    rng = np.random.default_rng(3)
    q = rng.normal(size=(2, 5, 4))
    assert ac.quat_to_dcm(q).shape == (2, 5, 3, 3)
    assert ac.dcm_to_quat(ac.quat_to_dcm(q)).shape == (2, 5, 4)
    assert ac.quat_to_euler(q).shape == (2, 5, 3)
    assert ac.heading(q).shape == (2, 5)
    assert ac.heading(ac.quat_to_dcm(q)).shape == (2, 5)
    assert ac.euler_to_quat(np.zeros(3)).shape == (4,)
    assert ac.quat_to_dcm(np.zeros((0, 4))).shape == (0, 3, 3)
    assert ac.quat_multiply(q, [1, 0, 0, 0]).shape == (2, 5, 4)


def test_conversion_errors() -> None:
    q = np.ones((3, 4))
    q[2, 1] = np.nan
    with pytest.raises(NonFiniteError, match="sample 2") as ei:
        ac.quat_to_dcm(q)
    assert ei.value.index == 2
    with pytest.raises(InvalidArgument, match="zero quaternion"):
        ac.quat_to_euler([[1, 0, 0, 0], [0, 0, 0, 0]])
    with pytest.raises(InvalidArgument, match=r"\(\.\.\., 3, 3\)"):
        ac.dcm_to_quat(np.eye(4))
    with pytest.raises(InvalidArgument, match="quaternions"):
        ac.heading(np.zeros(5))
    with pytest.raises(InvalidType, match="e must hold real"):
        ac.euler_to_dcm(np.array([True, False, True]))
    with pytest.raises(InvalidArgument, match="precision"):
        ac.quat_to_dcm([1, 0, 0, 0], precision="fixed")
