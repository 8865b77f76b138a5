"""Independent NumPy (float64) reference of the libattitude core.

Written from the mathematics (docs/conventions.md, docs/integrator.md),
not from the C source, and deliberately by different routes where one
exists:

* the attitude matrix from the vector form ``C = (λ² − p·p) I + 2 p pᵀ + 2 λ [p×]``
  (the C library expands eq. (1) element by element);
* matrix → quaternion from the eigenvector of Bar-Itzhack's symmetric
  4×4 matrix (the C library uses Shepperd's pivoting);
* Euler → matrix as the product of the three elementary rotations;
* q(Φ) through ``numpy.sinc`` (the C library uses a series below 0.2 rad);
* the coning-correction coefficients of rv2, rv3 and rv3-reuse are
  *derived* here at import time, in exact rational arithmetic, from the
  polynomial angular-rate models (Miller 1983), see :func:`fit_coefficients`;
* the integrator composes the update quaternions with an associative
  (parallel-prefix) product instead of a sequential loop; RK4 is the
  textbook k1…k4 scheme applied to the quaternion ODE.

Every function is vectorized over leading axes like its attitude_c.core
counterpart and returns float64.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:  # types only: the reference runs without the C library
    from .core import FloatPrecision, Method

__all__ = [
    "COEFFICIENTS",
    "GIMBAL_COS",
    "METHODS",
    "dcm_to_euler",
    "dcm_to_quat",
    "euler_to_dcm",
    "euler_to_quat",
    "fit_coefficients",
    "heading",
    "integrate",
    "integrate_rates",
    "quat_conj",
    "quat_multiply",
    "quat_normalize",
    "quat_to_dcm",
    "quat_to_euler",
    "quat_to_rotvec",
    "rotation_vectors",
    "rotvec_to_quat",
]

F = NDArray[np.float64]

METHODS = ("rv1", "rv2", "rv3", "rv3-coning", "rv3-reuse", "rk4")

#: Gimbal-lock threshold on cos θ (docs/integrator.md): sqrt(eps) of the build.
GIMBAL_COS = {"f64": 2.0 ** -26, "f32": 2.0 ** -12}


# ---------------------------------------------------------------------------
# coefficient derivation (exact)
# ---------------------------------------------------------------------------

def _coning_pair_integral(p: int, q: int, t0: Fraction, t1: Fraction) -> Fraction:
    """Coefficient of X_p × X_q (p < q) in ½ ∫_{t0}^{t1} α(t) × θ'(t) dt for
    θ(t) = Σ_k X_k t^k, α(t) = θ(t) − θ(t0)."""
    def integ(f_pow: int, coeff: Fraction) -> Fraction:  # ∫ coeff t^f_pow
        return coeff * (t1 ** (f_pow + 1) - t0 ** (f_pow + 1)) / (f_pow + 1)

    # (t^p − t0^p) q t^(q−1)  −  (t^q − t0^q) p t^(p−1)
    v = integ(p + q - 1, Fraction(q)) - t0 ** p * integ(q - 1, Fraction(q))
    v -= integ(p + q - 1, Fraction(p)) - t0 ** q * integ(p - 1, Fraction(p))
    return v / 2


def _solve(a: list[list[Fraction]], b: list[Fraction]) -> list[Fraction]:
    n = len(b)
    m = [row[:] + [bb] for row, bb in zip(a, b)]
    for c in range(n):
        piv = next(r for r in range(c, n) if m[r][c] != 0)
        m[c], m[piv] = m[piv], m[c]
        for r in range(n):
            if r != c and m[r][c] != 0:
                f = m[r][c] / m[c][c]
                m[r] = [x - f * y for x, y in zip(m[r], m[c])]
    return [m[i][n] / m[i][i] for i in range(n)]


def fit_coefficients(intervals: list[tuple[int, int]], target: tuple[int, int]) -> dict[tuple[int, int], Fraction]:
    """Cross-product coefficients k_ij (i < j, 0-based over ``intervals``) such
    that Σ k_ij Δθ_i × Δθ_j equals the second-order coning term
    ½ ∫ α × ω dt over ``target`` exactly whenever the angle θ(t) is a
    polynomial of degree len(intervals) (rate of degree len − 1).

    Intervals are in units of the sample interval; e.g. rv3 is
    ``fit_coefficients([(0, 1), (1, 2), (2, 3)], (0, 3))`` → 57/80, 33/80, 57/80.
    """
    n = len(intervals)
    degs = list(range(1, n + 1))           # θ(t) = Σ X_k t^k, k = 1..n
    basis = [(p, q) for i, p in enumerate(degs) for q in degs[i + 1:]]
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]

    def inc(k: int, iv: tuple[int, int]) -> Fraction:  # coefficient of X_k in Δθ over iv
        return Fraction(iv[1]) ** k - Fraction(iv[0]) ** k

    rows = []
    for (p, q) in basis:  # coefficient of X_p × X_q in Δθ_i × Δθ_j
        rows.append([inc(p, intervals[i]) * inc(q, intervals[j])
                     - inc(q, intervals[i]) * inc(p, intervals[j]) for (i, j) in pairs])
    rhs = [_coning_pair_integral(p, q, Fraction(target[0]), Fraction(target[1]))
           for (p, q) in basis]
    sol = _solve(rows, rhs)
    return dict(zip(pairs, sol))


def _derive() -> dict[str, tuple[Fraction, Fraction, Fraction]]:
    rv2 = fit_coefficients([(0, 1), (1, 2)], (0, 2))
    rv3 = fit_coefficients([(0, 1), (1, 2), (2, 3)], (0, 3))
    reuse = fit_coefficients([(-2, -1), (-1, 0), (0, 1)], (0, 1))
    reuse_start = fit_coefficients([(-1, 0), (0, 1)], (0, 1))
    z = Fraction(0)
    return {
        "rv1": (z, z, z),
        "rv2": (rv2[(0, 1)], z, z),
        "rv3": (rv3[(0, 1)], rv3[(0, 2)], rv3[(1, 2)]),
        # Ignagni (1990): the coefficients that minimize the classical-coning
        # drift of the three-sample form (not a polynomial fit).
        "rv3-coning": (Fraction(27, 40), Fraction(9, 20), Fraction(27, 40)),
        "rv3-reuse": (reuse[(0, 1)], reuse[(0, 2)], reuse[(1, 2)]),
        "rv3-reuse-start": (reuse_start[(0, 1)], z, z),
    }


#: (k12, k13, k23) per method, exact fractions (rv2: k12 only).
COEFFICIENTS: dict[str, tuple[Fraction, Fraction, Fraction]] = _derive()


# ---------------------------------------------------------------------------
# quaternion / matrix / Euler
# ---------------------------------------------------------------------------

def _arr(x: ArrayLike, tail: tuple[int, ...]) -> F:
    a = np.asarray(x, dtype=np.float64)
    if a.shape[a.ndim - len(tail):] != tail:
        raise ValueError(f"expected shape (..., {', '.join(map(str, tail))}), got {a.shape}")
    return a


def quat_multiply(a: ArrayLike, b: ArrayLike) -> F:
    """Hamilton product [a0 b0 − a·b, a0 b + b0 a + a × b]."""
    qa, qb = _arr(a, (4,)), _arr(b, (4,))
    a0, av = qa[..., :1], qa[..., 1:]
    b0, bv = qb[..., :1], qb[..., 1:]
    s = a0 * b0 - np.sum(av * bv, axis=-1, keepdims=True)
    v = a0 * bv + b0 * av + np.cross(av, bv)
    return np.concatenate([s, v], axis=-1)


def quat_conj(q: ArrayLike) -> F:
    return _arr(q, (4,)) * np.array([1.0, -1.0, -1.0, -1.0])


def quat_normalize(q: ArrayLike) -> F:
    a = _arr(q, (4,))
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def quat_to_dcm(q: ArrayLike) -> F:
    """C = (λ² − p·p) I + 2 p pᵀ + 2 λ [p×] for the unit q/|q|."""
    u = quat_normalize(q)
    lam, p = u[..., 0], u[..., 1:]
    eye = np.eye(3)
    px = np.zeros(p.shape[:-1] + (3, 3))
    px[..., 0, 1], px[..., 0, 2] = -p[..., 2], p[..., 1]
    px[..., 1, 0], px[..., 1, 2] = p[..., 2], -p[..., 0]
    px[..., 2, 0], px[..., 2, 1] = -p[..., 1], p[..., 0]
    s = (lam ** 2 - np.sum(p * p, axis=-1))[..., None, None]
    return s * eye + 2.0 * p[..., :, None] * p[..., None, :] + 2.0 * lam[..., None, None] * px


def dcm_to_quat(C: ArrayLike) -> F:
    """Eigenvector of Bar-Itzhack's K (largest eigenvalue), λ ≥ 0."""
    m = _arr(C, (3, 3))
    c = lambda i, j: m[..., i - 1, j - 1]  # 1-based like the docs
    K = np.empty(m.shape[:-2] + (4, 4))
    K[..., 0, 0] = c(1, 1) + c(2, 2) + c(3, 3)
    K[..., 1, 1] = c(1, 1) - c(2, 2) - c(3, 3)
    K[..., 2, 2] = -c(1, 1) + c(2, 2) - c(3, 3)
    K[..., 3, 3] = -c(1, 1) - c(2, 2) + c(3, 3)
    K[..., 0, 1] = K[..., 1, 0] = c(3, 2) - c(2, 3)
    K[..., 0, 2] = K[..., 2, 0] = c(1, 3) - c(3, 1)
    K[..., 0, 3] = K[..., 3, 0] = c(2, 1) - c(1, 2)
    K[..., 1, 2] = K[..., 2, 1] = c(1, 2) + c(2, 1)
    K[..., 1, 3] = K[..., 3, 1] = c(1, 3) + c(3, 1)
    K[..., 2, 3] = K[..., 3, 2] = c(2, 3) + c(3, 2)
    _, vec = np.linalg.eigh(K / 3.0)
    q = vec[..., :, -1]
    return np.where(q[..., :1] < 0, -q, q)


