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

from . import reference as ref

F = NDArray[np.float64]

__all__ = [
    "align",
    "field_nav",
    "gauss_newton",
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
