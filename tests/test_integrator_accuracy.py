"""Integrator accuracy on motions with a known answer, and the C integrator
against the NumPy reference. Formulas and sources: docs/integrator.md."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.integrate import solve_ivp

import attitude_c as ac
from attitude_c import reference as ref

FRAME = {"rv1": 1, "rv2": 2, "rv3": 3, "rv3-coning": 3, "rv3-reuse": 1}


def attitude_error(q: np.ndarray, q_true: np.ndarray) -> np.ndarray:
    """Navigation-frame error rotation vector e with q = Exp(e) ⊗ q_true."""
    return ref.quat_to_rotvec(ref.quat_multiply(q, ref.quat_conj(q_true)))


# ---------------------------------------------------------------------------
# coefficients
# ---------------------------------------------------------------------------

def test_c_coefficients_match_the_derivation() -> None:
    """The header's fractions equal the ones the reference derives from the
    polynomial rate models (exact rational arithmetic)."""
    from attitude_c._lib import ffi_lib

    _, lib = ffi_lib("f64")
    c = ref.COEFFICIENTS
    assert c["rv2"][0] == Fraction(lib.ATT_RV2_K_NUM, lib.ATT_RV2_DEN) == Fraction(2, 3)
    assert c["rv3"] == tuple(Fraction(getattr(lib, f"ATT_RV3_{k}_NUM"), lib.ATT_RV3_DEN)
                             for k in ("K12", "K13", "K23"))
    assert c["rv3"] == (Fraction(57, 80), Fraction(33, 80), Fraction(57, 80))  # paper eq. (5)
    assert c["rv3-coning"] == tuple(Fraction(getattr(lib, f"ATT_RV3C_{k}_NUM"), lib.ATT_RV3C_DEN)
                                    for k in ("K12", "K13", "K23"))
    assert c["rv3-reuse"] == tuple(Fraction(getattr(lib, f"ATT_RV3R_{k}_NUM"), lib.ATT_RV3R_DEN)
                                   for k in ("K12", "K13", "K23"))
    assert c["rv3-reuse"] == (Fraction(1, 720), Fraction(-31, 720), Fraction(121, 720))
    assert c["rv3-reuse-start"][0] == Fraction(lib.ATT_RV3R_START_K_NUM, lib.ATT_RV3R_START_DEN)


# ---------------------------------------------------------------------------
# C against the reference
# ---------------------------------------------------------------------------

increments = st.integers(6, 60).flatmap(
    lambda n: st.sampled_from([1e-6, 1e-2, 0.3, 2.0]).flatmap(
        lambda sc: arrays(np.float64, (n, 3), elements=st.floats(-sc, sc, allow_nan=False))))


@settings(max_examples=40, deadline=None)
@given(increments, st.sampled_from(ac.INCREMENT_METHODS))
def test_integrate_against_reference(d: np.ndarray, method: str) -> None:
    q0 = np.array([0.9, -0.1, 0.3, 0.2])
    got = ac.integrate(d, method, q0=q0)
    want = ref.integrate(d, method, q0=q0)
    assert got.shape == want.shape
    # ≤ 60 updates, each a few roundings of O(1) values: 1e-12 bounds the
    # accumulated float64 rounding (~60 × 10 × 1.1e-16 ≈ 7e-14) generously
    np.testing.assert_allclose(got, want, atol=1e-12)
    # float32: per update ~1e-7 (rounding of Q and of Φ); over ≤ 60 updates
    # and increments up to 2 rad (sin/cos arguments rounded): 2e-5
    np.testing.assert_allclose(ac.integrate(d, method, q0=q0, precision="f32"), want, atol=2e-5)


@settings(max_examples=25, deadline=None)
@given(arrays(np.float64, (21, 3), elements=st.floats(-3, 3, allow_nan=False)),
       st.floats(1e-4, 0.05))
def test_rk4_against_reference(w: np.ndarray, dt: float) -> None:
    # 10 RK4 steps, a few dozen operations each: 1e-13
    np.testing.assert_allclose(ac.integrate_rates(w, dt), ref.integrate_rates(w, dt), atol=1e-13)
    np.testing.assert_allclose(ac.integrate_rates(w, dt, precision="f32"),
                               ref.integrate_rates(w, dt), atol=1e-5)  # 10 steps × float32 ulps


# ---------------------------------------------------------------------------
# constant rate about a fixed axis: every increment method is exact
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("method", ac.INCREMENT_METHODS)
def test_constant_rate_exact(method: str) -> None:
    w = np.array([0.3, -0.5, 1.0])
    dt, n = 0.01, 3000
    q = ac.integrate(np.tile(w * dt, (n, 1)), method)
    t = dt * FRAME[method] * np.arange(1, len(q) + 1)
    exact = ref.rotvec_to_quat(w * t[:, None])
    # Δθ's are parallel: every cross product is 0 and q(Φ) is exact; what is
    # left is float64 rounding growing like a random walk over ≤ 3000
    # updates: √3000 × a few ulp ≈ 1e-14; 1e-13 is the bound.
    np.testing.assert_allclose(q, exact, atol=1e-13)


def test_constant_rate_rk4_truncation() -> None:
    w = np.array([0.3, -0.5, 1.0])
    h, n = 0.02, 500
    q = ac.integrate_rates(np.tile(w, (2 * n + 1, 1)), h / 2)
    exact = ref.rotvec_to_quat(w * (h * np.arange(1, n + 1))[:, None])
    # RK4 truncates exp(x) (x = |ω|h/2) after x⁴/24: per step an angle error
    # of 2·x⁵/120 (first omitted term); n steps add up linearly.
    x = np.linalg.norm(w) * h / 2
    bound = n * 2 * x ** 5 / 120
    err = np.linalg.norm(attitude_error(q, exact), axis=1)
    assert err[-1] <= 1.1 * bound + 1e-14
    assert err[-1] >= 0.5 * bound  # and it is really that term


# ---------------------------------------------------------------------------
# classical coning: drift against theory
# ---------------------------------------------------------------------------

def coning_increments(beta: float, omega: float, T: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Exact increments of q(t) = [cos β/2, 0, sin β/2 cos Ωt, sin β/2 sin Ωt],
    whose body rate is ω = [−2Ω sin²(β/2), −Ω sin β sin Ωt, Ω sin β cos Ωt]."""
    t = np.arange(n + 1) * T
    s2 = np.sin(beta / 2) ** 2
    d = np.stack([np.full(n, -2 * omega * s2 * T), np.sin(beta) * np.diff(np.cos(omega * t)),
                  np.sin(beta) * np.diff(np.sin(omega * t))], axis=-1)
    return d, t


