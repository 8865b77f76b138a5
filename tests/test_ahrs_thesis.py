"""attitude_c.ahrs_thesis: the UAV thesis's EKF against its NumPy model and the truth.

Differential: the C filter (double) against attitude_c.reference.thesis_ekf
(the thesis's equations in matrix form, NumPy Gauss–Newton) on synthetic
motion and on a BROAD segment; the float build against the double build.
Truth: closed-form constant-rate motion and a static attitude (exact
sensors), where the filter must settle on the truth and learn the bias.
BROAD: the documented figures of docs/ahrs.md ("The thesis's EKF").
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import angle_deg, motion

import attitude_c
from attitude_c import broad
from attitude_c import reference as ref
from attitude_c.errors import InvalidArgument, InvalidType, NonFiniteError
from attitude_c.thesis_ekf import default_settings, run
from attitude_c.reference.thesis_ekf import thesis_ekf_reference


@pytest.mark.parametrize("kw,given_q0", [({}, False),
                                          ({"bias_noise": 1e-3, "meas_noise": 0.01, "declination": 0.1}, True)])
def test_c_matches_reference_synthetic(kw, given_q0):
    gyr, acc, mag, truth = motion(200, 100.0, (0.3, -0.2, 0.5), q0=ref.euler_to_quat([0.4, 0.2, -0.3]),
                                  bias=(0.01, -0.02, 0.005), noise=0.002)
    q0 = truth[0] if given_q0 else None  # given q0, or aligned on the first sample
    r = run(gyr, acc, mag, rate=100.0, q0=q0, **kw)
    qr, br, skipped = thesis_ekf_reference(gyr, acc, mag, 0.01, q0=q0, **kw)
    # the same recursion evaluated twice in double; the measurement is the
    # Gauss–Newton root, which both solvers reach to ~1e-15, and the
    # filter's feedback keeps rounding from growing: 1e-12 is ~1e4 ulp
    assert np.abs(r.q - qr).max() < 1e-12
    assert np.abs(r.bias - br).max() < 1e-12
    assert r.gn_skipped == skipped == 0


def test_c_matches_reference_on_broad_segment_and_f32():
    folder = broad.default_dir()
    if folder is None:
        pytest.skip("BROAD data not found beside the checkout (../shared/data/broad)")
    t = broad.load_trial(folder / "07_undisturbed_fast_rotation_B.mat")
    sl = slice(6000, 6250)  # fast rotation: large GN corrections every sample
    qc = attitude_c.ahrs_thesis(t.gyr[sl], t.acc[sl], t.mag[sl], rate=t.rate)
    qr = thesis_ekf_reference(t.gyr[sl], t.acc[sl], t.mag[sl], 1.0 / t.rate)[0]
    assert np.abs(qc - qr).max() < 1e-12  # as above
    qf = attitude_c.ahrs_thesis(t.gyr[sl], t.acc[sl], t.mag[sl], rate=t.rate, precision="f32")
    # float: ~1e-7 relative rounding per step in the state and in the
    # Gauss–Newton root (its float tolerance 2e-6), damped by the filter's
    # 5 s time constant: 1e-4 rad (0.006°) bounds it
    assert angle_deg(qf, qc).max() < np.degrees(1e-4)


def test_static_converges_to_truth():
    bias = np.array([0.01, -0.02, 0.015])  # rad/s
    gyr, acc, mag, truth = motion(6000, 100.0, (0.0, 0.0, 0.0), q0=ref.euler_to_quat([0.7, 0.2, -0.3]),
                                  bias=bias)
    q0 = ref.euler_to_quat([0.8, 0.3, -0.2])  # 0.1 rad off on each Euler angle
    r = run(gyr, acc, mag, rate=100.0, q0=q0)
    err = angle_deg(r.q, truth)
    # with the thesis's db/dt = 0 the bias variance falls like 1/t, so the
    # bias error decays like 1/t: after 60 s below 1 % of its size, and the
    # attitude lags by it × the 5 s time constant (≈ 1e-3 rad = 0.06°)
    assert np.abs(r.bias - bias).max() < 2e-4
    assert err[-1] < 0.06 and err[-1] < 0.01 * err[0]
    # gyro integration alone would have drifted |bias| · 60 s ≈ 1.6 rad


def test_turning_converges_to_truth():
    bias = np.array([0.008, -0.006, 0.004])
    gyr, acc, mag, truth = motion(6000, 100.0, (0.4, 0.3, -0.5), bias=bias)
    r = run(gyr, acc, mag, rate=100.0)
    err = angle_deg(r.q, truth)
    # exact sensors: the GN root is the truth every sample; 60 s of turning
    # with an unknown bias (36° of drift unaided): below 0.3° and falling
    assert err[-1] < 0.3 and err[-1] < 0.5 * err[1000]


def test_skipped_update_counted():
    gyr, acc, mag, _ = motion(50, 100.0, (0.0, 0.0, 0.0))
    mag[20:25] = acc[20:25]  # field parallel to gravity: the Gauss–Newton solve fails
    r = run(gyr, acc, mag, rate=100.0)
    assert r.gn_skipped == 5
    assert np.isfinite(r.q).all()


def test_errors():
    gyr, acc, mag, _ = motion(10, 100.0, (0.0, 0.0, 0.0))
    with pytest.raises(InvalidArgument, match="rate"):
        attitude_c.ahrs_thesis(gyr, acc, mag)
    with pytest.raises(InvalidArgument, match="unknown thesis-EKF setting"):
        attitude_c.ahrs_thesis(gyr, acc, mag, rate=100.0, gyro_noise=1.0)
    with pytest.raises(InvalidArgument, match="outside its domain"):
        attitude_c.ahrs_thesis(gyr, acc, mag, rate=100.0, meas_noise=0.0)
    with pytest.raises(InvalidType, match="meas_noise"):
        attitude_c.ahrs_thesis(gyr, acc, mag, rate=100.0, meas_noise="x")
    with pytest.raises(InvalidArgument, match="gn_max_iter"):
        attitude_c.ahrs_thesis(gyr, acc, mag, rate=100.0, gn_max_iter=0)
    with pytest.raises(InvalidArgument, match="mag"):
        attitude_c.ahrs_thesis(gyr, acc, mag[:5], rate=100.0)
    with pytest.raises(InvalidArgument, match="precision"):
        attitude_c.ahrs_thesis(gyr, acc, mag, rate=100.0, precision="f16")
    bad = gyr.copy()
    bad[3, 1] = np.nan
    with pytest.raises(NonFiniteError, match="gyr: sample 3"):
        attitude_c.ahrs_thesis(bad, acc, mag, rate=100.0)
    with pytest.raises(InvalidArgument, match="dt: sample 2"):
        attitude_c.ahrs_thesis(gyr, acc, mag, dt=np.r_[0.01, 0.01, 0.0, np.full(7, 0.01)])


def test_defaults_documented():
    d = default_settings()
    assert d == {"gyr_noise": 0.01, "bias_noise": 0.0, "meas_noise": 0.025, "init_q_sigma": 0.05,
                 "init_bias_sigma": 0.03, "declination": 0.0, "gn_max_iter": 20}
    from attitude_c.reference.thesis_ekf import _DEFAULTS
    assert {k: d[k] for k in _DEFAULTS} == _DEFAULTS
