"""Integrator accuracy on motions with a known answer, and the C integrator
against the NumPy reference. Formulas and sources: docs/integrator.md.

``python tests/test_integrator_accuracy.py`` prints the coning table of
docs/integrator.md (measured drift of every method next to its derived
leading term, the issue's case: β = 1°, 10 Hz, T = 5 ms)."""

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
from attitude_c.cli.demo import coning_drifts as measure_coning_drifts

FRAME = ref.FRAME


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
    assert c["rv3-coning"] == (Fraction(27, 40), Fraction(9, 20), Fraction(27, 40))  # Ignagni
    assert c["rv3-reuse"] == tuple(Fraction(getattr(lib, f"ATT_RV3R_{k}_NUM"), lib.ATT_RV3R_DEN)
                                   for k in ("K12", "K13", "K23"))
    # Φk = Δθk + a Δθk−1×Δθk + b Δθk−2×Δθk, coning-optimal: a = 7/60, b = −1/60
    assert c["rv3-reuse"] == (0, Fraction(-1, 60), Fraction(7, 60))
    assert c["rv3-reuse-poly"] == tuple(Fraction(getattr(lib, f"ATT_RV3RP_{k}_NUM"), lib.ATT_RV3RP_DEN)
                                        for k in ("K12", "K13", "K23"))
    assert c["rv3-reuse-poly"] == (Fraction(1, 720), Fraction(-31, 720), Fraction(121, 720))
    assert c["rv3-reuse-start"][0] == Fraction(lib.ATT_RV3R_START_K_NUM, lib.ATT_RV3R_START_DEN)


def test_coning_optimal_forms() -> None:
    """The coning-series derivation: each coning-optimal form cancels the
    lowest orders of its drift, and the one-previous-sample start-up form
    (1/12) is both coning-optimal and the linear-rate fit."""
    assert ref.coning_optimal(1, (1, 2)) == {1: Fraction(7, 60), 2: Fraction(-1, 60)}
    assert ref.coning_optimal(3, (1, 2)) == {1: Fraction(27, 20), 2: Fraction(9, 20)}
    assert ref.coning_optimal(1, (1,)) == {1: Fraction(1, 12)}
    assert ref.fit_coefficients([(-1, 0), (0, 1)], (0, 1))[(0, 1)] == Fraction(1, 12)
    assert ref.coning_optimal(2, (1,)) == {1: ref.COEFFICIENTS["rv2"][0]}  # rv2: fit = optimum
    # leading terms of the drift / (Ω sin²β), λ = ΩT (docs/integrator.md, sec. 5)
    lead = {m: ref.coning_leading_term(m) for m in ac.METHODS}
    assert lead == {"rv1": (Fraction(-1, 12), 2), "rv2": (Fraction(-1, 60), 4),
                    "rv3": (Fraction(1, 80), 4), "rv3-coning": (Fraction(-1, 280), 6),
                    "rv3-reuse": (Fraction(-1, 280), 6), "rv3-reuse-poly": (Fraction(19, 720), 4),
                    "rk4": (Fraction(1, 60), 4)}
    # the series agree with their closed forms at a small λ (to the first
    # omitted power: λ^14 ≈ 1e-14 relative at λ = 0.1)
    for m in ac.METHODS:
        lam = 0.1
        series = sum(float(k) * lam ** p for p, k in enumerate(ref.coning_drift_series(m)))
        closed = ref.coning_drift(m, 0.01, 1.0, lam) / np.sin(0.01) ** 2
        assert series == pytest.approx(closed, rel=1e-9)


# ---------------------------------------------------------------------------
# C against the reference
# ---------------------------------------------------------------------------