def coning_truth(beta: float, omega: float, t: np.ndarray) -> np.ndarray:
    c, s = np.cos(beta / 2), np.sin(beta / 2)
    return np.stack([np.full_like(t, c), 0 * t, s * np.cos(omega * t), s * np.sin(omega * t)], -1)


def coning_drift_theory(method: str, beta: float, omega: float, T: float) -> float:
    """Drift rate (rad/s) about the cone axis of an algorithm
    Φ = ΣΔθ + Σ k_ij Δθ_i × Δθ_j under classical coning (Ignagni 1990;
    Savage 1998, eq. for the coning error of a general algorithm):
    cone-axis part of Δθ_i × Δθ_j = 2 sin²β (1 − cos λ) sin((j − i) λ),
    λ = ΩT, and of the true rotation vector over h = mT the coning term
    ½ sin²β (Ωh − sin Ωh); drift = (algorithm − truth) / h."""
    lam = omega * T
    k12, k13, k23 = (float(k) for k in ref.COEFFICIENTS[method])
    m = FRAME[method]
    if method == "rv1":
        pairs: list[tuple[float, int]] = []
    elif method == "rv2":
        pairs = [(k12, 1)]
    else:  # (coefficient, index distance j − i)
        pairs = [(k12, 1), (k13, 2), (k23, 1)]
    s2 = np.sin(beta) ** 2
    corr = sum(k * 2 * s2 * (1 - np.cos(lam)) * np.sin(d * lam) for k, d in pairs)
    h = m * T
    return float((corr - 0.5 * s2 * (omega * h - np.sin(omega * h))) / h)


