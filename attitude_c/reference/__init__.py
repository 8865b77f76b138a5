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
* the coning-correction coefficients are *derived* here at import time, in
  exact rational arithmetic: rv2, rv3 and rv3-reuse-poly from the
  polynomial angular-rate models (Miller 1983), see :func:`fit_coefficients`;
  rv3-coning, rv3-reuse and the reuse start-up from the classical-coning
  error series (Ignagni 1990), see :func:`coning_optimal` and
  :func:`coning_drift_series`, which also gives every method's drift;
* the integrator composes the update quaternions with an associative
  (parallel-prefix) product instead of a sequential loop; RK4 is the
  textbook k1…k4 scheme applied to the quaternion ODE.

Every function is vectorized over leading axes like its attitude_c.core
counterpart and returns float64.
"""

from __future__ import annotations

from fractions import Fraction
from math import factorial
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import METHODS  # the names only (importing core loads no C extension)

if TYPE_CHECKING:  # types only: the reference runs without the C library
    from ..core import FloatPrecision, Method

__all__ = [
    "COEFFICIENTS",
    "CONING_FORMS",
    "GIMBAL_COS",
    "METHODS",
    "coning_attitude",
    "coning_drift",
    "coning_drift_leading",
    "coning_drift_series",
    "coning_increments",
    "coning_leading_term",
    "coning_optimal",
    "coning_rates",
    "dcm_to_euler",
    "dcm_to_quat",
    "euler_to_dcm",
    "euler_to_quat",
    "fit_coefficients",
    "heading",
    "integrate",
    "integrate_rates",
    "quat_angle",
    "quat_conj",
    "quat_multiply",
    "quat_normalize",
    "quat_to_dcm",
    "quat_to_euler",
    "quat_to_rotvec",
    "rotation_vectors",
    "rotvec_to_quat",
    "sensor_values",
]

F = NDArray[np.float64]

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


# ---------------------------------------------------------------------------
# classical coning: the error series of every method (exact)
# ---------------------------------------------------------------------------
#
# Classical coning (docs/integrator.md, sec. 5): attitude
# q(t) = [cos β/2, 0, sin β/2 cos Ωt, sin β/2 sin Ωt], body rate
# ω = [−2Ω sin²(β/2), −Ω sin β sin Ωt, Ω sin β cos Ωt]. To second order in β,
# whatever the phase:
#
# * the cone-axis (x) component of Δθ_i × Δθ_j, increments over intervals of
#   length T that are d = j − i intervals apart, is 2 sin²β (1 − cos λ) sin(dλ),
#   λ = ΩT (direct integration);
# * the true rotation vector over an update of length h = mT holds, beside
#   ∫ω_x dt (which ΣΔθ reproduces exactly), the coning term
#   ½ sin²β (mλ − sin mλ) (Bortz's second-order term ½ ∫ α × ω dt).
#
# A method Φ = ΣΔθ + Σ k_ij Δθ_i × Δθ_j therefore errs about the cone axis by
#     e = [Σ_d c_d · 2(1 − cos λ) sin(dλ) − ½(mλ − sin mλ)] · sin²β
# per update, c_d the sum of its coefficients at distance d, and drifts at
# e / h: ε / (Ω sin²β) = e / (mλ sin²β). Every function below works on the
# Taylor series of these expressions in λ with exact rational coefficients.

_NSER = 16  #: Taylor coefficients kept (λ^0 … λ^15)

def _ser_trig(k: int, cosine: bool) -> list[Fraction]:
    """Taylor coefficients of sin(kλ) (cosine: cos(kλ)) in λ."""
    out = [Fraction(0)] * _NSER
    for p in range(_NSER):
        if (p % 2 == 0) == cosine:
            out[p] = Fraction((-1) ** (p // 2) * k ** p, factorial(p))
    return out


def _ser_mul(a: list[Fraction], b: list[Fraction]) -> list[Fraction]:
    out = [Fraction(0)] * _NSER
    for i, x in enumerate(a):
        if x:
            for j in range(_NSER - i):
                out[i + j] += x * b[j]
    return out


def _ser_add(*terms: tuple[Fraction | int, list[Fraction]]) -> list[Fraction]:
    out = [Fraction(0)] * _NSER
    for c, ser in terms:
        for i in range(_NSER):
            out[i] += c * ser[i]
    return out


_LAM = [Fraction(0), Fraction(1)] + [Fraction(0)] * (_NSER - 2)


def _cross_x(d: int) -> list[Fraction]:
    """(Δθ_i × Δθ_{i+d})_x / sin²β = 2(1 − cos λ) sin(dλ)."""
    one_minus_cos = _ser_add((-2, _ser_trig(1, True)))
    one_minus_cos[0] += 2
    return _ser_mul(one_minus_cos, _ser_trig(d, False))


def _true_coning(m: int) -> list[Fraction]:
    """True cone-axis coning term over h = mT, / sin²β: ½(mλ − sin mλ)."""
    return _ser_add((Fraction(m, 2), _LAM), (Fraction(-1, 2), _ser_trig(m, False)))


def _error_series(m: int, c: dict[int, Fraction]) -> list[Fraction]:
    """Cone-axis error per update / sin²β of a form with distance sums c."""
    return _ser_add(*[(cd, _cross_x(d)) for d, cd in c.items()], (-1, _true_coning(m)))


def _ser_inv(a: list[Fraction]) -> list[Fraction]:
    """1 / a for a series with a[0] ≠ 0."""
    out = [Fraction(0)] * _NSER
    out[0] = 1 / a[0]
    for n in range(1, _NSER):
        out[n] = -sum(a[k] * out[n - k] for k in range(1, n + 1)) / a[0]
    return out


def _rk4_drift_series() -> list[Fraction]:
    """RK4 from rate rows every T (rows t, t+h/2, t+h; h = 2T, μ = Ωh = 2λ):
    cone-axis drift rate / (Ω sin²β), two parts.

    1. The cone-axis part of the step. With a, b, c = ½ω at t, t+h/2, t+h
       (pure quaternions) the step is 1 + h/6 (K1 + 2K2 + 2K3 + K4),
       K1 = a, K2 = b + h/2 a⊗b, K3 = b + h/2 b⊗b + h²/4 a⊗b⊗b,
       K4 = c + h b⊗c + h²/2 b⊗b⊗c + h³/4 a⊗b⊗b⊗c. ω_x is O(β²) and ω_y, ω_z
       are O(β), so to O(β²) the x-part of the step's vector is
       h/6 (a + 4b + c)_x + h²/6 (a × b + b × c)_x = ½ω_x h +
       h²/24 ((ω_0 × ω_m)_x + (ω_m × ω_1)_x), with (ω(t1) × ω(t2))_x =
       Ω² sin²β sin Ω(t2 − t1); the rotation vector of the (normalized)
       step is twice its vector part to O(β²). Hence Φ_x − ∫ω_x =
       (μ²/6) sin(μ/2) sin²β, against the true ½(μ − sin μ) sin²β.
    2. The y, z part of the step is Simpson's rule on ω_y, ω_z, which for
       a sinusoid of phase advance μ per step is the exact increment times
       κ = μ(2 + cos(μ/2)) / (6 sin(μ/2)) (a pure scale factor, no phase
       error): δ_yz = (κ − 1) ∫ω_yz. It enters the navigation frame as
       C(t+h) δ_yz (the step's error is a body-frame rotation at its end;
       the right Jacobian adds nothing at O(β²) since δ_yz ∥ Φ_yz), whose
       cone-axis component is (κ − 1) sin²β sin μ: the body y-z rate seen
       in the navigation frame has the constant cone-axis component
       Ω sin²β (ω_n = Ω sin β w(t) + 2Ω sin²(β/2) e_x), and carrying
       ω_yz(s) to the end of the step adds ∫(φ × ω)_x = sin²β (sin μ − μ).
       The increment methods have no such term (their ΣΔθ is exact).
    """
    lam2 = _ser_mul(_LAM, _LAM)
    e = _ser_add((Fraction(4, 6), _ser_mul(lam2, _ser_trig(1, False))), (-1, _true_coning(2)))
    per_time = [x / 2 for x in e[1:]] + [Fraction(0)]  # e / (2λ)
    sinc = _ser_trig(1, False)[1:] + [Fraction(0)]     # sin λ / λ
    two_plus_cos = _ser_add((Fraction(1, 3), _ser_trig(1, True)))
    two_plus_cos[0] += Fraction(2, 3)                    # (2 + cos λ) / 3
    kappa = _ser_mul(two_plus_cos, _ser_inv(sinc))
    kappa[0] -= 1
    sinc2 = [x / 2 for x in _ser_trig(2, False)[1:]] + [Fraction(0)]  # sin 2λ / 2λ
    # the sinc series are known to λ^(_NSER − 2) only: so is the result
    return _ser_add((1, per_time), (1, _ser_mul(kappa, sinc2)))[: _NSER - 2]


def coning_optimal(m: int, distances: tuple[int, ...]) -> dict[int, Fraction]:
    """Distance sums c_d of the coning-optimal algorithm (Ignagni 1990).

    The algorithm updates over h = mT and corrects with cross products of
    increments d ∈ ``distances`` intervals apart; the c_d are chosen so that
    the lowest len(distances) non-zero orders of its classical-coning error
    (λ³, λ⁵, …: the error is odd in λ) vanish. E.g. ``coning_optimal(3, (1, 2))``
    → {1: 27/20, 2: 9/20} (rv3-coning), ``coning_optimal(1, (1, 2))`` →
    {1: 7/60, 2: −1/60} (rv3-reuse), ``coning_optimal(1, (1,))`` → {1: 1/12}.
    """
    n = len(distances)
    powers = [3 + 2 * i for i in range(n)]
    cols = [_cross_x(d) for d in distances]
    rhs = _true_coning(m)
    sol = _solve([[col[p] for col in cols] for p in powers], [rhs[p] for p in powers])
    return dict(zip(distances, sol))


def _derive() -> dict[str, tuple[Fraction, Fraction, Fraction]]:
    rv2 = fit_coefficients([(0, 1), (1, 2)], (0, 2))
    rv3 = fit_coefficients([(0, 1), (1, 2), (2, 3)], (0, 3))
    # the newest interval's quadratic-rate fit from it and the two before it
    poly = fit_coefficients([(-2, -1), (-1, 0), (0, 1)], (0, 1))
    coning3 = coning_optimal(3, (1, 2))
    reuse = coning_optimal(1, (1, 2))
    start = coning_optimal(1, (1,))
    z = Fraction(0)
    return {
        "rv1": (z, z, z),
        "rv2": (rv2[(0, 1)], z, z),
        "rv3": (rv3[(0, 1)], rv3[(0, 2)], rv3[(1, 2)]),
        # Ignagni's coning-optimal three-sample algorithm, in eq. (5)'s shape
        # k12 = k23 (k13 Δθ1×Δθ3 + k23 Δθ2×(Δθ3 − Δθ1)): 27/40, 9/20, 27/40
        "rv3-coning": (coning3[1] / 2, coning3[2], coning3[1] / 2),
        # update every sample: Φk = Δθk + a Δθk−1×Δθk + b Δθk−2×Δθk
        # (Δθ1 = Δθk−2, Δθ2 = Δθk−1, Δθ3 = Δθk): k12 = 0, k13 = b, k23 = a
        "rv3-reuse": (z, reuse[2], reuse[1]),
        "rv3-reuse-poly": (poly[(0, 1)], poly[(0, 2)], poly[(1, 2)]),
        # second update of both reuse forms (one previous increment):
        # Φ = Δθ2 + k Δθ1×Δθ2, coning-optimal k = 1/12 (= the linear-rate fit)
        "rv3-reuse-start": (start[1], z, z),
    }


#: (k12, k13, k23) per method, exact fractions (rv2: k12 only).
COEFFICIENTS: dict[str, tuple[Fraction, Fraction, Fraction]] = _derive()

#: Increments consumed per update (h = FRAME · T).
FRAME = {"rv1": 1, "rv2": 2, "rv3": 3, "rv3-coning": 3, "rv3-reuse": 1, "rv3-reuse-poly": 1}

#: Per increment method: (m, {d: c_d}), the update length in increments and
#: the sum of its cross-product coefficients at each distance d (what
#: classical coning sees of it): c_1 = k12 + k23, c_2 = k13.
CONING_FORMS: dict[str, tuple[int, dict[int, Fraction]]] = {
    m: (FRAME[m], {d: c for d, c in ((1, COEFFICIENTS[m][0] + COEFFICIENTS[m][2]),
                                     (2, COEFFICIENTS[m][1])) if c != 0})
    for m in FRAME
}


def coning_attitude(beta: float, omega: float, t: ArrayLike) -> F:
    """Classical coning, exact attitude (…, 4):
    q(t) = [cos β/2, 0, sin β/2 cos Ωt, sin β/2 sin Ωt]."""
    tt = np.asarray(t, dtype=np.float64)
    c, s = np.cos(beta / 2), np.sin(beta / 2)
    return np.stack([np.full_like(tt, c), np.zeros_like(tt), s * np.cos(omega * tt),
                     s * np.sin(omega * tt)], axis=-1)


def coning_rates(beta: float, omega: float, t: ArrayLike) -> F:
    """Body rate (…, 3) of :func:`coning_attitude` (from q' = ½ q ⊗ [0, ω]):
    ω = [−2Ω sin²(β/2), −Ω sin β sin Ωt, Ω sin β cos Ωt]."""
    tt = np.asarray(t, dtype=np.float64)
    return np.stack([np.full_like(tt, -2 * omega * np.sin(beta / 2) ** 2),
                     -omega * np.sin(beta) * np.sin(omega * tt),
                     omega * np.sin(beta) * np.cos(omega * tt)], axis=-1)


def coning_increments(beta: float, omega: float, T: float, n: int) -> tuple[F, F]:
    """Exact increments ∫ω dt of :func:`coning_rates` over [kT, (k+1)T],
    k = 0 … n−1, (n, 3), and the times kT, k = 0 … n, (n + 1,)."""
    t = np.arange(n + 1) * T
    d = np.stack([np.full(n, -2 * omega * np.sin(beta / 2) ** 2 * T),
                  np.sin(beta) * np.diff(np.cos(omega * t)),
                  np.sin(beta) * np.diff(np.sin(omega * t))], axis=-1)
    return np.asarray(d, dtype=np.float64), np.asarray(t, dtype=np.float64)


def coning_drift_series(method: str) -> list[Fraction]:
    """Taylor coefficients in λ = ΩT of ``method``'s classical-coning drift
    rate about the cone axis, in units of Ω sin²β (exact; second order in β).

    T is the sample interval: the increment interval, or for ``rk4`` the
    spacing of its rate rows (h = 2T). Entry p is the coefficient of λ^p
    (every entry returned is exact). E.g. rv1 → −λ²/12 + λ⁴/240 − …
    """
    if method == "rk4":
        return _rk4_drift_series()
    m, c = CONING_FORMS[method]
    e = _error_series(m, c)
    if e[0] != 0:
        raise AssertionError("coning error series must vanish at λ = 0")
    return [x / m for x in e[1:]]  # e / (mλ)


def coning_leading_term(method: str) -> tuple[Fraction, int]:
    """(k, p): the leading term k λ^p of :func:`coning_drift_series`."""
    ser = coning_drift_series(method)
    p = next(i for i, x in enumerate(ser) if x != 0)
    return ser[p], p


def coning_drift_leading(method: str, beta: float, omega: float, T: float) -> float:
    """Leading-term drift rate (rad/s) about the cone axis: k λ^p Ω sin²β."""
    k, p = coning_leading_term(method)
    return float(k) * (omega * T) ** p * omega * np.sin(beta) ** 2


def coning_drift(method: str, beta: float, omega: float, T: float) -> float:
    """Drift rate (rad/s) about the cone axis to second order in β, all
    orders in λ = ΩT (the closed forms behind :func:`coning_drift_series`)."""
    lam = omega * T
    s2 = np.sin(beta) ** 2
    cross = lambda d: 2 * (1 - np.cos(lam)) * np.sin(d * lam)
    true = lambda m: 0.5 * (m * lam - np.sin(m * lam))
    if method == "rk4":  # see _rk4_drift_series: step's cone-axis part + Simpson scale error
        e = (2 * lam) ** 2 / 6 * np.sin(lam) - true(2)
        kappa = lam * (2 + np.cos(lam)) / (3 * np.sin(lam)) - 1
        return float(e * s2 / (2 * T) + kappa * np.sin(2 * lam) * s2 / (2 * T))
    m, c = CONING_FORMS[method]
    e = sum(float(cd) * cross(d) for d, cd in c.items()) - true(m)
    return float(e * s2 / (m * T))


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


def quat_angle(qa: ArrayLike, qb: ArrayLike) -> F:
    """Angle (rad, [0, π]) of the rotation taking attitude qa to qb: 2 atan2(|v|, |w|)
    of qa* ⊗ qb (the sign of the quaternion does not matter)."""
    d = quat_multiply(quat_conj(qa), qb)
    return 2 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0]))


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

def rotation_vectors(dtheta: ArrayLike, method: Method) -> F:
    """Φ of every update of ``method`` (M, 3) from increments (N, 3)."""
    d = np.asarray(dtheta, dtype=np.float64).reshape(-1, 3)
    k = [float(x) for x in COEFFICIENTS[method]]
    if method in ("rv3-reuse", "rv3-reuse-poly"):
        z = np.zeros((2, 3))
        pad = np.concatenate([z, d])
        a, b, c = pad[:-2], pad[1:-1], d  # Δθ_{k−2}, Δθ_{k−1}, Δθ_k (zeros before the start)
        phi = c + k[0] * np.cross(a, b) + k[1] * np.cross(a, c) + k[2] * np.cross(b, c)
        if len(d) >= 2:  # second update: one previous increment, coning-optimal 1/12
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


# ---------------------------------------------------------------------------
# sensor words -> body values (attitude/sensor.h)
# ---------------------------------------------------------------------------

def sensor_values(words: ArrayLike, zero: ArrayLike, scale: ArrayLike, n: int = 1,
                  axes: ArrayLike = (0, 1, 2), signs: ArrayLike = (1, 1, 1),
                  matrix: ArrayLike | None = None, bias: ArrayLike | None = None) -> F:
    """Body-frame values (M, 3) of sample words (M, 3), each the sum of ``n``
    conversions: body axis i reads channel ``axes[i]`` with sign ``signs[i]``,
    value = sign · (mean code − zero) · scale (the mean code of the channel is
    word / n; zero in codes of one conversion, scale in units per code); then
    the correction out = matrix · (value − bias) (matrix 3 × 3, default the
    identity; bias in the output's units, default 0)."""
    w = np.asarray(words, dtype=np.float64).reshape(-1, 3)
    mean = w / float(n)
    chan = (mean - np.asarray(zero, dtype=np.float64)) * np.asarray(scale, dtype=np.float64)
    value = chan[:, np.asarray(axes, dtype=np.intp)] * np.asarray(signs, dtype=np.float64)
    if matrix is None and bias is None:
        return value
    m = np.eye(3) if matrix is None else np.asarray(matrix, dtype=np.float64).reshape(3, 3)
    b = np.zeros(3) if bias is None else np.asarray(bias, dtype=np.float64)
    return np.einsum("ij,kj->ki", m, value - b)

