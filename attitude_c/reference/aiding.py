"""NumPy reference of the aiding solvers (docs/aiding.md), written from the math.

Independent of the C code (csrc/src/aiding_*.c): the alignment goes through
Euler angles and the reference's rotation matrices, TRIAD through the
textbook two-triad product with an explicit reference field, the
Gauss–Newton solution through a plain undamped Newton iteration on the
residual of eq. 3.26–3.28 (with the east constraint) and ``numpy.linalg``;
the magnetometer fits through explicit design matrices and
``numpy.linalg.lstsq`` / ``eigh``. Conventions: docs/conventions.md (ENU,
body x right / y forward / z up, q scalar first body → nav, λ ≥ 0).

Everything is vectorized over leading axes: ``f``, ``m`` (..., 3).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import reference as ref

F = NDArray[np.float64]

__all__ = [
    "align",
    "field_nav",
    "gauss_newton",
    "magcal_apply",
    "magcal_fit",
    "magcal_minmax_2d",
    "triad",
]


def _unit(v: ArrayLike) -> F:
    a = np.asarray(v, dtype=np.float64)
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def field_nav(intensity: float, inclination: float, declination: float) -> F:
    """The Earth's field in ENU: horizontal part toward azimuth D (east of
    north), pointing down by the inclination I (north hemisphere I > 0)."""
    return intensity * np.array([np.sin(declination) * np.cos(inclination),
                                 np.cos(declination) * np.cos(inclination),
                                 -np.sin(inclination)])


def align(f: ArrayLike, m: ArrayLike | None, declination: float = 0.0) -> F:
    """Initial alignment: at rest f_b = Cᵀ [0, 0, g], so the third row of
    C = R_z(ψ) R_x(θ) R_y(γ), [−cθ sγ, sθ, cθ cγ], is f̂: θ = arcsin f̂_y,
    γ = arctan2(−f̂_x, f̂_z). The levelled field h = R_x(θ) R_y(γ) m equals
    R_z(ψ)ᵀ m_n; with m_n's horizontal part B_h [sin D, cos D],
    h_x = B_h sin(ψ + D), h_y = B_h cos(ψ + D): ψ = arctan2(h_x, h_y) − D."""
    fu = _unit(f)
    theta = np.arcsin(np.clip(fu[..., 1], -1.0, 1.0))
    gamma = np.arctan2(-fu[..., 0], fu[..., 2])
    if m is None:
        psi = np.zeros_like(theta)
    else:
        level = ref.euler_to_dcm(np.stack([np.zeros_like(theta), theta, gamma], axis=-1))
        h = np.einsum("...ij,...j->...i", level, np.asarray(m, dtype=np.float64))
        psi = np.arctan2(h[..., 0], h[..., 1]) - declination
    return ref.euler_to_quat(np.stack([psi, theta, gamma], axis=-1))


def _triad_frame(v1: F, v2: F) -> F:
    """Columns t1 = v̂1, t2 = (v1 × v2)/|·|, t3 = t1 × t2 (..., 3, 3)."""
    t1 = _unit(v1)
    t2 = _unit(np.cross(v1, v2))
    t3 = np.cross(t1, t2)
    return np.stack([t1, t2, t3], axis=-1)


def triad(f: ArrayLike, m: ArrayLike, declination: float = 0.0, inclination: float = 1.0) -> F:
    """TRIAD (Black 1964): C = [T1 T2 T3][t1 t2 t3]ᵀ with the triads of
    (up, field) in nav and (f, m) in body; the field's inclination drops out
    (any value in (−π/2, π/2) gives the same C)."""
    fb = np.asarray(f, dtype=np.float64)
    mb = np.asarray(m, dtype=np.float64)
    up = np.broadcast_to(np.array([0.0, 0.0, 1.0]), fb.shape)
    mn = np.broadcast_to(field_nav(1.0, inclination, declination), fb.shape)
    C = _triad_frame(up, mn) @ np.swapaxes(_triad_frame(fb, mb), -1, -2)
    return ref.dcm_to_quat(C)


def _residual(q: F, fu: F, mu: F) -> F:
    """[C(q)ᵀ e_z − f̂, e_xᵀ C(q) m̂] with C(q) = |q|² · (matrix of q/|q|)."""
    n2 = np.sum(q * q, axis=-1)[..., None, None]
    C = ref.quat_to_dcm(q) * n2
    r_acc = C[..., 2, :] - fu
    r_mag = np.einsum("...j,...j->...", C[..., 0, :], mu)
    return np.concatenate([r_acc, r_mag[..., None]], axis=-1)


def _jacobian(q: F, mu: F, h: float = 1e-6) -> F:
    """∂r/∂q by central differences of the exact quadratic residual: r is a
    quadratic form of q, so the central difference is exact up to rounding
    (no hand-derived derivative shared with the C code)."""
    fu0 = np.zeros(q.shape[:-1] + (3,))
    cols = []
    for k in range(4):
        e = np.zeros(4)
        e[k] = h
        cols.append((_residual(q + e, fu0, mu) - _residual(q - e, fu0, mu)) / (2 * h))
    return np.stack(cols, axis=-1)


def gauss_newton(f: ArrayLike, m: ArrayLike, q0: ArrayLike, declination: float = 0.0,
                 iterations: int = 30) -> tuple[F, NDArray[Any]]:
    """Newton's iteration on the four equations (3 specific-force rows and the
    field's east component, in the magnetic frame) from q0, renormalized each
    step, then the field-south root turned by π and the declination removed.
    Returns (q, converged) with converged = |r| < 1e-12 at the end."""
    fu = _unit(f)
    mu = _unit(m)
    qd = np.array([np.cos(declination / 2), 0.0, 0.0, np.sin(declination / 2)])
    x = ref.quat_multiply(np.broadcast_to(qd, np.shape(q0)), _unit(q0))
    for _ in range(iterations):
        r = _residual(x, fu, mu)
        J = _jacobian(x, mu)
        with np.errstate(all="ignore"):
            try:
                dx = np.linalg.solve(J, -r[..., None])[..., 0]
            except np.linalg.LinAlgError:
                dx = np.linalg.lstsq(J, -r, rcond=None)[0]
        good = np.all(np.isfinite(dx), axis=-1, keepdims=True)
        x = _unit(np.where(good, x + dx, x))
    ok = np.linalg.norm(_residual(x, fu, mu), axis=-1) < 1e-12
    C = ref.quat_to_dcm(x)
    north = np.einsum("...j,...j->...", C[..., 1, :], mu)
    flip = np.array([0.0, 0.0, 0.0, 1.0])
    x = np.where((north < 0)[..., None], ref.quat_multiply(np.broadcast_to(flip, x.shape), x), x)
    q = ref.quat_multiply(np.broadcast_to(ref.quat_conj(qd), x.shape), x)
    return np.where(q[..., :1] < 0, -q, q), ok


# ---------------------------------------------------------------------------
# magnetometer calibration
# ---------------------------------------------------------------------------

#: The fit's unknowns per model (columns of the design matrix below).
MAGCAL_COLUMNS = {"offset": (5, 6, 7, 8), "diagonal": (0, 1, 5, 6, 7, 8), "full": tuple(range(9))}


def _design(u: F) -> tuple[F, F]:
    """Design matrix of the trace-normalized quadric fit and its target:
    |u|² = v1 (x² + y² − 2z²) + v2 (x² + z² − 2y²) + 2 v3 xy + 2 v4 xz
           + 2 v5 yz + 2 v6 x + 2 v7 y + 2 v8 z + v9."""
    x, y, z = u[:, 0], u[:, 1], u[:, 2]
    D = np.stack([x * x + y * y - 2 * z * z, x * x + z * z - 2 * y * y, 2 * x * y, 2 * x * z, 2 * y * z,
                  2 * x, 2 * y, 2 * z, np.ones_like(x)], axis=1)
    return D, x * x + y * y + z * z


def magcal_fit(m: ArrayLike, model: str = "full") -> dict[str, Any]:
    """Least-squares ellipsoid (trace A = 3) of the samples m (N, 3), solved on
    the explicit design matrix with ``lstsq`` after centering on the mean and
    scaling by the RMS distance (the fit is invariant to both). The quadric
    uᵀAu + 2bᵀu + d = 0 has centre h = −A⁻¹b and (u − h)ᵀ A (u − h) = k with
    k = bᵀA⁻¹b − d; M = A/k, S = B M^½ (symmetric root), B = det(M)^(−1/6)
    (det S = 1). Returns h, S, field B, residual (RMS algebraic residual
    over 2k: ≈ RMS(|S(m − h)|/B − 1)) and span (√(λ_min/tr) of the samples'
    covariance)."""
    a = np.asarray(m, dtype=np.float64).reshape(-1, 3)
    mean = a.mean(axis=0)
    sc = float(np.sqrt(np.mean(np.sum((a - mean) ** 2, axis=1))))
    u = (a - mean) / sc
    D, t = _design(u)
    cols = list(MAGCAL_COLUMNS[model])
    sol, *_ = np.linalg.lstsq(D[:, cols], t, rcond=None)
    v = np.zeros(9)
    v[cols] = sol
    A = np.array([[1 - v[0] - v[1], -v[2], -v[3]],
                  [-v[2], 1 - v[0] + 2 * v[1], -v[4]],
                  [-v[3], -v[4], 1 + 2 * v[0] - v[1]]])
    b = -v[5:8]
    d = -v[8]
    hu = -np.linalg.solve(A, b)
    k = float(b @ np.linalg.solve(A, b) - d)
    lam, V = np.linalg.eigh(A / k)
    Bu = float(np.prod(lam) ** (-1 / 6))
    S = Bu * (V * np.sqrt(lam)) @ V.T
    e = t - D[:, cols] @ sol
    cov = np.cov(a.T, bias=True)
    ev = np.linalg.eigvalsh(cov)
    return {"h": mean + sc * hu, "S": S, "field": sc * Bu,
            "residual": float(np.sqrt(np.mean(e * e)) / (2 * k)),
            "span": float(np.sqrt(ev[0] / ev.sum())), "A": A / k}


def magcal_apply(m: ArrayLike, h: ArrayLike, S: ArrayLike) -> F:
    """m_cal = S (m − h), over leading axes."""
    return np.einsum("ij,...j->...i", np.asarray(S, dtype=np.float64),
                     np.asarray(m, dtype=np.float64) - np.asarray(h, dtype=np.float64))


def magcal_minmax_2d(m: ArrayLike) -> dict[str, Any]:
    """The 2-D min/max method: the mid-ranges of x and y are the offsets, the
    axis of the smaller range is scaled up to the larger one."""
    a = np.asarray(m, dtype=np.float64).reshape(-1, 3)
    lo, hi = a[:, :2].min(axis=0), a[:, :2].max(axis=0)
    rx, ry = hi - lo
    kx, ky = max(1.0, ry / rx), max(1.0, rx / ry)
    return {"h": np.array([(hi[0] + lo[0]) / 2, (hi[1] + lo[1]) / 2, 0.0]), "S": np.diag([kx, ky, 1.0]),
            "field": kx * rx / 2}