increments = st.integers(6, 60).flatmap(
    # 1.8 per component: |Δθ| ≤ 1.8·√3 = 3.12, inside the documented limit π (integrator.h)
    lambda n: st.sampled_from([1e-6, 1e-2, 0.3, 1.8]).flatmap(
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

# the case: half-cone angle 1°, 10 Hz, increments (rk4: rate rows)
# every 5 ms, λ = ΩT = 0.314 rad, 12 s
BETA, OMEGA, T_CONE, SECONDS = float(np.radians(1.0)), 2 * np.pi * 10, 0.005, 12.0


@pytest.fixture(scope="module")
def coning_drifts() -> dict[str, tuple[int, float, float]]:
    """{method: (updates, final error, measured drift)}: the C integrator on
    the exact increments/rates of attitude_c.reference's closed-form motion."""
    return measure_coning_drifts(BETA, OMEGA, T_CONE, SECONDS)


@pytest.mark.parametrize("method", ac.METHODS)
def test_coning_drift_matches_theory(method: str, coning_drifts: dict) -> None:
    measured = coning_drifts[method][2]
    # closed form (all orders in λ, second order in β): the neglected O(β⁴)
    # terms are relatively ~β²/λ² ≈ 3e-3 here (measured: 1.3 % for
    # rv3-coning, whose drift is the smallest, ≤ 0.1 % for the others): 2 %
    assert measured == pytest.approx(ref.coning_drift(method, BETA, OMEGA, T_CONE), rel=0.02)
    # the leading term alone: the next term of the series is λ² ≈ 0.1 times
    # a coefficient ratio ≤ 0.62 (rv3: (13/1680)/(1/80)), i.e. ≤ 6.2 %: 10 %
    assert measured == pytest.approx(ref.coning_drift_leading(method, BETA, OMEGA, T_CONE), rel=0.10)


def test_rv3_reuse_keeps_the_three_sample_benefit(coning_drifts: dict) -> None:
    """Issue 11, sec. 1: in the coning case the new rv3-reuse drifts within
    10 % of its derived leading term −λ⁶/280 · Ω sin²β and at least 30×
    less than the polynomial form (theory ≈ 71×), and less than rv2 and
    the one-previous-sample form."""
    reuse, poly = coning_drifts["rv3-reuse"][2], coning_drifts["rv3-reuse-poly"][2]
    lead = ref.coning_drift_leading("rv3-reuse", BETA, OMEGA, T_CONE)
    assert lead == pytest.approx(-(OMEGA * T_CONE) ** 6 / 280 * OMEGA * np.sin(BETA) ** 2)
    assert abs(reuse - lead) <= 0.10 * abs(lead)
    assert abs(poly) >= 30 * abs(reuse)
    assert abs(coning_drifts["rv2"][2]) >= 30 * abs(reuse)
    one_prev = ref.COEFFICIENTS["rv3-reuse-start"][0]  # Φk = Δθk + (1/12) Δθk−1×Δθk
    d, t = ref.coning_increments(BETA, OMEGA, T_CONE, round(SECONDS / T_CONE))
    phi = d.copy()
    phi[1:] += float(one_prev) * np.cross(d[:-1], d[1:])
    q = ref._prefix_product(ref.coning_attitude(BETA, OMEGA, 0.0), ref.rotvec_to_quat(phi))
    e = attitude_error(q, ref.coning_attitude(BETA, OMEGA, t[1:]))
    assert abs(np.polyfit(t[1:], e[:, 0], 1)[0]) >= 30 * abs(reuse)


def test_coning_ranking(coning_drifts: dict) -> None:
    """The measured drifts rank as the theory says (rv3-coning and rv3-reuse
    have the same leading term; their order is left to the next terms)."""
    mag = {m: abs(v[2]) for m, v in coning_drifts.items()}
    theory = {m: abs(ref.coning_drift(m, BETA, OMEGA, T_CONE)) for m in ac.METHODS}
    distinct = [m for m in ac.METHODS if m != "rv3-coning"]
    assert sorted(distinct, key=mag.get) == sorted(distinct, key=theory.get)
    assert max(mag["rv3-coning"], mag["rv3-reuse"]) < min(mag[m] for m in distinct if m != "rv3-reuse")
    # rv3-coning beats rv3 under coning by (λ⁴/80)/(λ⁶/280) = 3.5/λ² = 35 here
    assert mag["rv3"] / mag["rv3-coning"] > 10


def test_rv3_reuse_order_with_sample_rate() -> None:
    """Halving T divides the drift by 2^p, p the order of the leading term:
    2⁶ for rv3-reuse, 2⁴ for rv3-reuse-poly, 2² for rv1."""
    rates = {}
    for T in (T_CONE, T_CONE / 2):
        drifts = measure_coning_drifts(BETA, OMEGA, T, SECONDS)
        for m in ("rv1", "rv3-reuse", "rv3-reuse-poly"):
            rates[m, T] = drifts[m][2]
    for m in ("rv1", "rv3-reuse", "rv3-reuse-poly"):
        _, p = ref.coning_leading_term(m)
        # exact ratio from the closed forms; the leading power alone misses it
        # by the next term (≤ 8 % for λ = 0.31 → 0.16): 2 % is the margin of
        # the closed form itself (see test_coning_drift_matches_theory)
        want = ref.coning_drift(m, BETA, OMEGA, T_CONE) / ref.coning_drift(m, BETA, OMEGA, T_CONE / 2)
        assert rates[m, T_CONE] / rates[m, T_CONE / 2] == pytest.approx(want, rel=0.02)
        assert want == pytest.approx(2 ** p, rel=0.1)


def test_reusing_the_full_three_interval_vector_is_wrong() -> None:
    """The paper's sec. 1.2 read literally (apply eq. (5) over the last three
    increments at every step) counts each increment three times: at a
    constant rate it turns three times too fast. The reuse forms do not."""
    w, dt, n = np.array([0.0, 0.0, 1.0]), 0.01, 300
    d = np.tile(w * dt, (n, 1))
    naive_phi = d[:-2] + d[1:-1] + d[2:]  # Φ over the last three intervals, each step
    naive = ref._prefix_product(np.array([1.0, 0, 0, 0]), ref.rotvec_to_quat(naive_phi))
    yaw_naive = ref.quat_to_euler(naive[-1])[0]
    assert yaw_naive == pytest.approx(3 * (n - 2) * dt - 2 * np.pi, abs=1e-9)
    for m in ("rv3-reuse", "rv3-reuse-poly"):
        yaw_reuse = ac.quat_to_euler(ac.integrate(d, m)[-1])[0]
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


def _print_coning_table() -> None:
    """The table of docs/integrator.md, sec. 5."""
    drifts = measure_coning_drifts(BETA, OMEGA, T_CONE, SECONDS)
    print(f"classical coning, β = 1°, 10 Hz, T = 5 ms (λ = {OMEGA * T_CONE:.4f} rad), {SECONDS:g} s\n")
    print("| method | updates | measured drift (rad/s) | leading term | leading term (rad/s) "
          "| measured / leading | closed form (rad/s) |")
    print("|---|---:|---:|---|---:|---:|---:|")
    for m, (n, _, slope) in drifts.items():
        k, p = ref.coning_leading_term(m)
        lead = ref.coning_drift_leading(m, BETA, OMEGA, T_CONE)
        print(f"| `{m}` | {n} | {slope:.3e} | {k} λ^{p} | {lead:.3e} | {slope / lead:.3f} "
              f"| {ref.coning_drift(m, BETA, OMEGA, T_CONE):.3e} |")


if __name__ == "__main__":
    _print_coning_table()
