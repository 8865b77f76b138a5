"""The attitude filter's uncertainty (issue 32): covariance, heading observability, NEES tools.

Differential: the C filter's covariance and flags against attitude_c.reference.ahrs
(whose P is the full 6×6 matrix recursion written from docs/ahrs.md), sample by sample.
Closed forms: the error vector of a known rotation, the χ²(3) band against the printed
tables.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import M_N, motion

from attitude_c import names
from attitude_c import reference as ref
from attitude_c.ahrs_filter import Ahrs, ahrs
from attitude_c.reference.ahrs import ReferenceAhrs
from attitude_c.errors import InvalidType
from attitude_c.uncertainty import attitude_error, chi2_band, chi2_cdf3, coverage, nees

NO_HEADING = names.C["ATT_AHRS_F_NO_HEADING"]


def _reference_run(gyr, acc, mag, rate, **kw):
    f = ReferenceAhrs(**kw)
    cov, flags = [], []
    for i in range(len(gyr)):
        f.update(gyr[i], acc[i], None if mag is None else mag[i], 1.0 / rate)
        cov.append(f.covariance)
        flags.append(f.flags)
    return np.array(cov), flags, f


@pytest.mark.parametrize("nine_axis", [True, False])
def test_covariance_and_flags_match_reference(nine_axis):
    gyr, acc, mag, _ = motion(900, 100.0, (0.3, -0.2, 0.5), q0=ref.euler_to_quat([0.4, 0.2, -0.3]),
                              bias=(0.01, -0.02, 0.005), noise=0.002)
    m = mag if nine_axis else None
    # a tight bound: the flag changes within the record; mag_noise pinned at 0.05 (a 5 s heading
    # time constant) so heading σ reaches the bound inside these 9 s whatever the default. The
    # bound sits above σ_ψ's floor, tan(dip)·σ of the tilt about magnetic north (the heading
    # measurement's row, docs/ahrs.md): 2.0 × 0.020 rad with M_N's 63° dip and the default
    # acc_noise and gyr_noise, so σ_ψ settles near 0.041 rad
    kw = {"heading_sigma_max": 0.05, "mag_noise": 0.05}
    f = Ahrs(rate=100.0, **kw)
    q, cov = f.update(gyr, acc, m, covariance=True)
    cr, flags_r, r = _reference_run(gyr, acc, m, 100.0, **kw)
    # the same recursion in double (3×3 blocks vs full matrices): P ~ 1e-2 rad², kept to ~1e4 ulp
    assert np.abs(cov - cr).max() < 1e-14
    np.testing.assert_allclose(f.bias_covariance, r.bias_covariance, rtol=0, atol=1e-16)
    assert f.flags == flags_r[-1]
    np.testing.assert_array_equal(f.covariance, cov[-1])
    assert f.heading_sigma == pytest.approx(math.sqrt(cov[-1][2, 2]), rel=1e-15)
    if not nine_axis:
        assert all(fl & NO_HEADING for fl in flags_r) and not f.heading_observable
    else:  # unobservable while σ_ψ starts above 0.05 rad (init_att_sigma 0.1), then observable
        assert flags_r[0] & NO_HEADING and not flags_r[-1] & NO_HEADING and f.heading_observable


def test_turn_variance_closed_form():
    """turn_sigma: at a constant turn rate w the reported variance adds v with
    v_k = a v_(k−1) + (σ_t w)² dt, a = τ/(τ + dt): v_n = (σ_t w)² dt (1 − aⁿ)/(1 − a); the attitude
    itself is the same as with the term off (the gains use P alone)."""
    w = np.array([2.0, -1.0, 3.0])
    gyr, acc, mag, truth = motion(600, 100.0, tuple(w), noise=0.0)
    # the bias states off (zero prior, no random walk): their gains are 0, b stays 0 exactly
    kw = {"turn_sigma": 0.01, "turn_tau": 2.0, "init_bias_sigma": 0.0, "bias_noise": 0.0, "q0": truth[0]}
    q1, c1 = ahrs(gyr, acc, mag, rate=100.0, covariance=True, **kw)
    q0, c0 = ahrs(gyr, acc, mag, rate=100.0, covariance=True, **{**kw, "turn_sigma": 0.0})
    np.testing.assert_array_equal(q1, q0)
    a, u = 2.0 / 2.01, (0.01 * np.linalg.norm(w)) ** 2 * 0.01  # |ω − b| = |w|
    n = np.arange(1, 601)
    v = u * (1 - a ** n) / (1 - a)
    # the same recursion in double, 600 steps: ~1e-13 relative; the difference of two P's ~1e-2
    # rad² carries their rounding (1e-18 absolute)
    np.testing.assert_allclose(c1 - c0, v[:, None, None] * np.eye(3), rtol=1e-12, atol=1e-17)


def test_flags_per_sample_match_reference_through_rejection():
    """The field switched off for a while (six-axis samples): observable until the heading's
    σ passes the bound, then again after the field returns; C and model agree on every sample."""
    gyr, acc, mag, _ = motion(1500, 100.0, (0.0, 0.0, 0.4), noise=0.001)
    kw = {"heading_sigma_max": 0.05, "gyr_noise": 0.02, "mag_noise": 0.05}  # mag_noise: as above
    f = Ahrs(rate=100.0, **kw)
    flags_c = []
    for i in range(len(gyr)):
        f.update(gyr[i], acc[i], None if 400 <= i < 1100 else mag[i])
        flags_c.append(f.flags)
    r = ReferenceAhrs(**kw)
    flags_r = []
    for i in range(len(gyr)):
        r.update(gyr[i], acc[i], None if 400 <= i < 1100 else mag[i], 0.01)
        flags_r.append(r.flags)
    assert flags_c == flags_r
    lost = [bool(x & NO_HEADING) for x in flags_c]
    assert not lost[399] and lost[1099] and not lost[-1]  # observable, lost in the gap, back after


def test_float_covariance_near_double():
    gyr, acc, mag, _ = motion(600, 100.0, (0.6, -0.4, 1.0), noise=0.002)
    _, c64 = ahrs(gyr, acc, mag, rate=100.0, covariance=True)
    _, c32 = ahrs(gyr, acc, mag, rate=100.0, covariance=True, precision="f32")
    assert c32.dtype == np.float32
    # float carries ~6e-8 relative per operation; the Riccati recursion contracts: 1e-4 relative
    np.testing.assert_allclose(c32.astype(float), c64, rtol=0, atol=1e-4 * np.abs(c64).max())


def test_covariance_argument_type():
    gyr, acc, mag, _ = motion(10, 100.0, (0.0, 0.0, 0.1))
    with pytest.raises(InvalidType, match="covariance"):
        ahrs(gyr, acc, mag, rate=100.0, covariance="yes")  # type: ignore[call-overload]


def test_attitude_error_closed_form():
    rng = np.random.default_rng(3)
    q_est = ref.quat_normalize(rng.standard_normal((50, 4)))
    d = rng.uniform(-0.3, 0.3, (50, 3))
    q_true = ref.quat_multiply(ref.rotvec_to_quat(d), q_est)  # q_true = exp(δθ) ⊗ q_est
    np.testing.assert_allclose(attitude_error(q_est, q_true), d, rtol=0, atol=1e-12)
    np.testing.assert_allclose(attitude_error(q_est, -q_true), d, rtol=0, atol=1e-12)  # sign of q


def test_chi2_band_against_tables():
    lo, hi = chi2_band(0.95)
    # χ²(3) table values 0.2158 (2.5 %) and 9.3484 (97.5 %), to their printed digits
    assert lo == pytest.approx(0.2158, abs=5e-5) and hi == pytest.approx(9.3484, abs=5e-5)
    assert chi2_cdf3(7.8147) == pytest.approx(0.95, abs=5e-6)  # the 95 % one-sided table value


def test_nees_and_coverage_of_consistent_samples():
    """Errors drawn from the covariance itself: NEES mean 3, 3σ ellipsoid coverage 97.1 %."""
    rng = np.random.default_rng(5)
    a = rng.standard_normal((3, 3)) * 0.01
    P = a @ a.T + 1e-5 * np.eye(3)
    err = rng.multivariate_normal(np.zeros(3), P, size=200_000)
    cov = np.broadcast_to(P, (len(err), 3, 3))
    n = nees(err, cov)
    assert n.mean() == pytest.approx(3.0, abs=0.03)  # σ of the mean: √(6/200000) = 0.0055, ×5
    c = coverage(err, cov)
    assert c.ellipsoid == pytest.approx(c.expected_ellipsoid, abs=0.002)  # binomial σ 3.8e-4, ×5
    assert c.heading == pytest.approx(c.expected_heading, abs=0.001)  # binomial σ 1.2e-4, ×8


def _pulsing_field(n: int, rate: float, a: float, hold: int):
    """At rest, level, the field's norm alternating (1 ± a)·|M_N| every ``hold`` samples (its
    direction fixed): every sample agrees with the reference for a < mag_norm_tol."""
    gyr, acc, mag, truth = motion(n, rate, (0.0, 0.0, 0.0))
    mag = mag * (1 + a * (-1.0) ** (np.arange(n) // hold))[:, None]
    return gyr, acc, mag, truth


def test_field_spread_heading_term_matches_reference():
    """The heading's field term sample by sample, C against the model (docs/ahrs.md,
    "Uncertainty"), and the attitude it leaves as it was (reported only)."""
    gyr, acc, mag, truth = _pulsing_field(1500, 100.0, 0.03, 50)
    f = Ahrs(rate=100.0, q0=truth[0])
    q, cov = f.update(gyr, acc, mag, covariance=True)
    cr, flags_r, _ = _reference_run(gyr, acc, mag, 100.0, q0=truth[0])
    # the same recursions in double; the field term ~1e-2 rad², kept to ~1e4 ulp as above
    assert np.abs(cov - cr).max() < 1e-14
    assert f.flags == flags_r[-1]
    q_homog, c_homog = ahrs(gyr, acc, motion(1500, 100.0, (0.0, 0.0, 0.0))[2], rate=100.0, q0=truth[0],
                            covariance=True)
    # the norm is not used by the updates (only its agreement, and all agree): the same attitude
    np.testing.assert_array_equal(q, q_homog)
    assert cov[-1][2, 2] > c_homog[-1][2, 2]


def test_field_spread_heading_term_closed_form():
    """A norm alternating by ±a about its mean every h samples: the spread tends to a², its
    white part (half the mean squared step) to (2a)²/2 · 1/h, so the heading's field term to
    (a² − 2a²/h·(1 + 2√(dt/W)))/cos²(dip) (dip that of M_N); a norm alternating every sample (h = 1: white
    as far as the term can tell) gives no term."""
    a, rate, n, h = 0.04, 50.0, 15000, 100  # 300 s: ten times mag_ref_tau (30 s)
    dip = math.atan2(-M_N[2], math.hypot(M_N[0], M_N[1]))
    gyr, acc, mag, truth = _pulsing_field(n, rate, a, h)
    f = Ahrs(rate=rate, q0=truth[0])
    f.update(gyr, acc, mag)
    p_head = f.sigma[0][2] ** 2  # P's heading variance (att_ahrs_sigma: P alone)
    # the steps' weight in the 30 s mean depends on the phase: with 15 steps per 1500 samples, the
    # last one's share moves it by ±3 % of its 2/h (6e-4 relative); the reference ripples by
    # a·h/(4·1500) about the mean (its square 3e-4 relative of a²); the weighted mean forgets its
    # first samples as exp(−(300 − 30)/30) = 1.2e-4: 2e-3 relative covers them
    white = 2 * a * a / h * (1 + 2 * math.sqrt(1 / rate / 30.0))  # less its 2σ, W = 30 s
    assert f.covariance[2, 2] - p_head == pytest.approx((a * a - white) / math.cos(dip) ** 2, rel=2e-3)
    gyr, acc, mag, truth = _pulsing_field(n, rate, a, 1)
    f = Ahrs(rate=rate, q0=truth[0])
    f.update(gyr, acc, mag)
    assert f.covariance[2, 2] == pytest.approx(f.sigma[0][2] ** 2, rel=1e-14)  # √ then ²: a few ulp


@pytest.mark.parametrize("precision", ["f64", "f32"])
def test_a_tilt_about_magnetic_north_does_not_turn_the_heading(precision):
    """The field's heading taken in the estimate's frame measures δθz + tan(dip)·(δθ·u), u the
    horizontal field's direction (docs/ahrs.md, "Magnetometer"). One sample, the estimate tilted
    by ε about magnetic north and its heading right, the accelerometer trusted (its gain ≈ 1: it
    finds δθ·u = ε): the magnetometer's innovation y − h·x holds no heading error, so the
    heading is left as it was. With the row's tilt term left out (H = e_z) the heading would
    turn by K·tan(dip)·ε ≈ 2ε = 0.02 rad here."""
    eps = 0.01
    q_true = np.array([1.0, 0.0, 0.0, 0.0])
    q_est = ref.rotvec_to_quat(np.array([0.0, -eps, 0.0]))  # q_true = exp(ε e_north) ⊗ q_est
    gyr, acc, mag = np.zeros((1, 3)), np.array([[0.0, 0.0, 9.81]]), np.array([M_N])  # M_N: north, dip 63°
    q = ahrs(gyr, acc, mag, rate=100.0, precision=precision, q0=q_est, acc_noise=1e-6, mag_noise=1e-4,
             tilt_tau=0.0)
    e = attitude_error(q, q_true[None])[0]
    assert abs(e[1]) < 1e-6  # the tilt found: 1 − K_acc = R/(P + R) ≈ 1e-8
    # the row is first order in ε: for a tilt about north with M_N, y = atan(2 sin ε) and
    # h·x = 2ε cos ε/(1 + 4 sin²ε) differ by 6ε³ = 6e-6 rad, which the heading takes (K ≈ 1)
    assert abs(e[2]) < 1e-5
