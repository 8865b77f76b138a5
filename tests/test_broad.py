"""attitude_c.broad: the BROAD loader and the benchmark's error metric.

The metric is checked against closed forms (a pure heading error, a pure tilt, their
composition); the loader on the shipped trials (../shared/data/broad, BROAD:
Laidig et al., Data 6(7), 2021, doi:10.3390/data6070072).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from attitude_c import broad
from attitude_c.errors import InvalidArgument


def qaxis(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.r_[math.cos(angle / 2), math.sin(angle / 2) * axis]


def qmul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def test_metric_closed_forms():
    rng = np.random.default_rng(1)
    ref = np.array([qaxis(rng.normal(size=3), rng.uniform(0, math.pi)) for _ in range(50)])
    h, t = 0.2, 0.1
    # a heading error is a rotation about the navigation z axis applied on the left
    est_h = np.array([qmul(qaxis([0, 0, 1], h), r) for r in ref])
    tot, hd, inc = broad.error_angles(est_h, ref)
    np.testing.assert_allclose(tot, h, atol=1e-12)   # rounding of unit quaternions
    np.testing.assert_allclose(hd, h, atol=1e-12)
    # acos near 1 resolves only 2·acos(1 − ε) ≈ 2·√(2ε) ≈ 4e-8 per ulp ε = 2^-52 of the argument
    np.testing.assert_allclose(inc, 0, atol=1e-7)
    # an inclination error: rotation about a horizontal navigation axis
    est_t = np.array([qmul(qaxis([1, 0, 0], t), r) for r in ref])
    tot, hd, inc = broad.error_angles(est_t, ref)
    np.testing.assert_allclose(inc, t, atol=1e-12)
    np.testing.assert_allclose(hd, 0, atol=1e-12)
    # e = heading ⊗ inclination: the metric separates the two parts exactly
    est_b = np.array([qmul(qmul(qaxis([0, 0, 1], h), qaxis([0, 1, 0], t)), r) for r in ref])
    tot, hd, inc = broad.error_angles(est_b, ref)
    np.testing.assert_allclose(hd, h, atol=1e-12)
    np.testing.assert_allclose(inc, t, atol=1e-12)
    # sign and scale of either quaternion do not matter
    tot2, _, _ = broad.error_angles(-3.0 * est_b, ref)
    np.testing.assert_allclose(tot2, tot, atol=1e-12)


def test_errors_rms_and_mask():
    ref = np.tile([1.0, 0, 0, 0], (4, 1))
    est = np.array([qaxis([0, 0, 1], a) for a in (0.1, 0.2, 0.3, 0.4)])
    ref[3] = np.nan  # lost markers: left out
    f = broad.errors(est, ref, movement=[1, 1, 0, 1])
    assert f.samples == 2
    assert f.heading == pytest.approx(math.degrees(math.sqrt((0.1**2 + 0.2**2) / 2)), rel=1e-12)
    with pytest.raises(InvalidArgument, match="movement"):
        broad.errors(est, ref, movement=[1, 1])
    with pytest.raises(InvalidArgument, match="nothing to score"):
        broad.errors(est, ref, movement=[0, 0, 0, 0])


def test_load_shipped_trial():
    folder = broad.default_dir()
    if folder is None:
        pytest.skip("BROAD data not found beside the checkout (../shared/data/broad)")
    files = broad.find_trials(folder)
    assert len(files) == 15
    tr = broad.load_trial(files[0])
    assert tr.name.startswith("01_undisturbed")
    assert tr.rate == pytest.approx(285.714, abs=1e-3)
    assert tr.gyr.shape == tr.acc.shape == tr.mag.shape == (tr.n, 3)
    assert tr.quat.shape == (tr.n, 4) and tr.movement.shape == (tr.n,)
    assert not tr.disturbed and "undisturbed" in tr.groups
    # at rest the accelerometer reads gravity (m/s²) and the field is Earth-like (µT)
    still = slice(0, int(tr.rate))
    assert np.linalg.norm(tr.acc[still].mean(0)) == pytest.approx(9.81, abs=0.3)
    assert 20 < np.linalg.norm(tr.mag[still].mean(0)) < 80
    # the reference is unit where valid
    ok = np.isfinite(tr.quat).all(1)
    np.testing.assert_allclose(np.linalg.norm(tr.quat[ok], axis=1), 1, atol=1e-6)


def test_load_errors(tmp_path):
    with pytest.raises(InvalidArgument, match="no BROAD trial file"):
        broad.load_trial(tmp_path / "missing.mat")
    bad = tmp_path / "bad.mat"
    bad.write_bytes(b"not a mat file")
    with pytest.raises(InvalidArgument, match="not a readable MATLAB file"):
        broad.load_trial(bad)
