"""How honest a reported attitude covariance is: the error vector, NEES and its band.

The attitude filter reports the covariance of δθ, the rotation vector about the
fixed ENU axes with q_true = exp(δθ) ⊗ q_est (``Ahrs.covariance``, docs/ahrs.md,
"Uncertainty"). Against a known truth:

* :func:`attitude_error` — δθ per sample (rad);
* :func:`nees` — the normalized estimation error squared δθᵀ P⁻¹ δθ, which for a
  consistent filter is χ² with 3 degrees of freedom;
* :func:`chi2_band` — the two-sided band holding a fraction ``p`` of that χ²(3),
  from its closed-form distribution function (no SciPy);
* :func:`coverage` — the fraction of samples inside the k-σ ellipsoid (NEES ≤ k²)
  and, for the heading alone, |δθ_z| ≤ k σ_z.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import reference as ref
from .errors import InvalidArgument

__all__ = ["Coverage", "attitude_error", "chi2_band", "chi2_cdf3", "coverage", "nees"]

FloatArray = NDArray[np.float64]


def attitude_error(q_est: ArrayLike, q_true: ArrayLike) -> FloatArray:
    """δθ (N, 3), rad: the ENU rotation vector with q_true = exp(δθ) ⊗ q_est, i.e.
    log(q_true ⊗ q_est⁻¹) (the shorter of the two rotations). Rows with a
    non-finite quaternion give NaN."""
    a = np.asarray(q_est, dtype=np.float64).reshape(-1, 4)
    b = np.asarray(q_true, dtype=np.float64).reshape(-1, 4)
    if a.shape != b.shape:
        raise InvalidArgument(f"q_est and q_true must have the same shape, got {a.shape} and {b.shape}")
    with np.errstate(invalid="ignore", divide="ignore"):
        a = a / np.linalg.norm(a, axis=1, keepdims=True)
        b = b / np.linalg.norm(b, axis=1, keepdims=True)
        e = ref.quat_multiply(b, ref.quat_conj(a))
        e = np.where(e[:, :1] < 0, -e, e)  # the shorter rotation
        return np.asarray(ref.quat_to_rotvec(e), dtype=np.float64)


def nees(err: ArrayLike, cov: ArrayLike) -> FloatArray:
    """δθᵀ P⁻¹ δθ per sample: err (N, 3), cov (N, 3, 3) → (N,)."""
    e = np.asarray(err, dtype=np.float64).reshape(-1, 3)
    p = np.asarray(cov, dtype=np.float64).reshape(-1, 3, 3)
    if len(e) != len(p):
        raise InvalidArgument(f"err and cov must have the same number of samples, got {len(e)} and {len(p)}")
    return np.einsum("ni,ni->n", e, np.linalg.solve(p, e[:, :, None])[:, :, 0])


def chi2_cdf3(x: float) -> float:
    """P(χ²₃ ≤ x) = erf(√(x/2)) − √(2x/π) e^(−x/2)."""
    if x <= 0:
        return 0.0
    return math.erf(math.sqrt(x / 2)) - math.sqrt(2 * x / math.pi) * math.exp(-x / 2)


def _quantile3(p: float) -> float:
    lo, hi = 0.0, 100.0  # P(χ²₃ ≤ 100) = 1 − 1e-20: every p < 1 − 1e-15 lies below
    for _ in range(200):  # bisection to the last bit
        mid = 0.5 * (lo + hi)
        if chi2_cdf3(mid) < p:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def chi2_band(p: float = 0.95) -> tuple[float, float]:
    """The two-sided band of χ²₃ holding the fraction p: its (1 − p)/2 and (1 + p)/2
    quantiles (0.2158, 9.348 for p = 0.95)."""
    if not 0 < p < 1:
        raise InvalidArgument(f"p must be in (0, 1), got {p}")
    return _quantile3((1 - p) / 2), _quantile3((1 + p) / 2)


@dataclass(frozen=True)
class Coverage:
    """Fractions of the samples judged (0..1) and what a consistent Gaussian gives."""

    ellipsoid: float          #: NEES ≤ k² (inside the k-σ ellipsoid)
    heading: float            #: |δθ_z| ≤ k·σ_z
    samples: int
    expected_ellipsoid: float  #: P(χ²₃ ≤ k²): 0.971 for k = 3
    expected_heading: float    #: P(|N(0,1)| ≤ k): 0.9973 for k = 3


def coverage(err: ArrayLike, cov: ArrayLike, k: float = 3.0, mask: ArrayLike | None = None) -> Coverage:
    """How often the true error lies within the reported k σ (rows with NaN left out)."""
    e = np.asarray(err, dtype=np.float64).reshape(-1, 3)
    p = np.asarray(cov, dtype=np.float64).reshape(-1, 3, 3)
    ok = np.isfinite(e).all(axis=1) & np.isfinite(p).all(axis=(1, 2))
    if mask is not None:
        ok &= np.asarray(mask, bool).ravel()
    if not ok.any():
        raise InvalidArgument("no sample with a finite error and covariance to judge")
    n = nees(e[ok], p[ok])
    head = np.abs(e[ok, 2]) <= k * np.sqrt(p[ok, 2, 2])
    return Coverage(float(np.mean(n <= k * k)), float(np.mean(head)), int(ok.sum()), chi2_cdf3(k * k),
                    math.erf(k / math.sqrt(2)))