BETA, OMEGA, T_CONE, N_CONE = 0.01, 2 * np.pi * 10, 0.004, 3000  # λ = ΩT = 0.25 rad


@pytest.fixture(scope="module")
def coning_drifts() -> dict[str, tuple[float, float]]:
    d, t = coning_increments(BETA, OMEGA, T_CONE, N_CONE)
    q0 = coning_truth(BETA, OMEGA, t[:1])[0]
    out = {}
    for m in ac.INCREMENT_METHODS:
        q = ac.integrate(d, m, q0=q0)
        tt = t[FRAME[m]::FRAME[m]][: len(q)]
        e = attitude_error(q, coning_truth(BETA, OMEGA, tt))
        # least-squares slope of the cone-axis error (the drift) over 12 s
        slope = np.polyfit(tt, e[:, 0], 1)[0] / np.cos(BETA)
        out[m] = (float(slope), coning_drift_theory(m, BETA, OMEGA, T_CONE))
    return out


@pytest.mark.parametrize("method", ac.INCREMENT_METHODS)
def test_coning_drift_matches_theory(method: str, coning_drifts: dict) -> None:
    measured, theory = coning_drifts[method]
    # The theory keeps the O(β²) terms only; the neglected higher-order terms
    # (third-order Bortz terms, sin β vs β) are relatively O(β²)·(1/λ^k): at
    # β = 0.05 they were measured at 8 % for rv3-coning (whose drift is the
    # smallest), scaling as β² to 0.3 % at β = 0.01. 2 % is the margin.
    assert measured == pytest.approx(theory, rel=0.02)


def test_coning_ranking(coning_drifts: dict) -> None:
    mag = {m: abs(v[0]) for m, v in coning_drifts.items()}
    # theory (docs/integrator.md), drift / (Ω sin²β): rv1 λ²/12, rv2 λ⁴/60,
    # rv3 λ⁴/80, rv3-coning λ⁶/280, rv3-reuse 19λ⁴/720 (λ = ΩT, T the increment interval)
    assert mag["rv3-coning"] < mag["rv3"] < mag["rv2"] < mag["rv3-reuse"] < mag["rv1"]
    # rv3-coning beats rv3 under coning by the λ² factor
    assert mag["rv3"] / mag["rv3-coning"] > 10
    # rv3-reuse: same λ⁴ order as the three-sample algorithm at three times
    # its output rate: theory ratio (19/720)/(1/80) = 2.11
    assert mag["rv3-reuse"] / mag["rv3"] == pytest.approx(19 / 720 * 80, rel=0.05)
    # ... and far better than rv1 at the same output rate: theory ratio
    # (λ²/12)/(19λ⁴/720) = 60/(19λ²) = 50.5 at λ = 0.25, growing as 1/λ²
    assert mag["rv1"] / mag["rv3-reuse"] == pytest.approx(60 / (19 * (OMEGA * T_CONE) ** 2),
                                                          rel=0.05)


def test_rv3_reuse_order_with_sample_rate() -> None:
    """Halving T divides the rv3-reuse drift by 2⁴ (a fourth-order algorithm
    like rv3), and rv1's only by 2²."""
    rates = {}
    for T in (0.004, 0.002):
        d, t = coning_increments(BETA, OMEGA, T, int(12 / T))
        q0 = coning_truth(BETA, OMEGA, t[:1])[0]
        for m in ("rv1", "rv3-reuse"):
            q = ac.integrate(d, m, q0=q0)
            e = attitude_error(q, coning_truth(BETA, OMEGA, t[1:]))
            rates[m, T] = np.polyfit(t[1:], e[:, 0], 1)[0]
    # exact ratios from the series: higher-order terms in λ move them by < 5 %
    assert rates["rv3-reuse", 0.004] / rates["rv3-reuse", 0.002] == pytest.approx(16, rel=0.05)
    assert rates["rv1", 0.004] / rates["rv1", 0.002] == pytest.approx(4, rel=0.05)


