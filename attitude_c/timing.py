"""Aiding-sensor time alignment: how long a body-frame vector's samples lag the gyro's.

An IMU whose magnetometer (or accelerometer) is sampled at another instant than
its gyro, or filtered with another group delay, delivers x(t − d) with the gyro's
ω(t). The attitude filter undoes a declared lag (``acc_delay``, ``mag_delay`` of
:func:`attitude_c.ahrs`, docs/ahrs.md "Sensor timing"); :func:`aiding_delay`
estimates it from a recording, without a reference attitude.

Principle. A vector fixed in the navigation frame, seen from the body, obeys
ẋ = −ω × x, so a sample that lags by d reads x(t − d) ≈ x(t) + d·ω × x. Rotated
into the navigation frame with the attitude C (body → ENU):

    C x_meas ≈ x_n + d · C (ω × x_meas),

a constant plus d times a signal the motion makes. After a high-pass (a centred
moving mean of ``window`` seconds removed from both sides, which also removes slow
attitude errors and slow field changes) d is the least-squares slope of the first
on the second over the selected samples.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._validate import real
from .core import _rows, quat_to_dcm
from .errors import InvalidArgument, InvalidType

__all__ = ["aiding_delay"]

F = NDArray[np.float64]


def _number(x: Any, name: str, unit: str) -> float:
    return real(x, name, unit, lo=0.0, lo_open=True)


def _highpass(v: F, half: int) -> F:
    """v minus its centred moving mean over 2·half + 1 samples (fewer at the ends)."""
    n = len(v)
    c = np.vstack([np.zeros((1, v.shape[1])), np.cumsum(v, axis=0)])
    i = np.arange(n)
    lo = np.maximum(i - half, 0)
    hi = np.minimum(i + half + 1, n)
    return v - (c[hi] - c[lo]) / (hi - lo)[:, None]


def aiding_delay(gyr: ArrayLike, vec: ArrayLike, q: ArrayLike, rate: float, *, window: float = 2.0,
                 mask: ArrayLike | None = None) -> float:
    """How long the samples of a body-frame aiding vector lag the gyro's (s).

    Parameters
    ----------
    gyr : (N, 3) angular rate, rad/s, body frame (bias-corrected if its bias is
        large: a bias b adds C (b × x) to the regressor).
    vec : (N, 3) the aiding vector in the body frame, any unit (a magnetometer).
    q : (N, 4) attitude, scalar first, body → ENU — e.g. ``attitude_c.ahrs``'s
        output on the same recording (only its high-passed part matters, which
        the gyro dominates; no reference attitude is needed).
    rate : sample rate, Hz.
    window : length of the high-pass moving mean, s (> 0, at least 3 samples).
    mask : optional (N,) bool, the samples to fit over (e.g. the movement phases);
        the high-pass runs over all samples first.

    Returns
    -------
    d in seconds: positive when ``vec`` lags the gyro — relative to the attitude ``q``.
    With a true attitude it is the physical lag. With the filter's own attitude it is
    the lag the filter should be told (pass it as ``mag_delay``): the filter takes ω_k
    as the mean rate over [t_k−1, t_k], so for point-sampled rates its attitude leads
    by dt/2 and the estimate reads d + dt/2 (synthetic, 100 Hz: 13 ms → 18.0 ms, and
    the filter scores best with 18 ms; tests/test_timing.py).

    Reliability. The model is a vector *fixed in the navigation frame*. It holds for
    a magnetometer in a homogeneous field: on the 15 BROAD trials the estimate from
    the filter's own attitude is 11.1–13.4 ms on the 9 undisturbed trials (8 of them
    within 12.5–13.4 ms; docs/ahrs.md, ``invoke bench --only broad_timing``). It fails where the field is
    not fixed: near a magnet moved with the sensor (BROAD trials 33/35: −6 and
    +18 ms). It is **not** usable for an accelerometer: the specific force holds the
    linear acceleration, and that correlates with the rotation (a hand-held or swung
    sensor accelerates as it turns), which biases the slope — on BROAD the same
    estimate for the accelerometer spreads over −31…+40 ms between trials, where a
    scan scored with the reference puts the lag near 5 ms. Declare an
    accelerometer's lag from its data sheet or its filter's group delay instead.

    Iterating. The attitude used here comes from a filter fed the lagged vector; its
    high-passed part follows the gyro, so one pass is usually enough. To check, re-run
    the filter with ``mag_delay=d`` and estimate again: the new estimate should agree
    (it measures the same lag, now through a better attitude).

    Raises
    ------
    InvalidType / InvalidArgument (naming the argument) for wrong types, shapes or
    values; NonFiniteError for NaN/Inf samples; InvalidArgument when the selected
    samples hold no rotation that would make the lag observable.
    """
    g = _rows(gyr, "gyr", 3, "angular rate")
    x = _rows(vec, "vec", 3, "aiding vector")
    qq = _rows(q, "q", 4, "quaternion")
    n = len(g)
    if len(x) != n or len(qq) != n:
        raise InvalidArgument(f"gyr, vec and q must have the same number of samples, got {n}, {len(x)}, {len(qq)}")
    r = _number(rate, "rate", "Hz")
    w = _number(window, "window", "s")
    half = round(w * r / 2)
    if half < 1:
        raise InvalidArgument(f"window must span at least 3 samples at {r:g} Hz, got {w:g} s")
    if np.any(np.linalg.norm(qq, axis=1) == 0):
        raise InvalidArgument("q: a zero quaternion")
    if mask is None:
        sel = np.ones(n, dtype=bool)
    else:
        m = np.asarray(mask)
        if m.dtype != np.bool_:
            raise InvalidType(f"mask must be a bool array, got dtype {m.dtype}")
        if m.shape != (n,):
            raise InvalidArgument(f"mask must have shape ({n},), got {m.shape}")
        sel = m
    C = quat_to_dcm(qq)  # C_b^n of q/|q| (docs/conventions.md eq. 1)
    xn = np.einsum("nij,nj->ni", C, x)
    yn = np.einsum("nij,nj->ni", C, np.cross(g, x))
    a = _highpass(xn, half)[sel]
    b = _highpass(yn, half)[sel]
    den = float(np.sum(b * b))
    scale = float(np.sum(x[sel] ** 2)) if sel.any() else 0.0
    # the regressor's energy relative to the vector's: below 1e-12 (rad/s)²·s² there is
    # no rotation to see the lag through (a still or uniformly turning record)
    if not sel.any() or den <= 1e-12 * scale:
        raise InvalidArgument("the selected samples hold no varying rotation: the lag is not observable "
                              "(give a recording with motion, or a mask selecting it)")
    return float(np.sum(a * b)) / den