def _wrap(a: F) -> F:
    return np.where(a <= -np.pi, np.pi, a)


def dcm_to_euler(C: ArrayLike, precision: FloatPrecision = "f64") -> F:
    """[ψ, θ, γ] with the gimbal-lock rule (γ = 0, ψ = atan2(C21, C11))."""
    m = _arr(C, (3, 3))
    c12, c22 = m[..., 0, 1], m[..., 1, 1]
    ct = np.hypot(c12, c22)
    theta = np.arctan2(m[..., 2, 1], ct)
    lock = ct < GIMBAL_COS[precision]
    psi = np.where(lock, np.arctan2(m[..., 1, 0], m[..., 0, 0]), np.arctan2(-c12, c22))
    gamma = np.where(lock, 0.0, np.arctan2(-m[..., 2, 0], m[..., 2, 2]))
    return np.stack([_wrap(psi), theta, _wrap(gamma)], axis=-1)


def _rot(axis: int, ang: F) -> F:
    c, s = np.cos(ang), np.sin(ang)
    R = np.zeros(ang.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]  # plane rotated by the axis
    R[..., axis, axis] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    return R


def euler_to_dcm(e: ArrayLike) -> F:
    """R_z(ψ) R_x(θ) R_y(γ)."""
    a = _arr(e, (3,))
    return _rot(2, a[..., 0]) @ _rot(0, a[..., 1]) @ _rot(1, a[..., 2])