def test_reusing_the_full_three_interval_vector_is_wrong() -> None:
    """The paper's sec. 1.2 read literally (apply eq. (5) over the last three
    increments at every step) counts each increment three times: at a
    constant rate it turns three times too fast. rv3-reuse does not."""
    w, dt, n = np.array([0.0, 0.0, 1.0]), 0.01, 300
    d = np.tile(w * dt, (n, 1))
    naive_phi = d[:-2] + d[1:-1] + d[2:]  # Φ over the last three intervals, each step
    naive = ref._prefix_product(np.array([1.0, 0, 0, 0]), ref.rotvec_to_quat(naive_phi))
    yaw_naive = ref.quat_to_euler(naive[-1])[0]
    yaw_reuse = ac.quat_to_euler(ac.integrate(d, "rv3-reuse")[-1])[0]
    assert yaw_naive == pytest.approx(3 * (n - 2) * dt - 2 * np.pi, abs=1e-9)
    assert yaw_reuse == pytest.approx(n * dt, abs=1e-12)


# ---------------------------------------------------------------------------
# a rate quadratic in time: Miller's rv3 is the right one
# ---------------------------------------------------------------------------

def quadratic_rate_errors(s: float) -> dict[str, float]:
    """One three-sample frame (T = 0.01 s) of ω(t) = s (a + b u + c u²),
    u = t/τ − 1 over [0, 2τ]; truth from DOP853 at rtol 2.3e-14."""
    T, N = 0.01, 3
    tau = N * T / 2
    a, b, c = np.array([0.5, -0.3, 0.2]), np.array([-0.4, 0.8, 0.3]), np.array([0.3, 0.2, -0.6])

    def w(t: float) -> np.ndarray:
        u = t / tau - 1
        return s * (a + b * u + c * u * u)

    def th(t: float) -> np.ndarray:
        u = t / tau - 1
        return s * tau * (a * u + b * u * u / 2 + c * u ** 3 / 3)

    t = np.arange(N + 1) * T
    d = np.diff(np.array([th(x) for x in t]), axis=0)
    sol = solve_ivp(lambda tt, q: 0.5 * ref.quat_multiply(q, np.r_[0.0, w(tt)]), (0, t[-1]),
                    [1.0, 0, 0, 0], method="DOP853", rtol=2.3e-14, atol=1e-16)
    q_true = sol.y[:, -1] / np.linalg.norm(sol.y[:, -1])
    return {m: float(np.linalg.norm(attitude_error(ac.integrate(d, m)[-1], q_true)))
            for m in ("rv3", "rv3-coning")}


def test_quadratic_rate_rv3_beats_rv3_coning() -> None:
    e1, e2 = quadratic_rate_errors(0.2), quadratic_rate_errors(0.05)
    # rv3's coefficients reproduce the second-order coning integral exactly
    # for a quadratic rate (they are fitted to it): its error is the neglected
    # third-order terms, ∝ s³. rv3-coning's coefficients are not: its error
    # is second order, ∝ s². (Measured: 1.4e-9 vs 5.9e-8 at s = 0.2.)
    assert e1["rv3"] * 10 < e1["rv3-coning"]
    assert e1["rv3"] / e2["rv3"] == pytest.approx(4 ** 3, rel=0.1)
    assert e1["rv3-coning"] / e2["rv3-coning"] == pytest.approx(4 ** 2, rel=0.1)


# ---------------------------------------------------------------------------
# float32 over 10⁶ updates
# ---------------------------------------------------------------------------

def test_float32_long_run() -> None:
    n, dt = 10 ** 6, 1e-3
    t = (np.arange(n) + 0.5) * dt
    w = np.stack([0.6 * np.sin(0.7 * t), 0.5 * np.cos(1.3 * t) + 0.3,
                  0.7 * np.sin(0.4 * t + 1.0)], axis=-1)  # |ω| ≈ 0.4 … 1.1 rad/s
    d = (w * dt).astype(np.float32).astype(np.float64)  # the same increments for both builds
    q32 = ac.integrate(d, "rv1", precision="f32")[-1]
    q64 = ac.integrate(d, "rv1", precision="f64")[-1]
    err = float(np.linalg.norm(attitude_error(q32, q64)))
    # Target of issue 2: ≤ 2e-4 rad (the random-walk rounding limit is
    # ~√10⁶ × 6e-8 ≈ 6e-5 rad; a multiply-then-normalize update drifts to ~1e-2).
    assert err <= 2e-4