def quat_to_euler(q: ArrayLike, precision: FloatPrecision = "f64") -> F:
    return dcm_to_euler(quat_to_dcm(q), precision)


def euler_to_quat(e: ArrayLike) -> F:
    a = _arr(e, (3,))

    def axis_q(axis: int, ang: F) -> F:
        q = np.zeros(ang.shape + (4,))
        q[..., 0] = np.cos(ang / 2)
        q[..., 1 + axis] = np.sin(ang / 2)
        return q

    q = quat_multiply(quat_multiply(axis_q(2, a[..., 0]), axis_q(0, a[..., 1])), axis_q(1, a[..., 2]))
    return np.where(q[..., :1] < 0, -q, q)


def heading(x: ArrayLike, precision: FloatPrecision = "f64") -> F:
    a = np.asarray(x, dtype=np.float64)
    psi = (quat_to_euler(a, precision) if a.shape[-1] == 4 else dcm_to_euler(a, precision))[..., 0]
    h = np.mod(-psi, 2 * np.pi)
    return np.where(h >= 2 * np.pi, 0.0, h)


def rotvec_to_quat(phi: ArrayLike) -> F:
    """[cos(φ/2), sin(φ/2)/φ Φ] with sin(φ/2)/φ = ½ sinc(φ/2π)."""
    p = _arr(phi, (3,))
    n = np.linalg.norm(p, axis=-1, keepdims=True)
    return np.concatenate([np.cos(n / 2), 0.5 * np.sinc(n / (2 * np.pi)) * p], axis=-1)


def quat_to_rotvec(q: ArrayLike) -> F:
    u = quat_normalize(q)
    u = np.where(u[..., :1] < 0, -u, u)
    v = np.linalg.norm(u[..., 1:], axis=-1, keepdims=True)
    half = np.arctan2(v, u[..., :1])
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.where(v > 0, 2 * half / np.where(v > 0, v, 1.0), 2.0)
    return k * u[..., 1:]


# ---------------------------------------------------------------------------
# integrator
# ---------------------------------------------------------------------------

FRAME = {"rv1": 1, "rv2": 2, "rv3": 3, "rv3-coning": 3, "rv3-reuse": 1}


def rotation_vectors(dtheta: ArrayLike, method: Method) -> F:
    """Φ of every update of ``method`` (M, 3) from increments (N, 3)."""
    d = np.asarray(dtheta, dtype=np.float64).reshape(-1, 3)
    k = [float(x) for x in COEFFICIENTS[method]]
    if method == "rv3-reuse":
        z = np.zeros((2, 3))
        pad = np.concatenate([z, d])
        a, b, c = pad[:-2], pad[1:-1], d  # Δθ_{k−2}, Δθ_{k−1}, Δθ_k (zeros before the start)
        phi = c + k[0] * np.cross(a, b) + k[1] * np.cross(a, c) + k[2] * np.cross(b, c)
        if len(d) >= 2:  # second update: one previous increment, linear-rate fit
            ks = float(COEFFICIENTS["rv3-reuse-start"][0])
            phi[1] = d[1] + ks * np.cross(d[0], d[1])
        return phi
    m = FRAME[method]
    n = (len(d) // m) * m
    g = d[:n].reshape(-1, m, 3)
    phi = g.sum(axis=1)
    if m == 2:
        phi = phi + k[0] * np.cross(g[:, 0], g[:, 1])
    elif m == 3:
        phi = (phi + k[0] * np.cross(g[:, 0], g[:, 1]) + k[1] * np.cross(g[:, 0], g[:, 2])
               + k[2] * np.cross(g[:, 1], g[:, 2]))
    return phi


def _prefix_product(q0: F, steps: F) -> F:
    """Q_k = q0 ⊗ s_1 ⊗ … ⊗ s_k for every k (Hillis–Steele scan, log2(M) passes)."""
    acc = steps.copy()
    k = 1
    while k < len(acc):
        acc[k:] = quat_multiply(acc[:-k], acc[k:])
        k *= 2
    return quat_normalize(quat_multiply(q0, acc))


def integrate(dtheta: ArrayLike, method: Method = "rv3", q0: ArrayLike | None = None) -> F:
    """Attitude after each update, (M, 4); same output semantics as the C batch."""
    if method not in FRAME:
        raise ValueError(f"unknown increment method {method!r}")
    q = np.array([1.0, 0, 0, 0]) if q0 is None else quat_normalize(q0)
    steps = rotvec_to_quat(rotation_vectors(dtheta, method))
    return _prefix_product(q, steps)


def _rk4_step_quats(w0: F, wm: F, w1: F, h: F) -> F:
    """RK4 on q' = ½ q ⊗ [0, ω] over one step, started from q = 1 (the step
    is linear in q, so Q_new = Q ⊗ result)."""
    def f(q: F, w: F) -> F:
        return 0.5 * quat_multiply(q, np.concatenate([np.zeros(w.shape[:-1] + (1,)), w], axis=-1))

    one = np.zeros(w0.shape[:-1] + (4,))
    one[..., 0] = 1.0
    hh = h[:, None]
    k1 = f(one, w0)
    k2 = f(one + hh / 2 * k1, wm)
    k3 = f(one + hh / 2 * k2, wm)
    k4 = f(one + hh * k3, w1)
    return one + hh / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def integrate_rates(omega: ArrayLike, dt: ArrayLike, method: Method = "rk4",
                    q0: ArrayLike | None = None) -> F:
    """Rates (N, 3) every dt (scalar or (N,)). rk4: rows t, t+h/2, t+h, …,
    h = dt[2k] + dt[2k+1]; others: Δθ_i = ω_i dt_i."""
    w = np.asarray(omega, dtype=np.float64).reshape(-1, 3)
    d = np.broadcast_to(np.asarray(dt, dtype=np.float64), (len(w),))
    if method != "rk4":
        return integrate(w * d[:, None], method, q0)
    m = (len(w) - 1) // 2
    h = d[0:2 * m:2] + d[1:2 * m:2]
    steps = _rk4_step_quats(w[0:2 * m:2], w[1:2 * m:2], w[2:2 * m + 1:2], h)
    q = np.array([1.0, 0, 0, 0]) if q0 is None else quat_normalize(q0)
    return _prefix_product(q, steps)
