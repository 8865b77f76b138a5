"""API contract of attitude_c.core: shapes, dtypes, errors, streaming semantics."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import attitude_c as ac
from attitude_c.errors import InvalidArgument, InvalidType, NonFiniteError, RangeError

RNG = np.random.default_rng(7)
D = RNG.normal(scale=0.01, size=(30, 3))


@pytest.mark.parametrize("precision", ["f64", "f32"])
@pytest.mark.parametrize("method,per", [("rv1", 1), ("rv2", 2), ("rv3", 3), ("rv3-coning", 3),
                                        ("rv3-reuse", 1)])
def test_output_counts_and_leftovers(method: str, per: int, precision: str) -> None:
    q = ac.integrate(D[:29], method, precision=precision)
    assert q.shape == (29 // per, 4) and q.dtype == (np.float32 if precision == "f32" else np.float64)
    # unit quaternions: renormalized every 16 updates, error between ~ 16 ulp of the build
    tol = 2e-6 if precision == "f32" else 1e-14
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=tol)
    # streaming in odd chunks gives the same attitudes (leftovers stay buffered)
    it = ac.Integrator(method, precision=precision)
    parts = [it.update(D[a:b]) for a, b in ((0, 1), (1, 8), (8, 9), (9, 29))]
    np.testing.assert_array_equal(np.concatenate(parts), q)
    assert it.pending == (29 % per if method != "rv3-reuse" else 2)
    one = ac.Integrator(method, precision=precision)
    singles = [one.update(d) for d in D[:29]]
    np.testing.assert_array_equal(np.concatenate(singles), q)


def test_q0_and_reset() -> None:
    q0 = np.array([2.0, 0.0, 0.0, 2.0])  # normalized by the integrator
    q = ac.integrate(np.zeros((3, 3)), "rv1", q0=q0)
    np.testing.assert_allclose(q, np.tile(q0 / np.linalg.norm(q0), (3, 1)), atol=1e-15)
    it = ac.Integrator("rv3", q0=q0)
    it.update(D[:4])
    assert it.pending == 1 and it.updates == 1
    it.reset()
    assert it.pending == 0 and it.updates == 0
    np.testing.assert_array_equal(it.q, [1.0, 0.0, 0.0, 0.0])


def test_bad_inputs_name_the_problem() -> None:
    bad = D.copy()
    bad[17, 1] = np.nan
    with pytest.raises(NonFiniteError, match="sample 17") as ei:
        ac.integrate(bad, "rv3")
    assert ei.value.index == 17
    bad[17, 1] = np.inf
    with pytest.raises(ValueError):
        ac.integrate(bad, "rv1", precision="f32")
    with pytest.raises(InvalidArgument, match="method"):
        ac.integrate(D, "rv5")
    with pytest.raises(InvalidArgument, match="integrate_rates"):
        ac.integrate(D, "rk4")
    with pytest.raises(InvalidType, match="method"):
        ac.integrate(D, 3)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="precision"):
        ac.integrate(D, "rv3", precision="f16")
    with pytest.raises(InvalidArgument, match=r"shape \(\.\.\., 3\)"):
        ac.integrate(np.zeros((5, 4)))
    with pytest.raises(InvalidArgument, match=r"\(N, 3\)"):
        ac.integrate(np.zeros((2, 5, 3)))
    with pytest.raises(InvalidArgument, match="empty"):
        ac.integrate(np.zeros((0, 3)))
    with pytest.raises(InvalidArgument, match="at least 3"):
        ac.integrate(np.zeros((2, 3)), "rv3")
    with pytest.raises(InvalidType, match="dtheta"):
        ac.integrate(np.zeros((3, 3), dtype=complex))
    with pytest.raises(InvalidType, match="dtheta"):
        ac.integrate([["a", "b", "c"]] * 3)
    with pytest.raises(InvalidArgument, match="zero quaternion"):
        ac.integrate(D, q0=[0, 0, 0, 0])
    with pytest.raises(NonFiniteError, match="q0"):
        ac.integrate(D, q0=[1, 0, np.nan, 0])
    with pytest.raises(RangeError, match="float32"):
        ac.integrate(np.full((3, 3), 1e39), "rv1", precision="f32")
    with pytest.raises(RangeError, match="too large"):
        ac.integrate(np.full((3, 3), 1e200), "rv1")


def test_failed_update_consumes_nothing() -> None:
    it = ac.Integrator("rv3")
    it.update(D[:2])
    q_before, pending = it.q, it.pending
    bad = D[2:10].copy()
    bad[5] = np.nan
    with pytest.raises(NonFiniteError):
        it.update(bad)
    assert it.pending == pending
    np.testing.assert_array_equal(it.q, q_before)
    np.testing.assert_array_equal(
        np.concatenate([ac.Integrator("rv3").update(D[:2]), it.update(D[2:10])]),
        ac.integrate(D[:10], "rv3"))


def test_rates_interfaces() -> None:
    w = np.array([0.2, -0.1, 0.4])
    om = np.tile(w, (21, 1))
    q = ac.integrate_rates(om, 0.005)  # rk4: rows at h/2 spacing, h = 0.01
    assert q.shape == (10, 4)
    # one dt per row gives the same as the scalar
    np.testing.assert_array_equal(ac.integrate_rates(om, np.full(21, 0.005)), q)
    # streaming rk4 with per-row dt in odd chunks
    it = ac.Integrator("rk4")
    parts = [it.update(om[a:b], dt=np.full(b - a, 0.005)) for a, b in ((0, 2), (2, 7), (7, 21))]
    np.testing.assert_array_equal(np.concatenate(parts), q)
    # increment methods through rates: dtheta = omega * dt
    np.testing.assert_array_equal(ac.integrate_rates(om, 0.01, method="rv3"),
                                  ac.integrate(om * 0.01, "rv3"))
    with pytest.raises(InvalidArgument, match="dt is required"):
        ac.Integrator("rk4").update(om)
    with pytest.raises(InvalidArgument, match="dt must be > 0"):
        ac.integrate_rates(om, -0.01)
    with pytest.raises(InvalidArgument, match="one value per row"):
        ac.integrate_rates(om, np.ones(3))
    with pytest.raises(InvalidArgument, match="at least 3"):
        ac.integrate_rates(om[:2], 0.01)
    with pytest.raises(NonFiniteError, match="dt"):
        ac.integrate_rates(om, np.full(21, np.nan))


def test_fixed_precision_is_the_same_contract() -> None:
    """precision="fixed" everywhere the integrator is: integrate(), integrate_rates() of
    increment methods and Integrator, with the float builds' shapes (float64 out)."""
    from attitude_c import fixedpoint

    d = D[:12] * 0.1
    out = ac.integrate(d, "rv3", precision="fixed")
    assert out.shape == (4, 4) and out.dtype == np.float64
    np.testing.assert_array_equal(out, fixedpoint.integrate(d, "rv3"))
    it = ac.Integrator("rv3", precision="fixed")
    parts = [it.update(d[a:b]) for a, b in ((0, 2), (2, 7), (7, 12))]
    assert [p.shape for p in parts] == [(0, 4), (2, 4), (2, 4)] and it.pending == 0 and it.updates == 4
    np.testing.assert_array_equal(np.concatenate(parts), out)
    np.testing.assert_array_equal(it.q, out[-1])
    assert it.outputs(7) == 2
    one = it.update(d[0])  # one increment: (M, 4) too, M = 0 here
    assert one.shape == (0, 4) and it.pending == 1
    it.reset()
    assert it.pending == 0 and it.updates == 0
    np.testing.assert_array_equal(fixedpoint.Integrator("rv3").update(d), out)
    np.testing.assert_array_equal(ac.integrate_rates(d / 0.01, 0.01, "rv3", precision="fixed"),
                                  ac.integrate(d / 0.01 * 0.01, "rv3", precision="fixed"))
    with pytest.raises(InvalidArgument, match="rk4"):
        ac.integrate_rates(np.zeros((3, 3)), 0.01, precision="fixed")
    with pytest.raises(InvalidArgument, match="rk4"):
        ac.Integrator("rk4", precision="fixed")
    with pytest.raises(InvalidArgument, match="zero quaternion"):
        ac.Integrator("rv3", q0=[0, 0, 0, 0], precision="fixed")


def test_methods_constant() -> None:
    assert ac.METHODS == ("rv1", "rv2", "rv3", "rv3-coning", "rv3-reuse", "rv3-reuse-poly", "rk4")
    assert ac.INCREMENT_METHODS == tuple(m for m in ac.METHODS if m != "rk4")
    from attitude_c._lib import ffi_lib

    # every name has its own enum value, the values cover att_method exactly,
    # and the numbers of the methods that existed before stay as they were (ABI)
    _, lib = ffi_lib("f64")
    codes = {m: ac.method_code(m) for m in ac.METHODS}
    assert sorted(codes.values()) == list(range(lib.ATT_METHOD_COUNT))
    assert codes == {"rv1": 0, "rv2": 1, "rv3": 2, "rv3-coning": 3, "rv3-reuse": 4, "rk4": 5,
                     "rv3-reuse-poly": 6}
    for prec in ("f64", "f32"):
        ffi, lib = ffi_lib(prec)
        assert {m: ac.method_code(m, lib) for m in ac.METHODS} == codes
        # ... and the library's own names (att_integ_method_name) are these
        assert {m: ffi.string(lib.att_integ_method_name(c)).decode() for m, c in codes.items()} \
            == {m: m for m in codes}
    with pytest.raises(InvalidArgument, match="method"):
        ac.method_code("rv3-reuse-old")
    # the simulate command offers exactly these methods
    from attitude_c.cli import simulate

    assert simulate._METHODS == ac.METHODS


def test_demo_command(capsys: pytest.CaptureFixture[str]) -> None:
    from attitude_c.cli import main

    assert main(["demo", "--seconds", "1"]) == 0
    out = capsys.readouterr().out
    for m in ac.INCREMENT_METHODS:
        assert m in out
    with pytest.raises(SystemExit) as ei:  # the shared option validator: a usage error of the parser
        main(["demo", "--beta", "-1"])
    assert ei.value.code == 2
    assert "--beta: must be a finite number > 0" in capsys.readouterr().err


@settings(max_examples=30, deadline=None)
@given(st.sampled_from(ac.METHODS), st.sampled_from(["f64", "f32"]),
       st.lists(st.integers(0, 9), min_size=1, max_size=8))
def test_stream_cut_anywhere_is_bit_identical(method: str, precision: str, cuts: list[int]) -> None:
    """A stream cut at arbitrary points gives exactly the one-shot result."""
    x = RNG.normal(scale=0.3, size=(sum(cuts) + 3, 3))
    dt = np.linspace(0.004, 0.006, len(x))  # per-row spacing (used by rk4 only)
    kw = {"dt": dt} if method == "rk4" else {}
    whole = ac.Integrator(method, precision=precision).update(x, **kw)
    it = ac.Integrator(method, precision=precision)
    parts, i = [], 0
    for c in cuts + [3]:
        parts.append(it.update(x[i:i + c], **({"dt": dt[i:i + c]} if method == "rk4" else {})))
        i += c
    np.testing.assert_array_equal(np.concatenate(parts), whole)


ROTATION_FUNCS = [
    ("quat_to_dcm", (4,)), ("dcm_to_quat", (3, 3)), ("dcm_to_euler", (3, 3)), ("euler_to_dcm", (3,)),
    ("quat_to_euler", (4,)), ("euler_to_quat", (3,)), ("heading", (4,)), ("quat_normalize", (4,)),
    ("rotvec_to_quat", (3,)), ("quat_to_rotvec", (4,)),
]


@pytest.mark.parametrize("precision, dtype", [("f64", np.float64), ("f32", np.float32)])
def test_output_dtype_follows_the_precision(precision: str, dtype: type) -> None:
    """f32 returns the float build's own float32 results; f64 returns float64;
    fixed returns float64 (the Q2.30 values exactly)."""
    x = {(4,): np.array([[0.9, 0.1, -0.2, 0.3]] * 2), (3,): np.array([[0.1, -0.2, 0.3]] * 2),
         (3, 3): ac.euler_to_dcm(np.array([[0.1, -0.2, 0.3]] * 2))}
    for name, tail in ROTATION_FUNCS:
        assert getattr(ac, name)(x[tail], precision=precision).dtype == dtype, name
    assert ac.quat_multiply(x[(4,)], x[(4,)], precision=precision).dtype == dtype
    assert ac.integrate(D, "rv3", precision=precision).dtype == dtype
    assert ac.integrate_rates(D, 0.01, "rk4", precision=precision).dtype == dtype
    it = ac.Integrator("rv1", precision=precision)
    assert it.update(D[0]).dtype == dtype and it.update(D[:1]).dtype == dtype
    assert it.update(D[:0]).dtype == dtype and it.q.dtype == dtype
    assert ac.quat_conj(x[(4,)]).dtype == np.float64


def test_fixed_precision_returns_float64() -> None:
    assert ac.integrate(D, "rv3", precision="fixed").dtype == np.float64


@pytest.mark.parametrize("precision", ["f64", "f32"])
def test_integrate_checks_samples_once_in_c(precision: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """The batch call checks every sample itself: integrate() makes no
    NumPy pass over good data (that pass cost three quarters of its time),
    and a bad sample still gets today's message and index."""
    x = D.astype(np.float32 if precision == "f32" else np.float64)
    calls = []
    real = np.isfinite
    monkeypatch.setattr(np, "isfinite", lambda *a, **k: calls.append(1) or real(*a, **k))
    ac.integrate(x, "rv3", precision=precision)
    ac.Integrator("rv3", precision=precision).update(x)
    assert calls == []
    monkeypatch.undo()
    bad = D.copy()
    bad[22, 2] = np.inf
    with pytest.raises(NonFiniteError, match=r"^dtheta: sample 22 holds NaN or Inf$") as ei:
        ac.integrate(bad, "rv3-reuse", precision=precision)
    assert ei.value.index == 22
    big = D.copy()
    big[4] = 1e39  # finite in float64, not in float32
    if precision == "f32":
        with pytest.raises(RangeError, match=r"^dtheta: sample 4 overflows float32"):
            ac.integrate(big, "rv1", precision="f32")


def test_method_and_precision_are_literal_types() -> None:
    """The annotations are Literal types listing exactly the run-time choices,
    so a type checker rejects method="rv4"."""
    import typing

    hints = typing.get_type_hints(ac.integrate)
    assert typing.get_args(hints["method"]) == ac.METHODS
    assert typing.get_args(hints["precision"]) == ac.PRECISIONS
    # one Integrator contract for every precision (the fixed-point port included)
    assert typing.get_args(typing.get_type_hints(ac.Integrator.__init__)["precision"]) == ac.PRECISIONS
    assert typing.get_args(typing.get_type_hints(ac.quat_to_dcm)["precision"]) == ("f64", "f32")


@pytest.mark.parametrize("precision", ["f64", "f32", "fixed"])
def test_out_gives_identical_results(precision: str) -> None:
    """``out=`` fills the caller's buffer with exactly the values a fresh
    call returns (same C call, so bit-identical) and returns that buffer."""
    dtype = np.float32 if precision == "f32" else np.float64
    x = D.astype(dtype)
    for method in ac.INCREMENT_METHODS:
        want = ac.integrate(x, method, precision=precision)  # type: ignore[arg-type]
        out = np.full_like(want, np.nan)
        got = ac.integrate(x, method, precision=precision, out=out)  # type: ignore[arg-type]
        assert got is out
        np.testing.assert_array_equal(out, want)
        want = ac.integrate_rates(x, 0.01, method, precision=precision)  # type: ignore[arg-type]
        out = np.full_like(want, np.nan)
        assert ac.integrate_rates(x, 0.01, method, precision=precision, out=out) is out  # type: ignore[arg-type]
        np.testing.assert_array_equal(out, want)
    if precision != "fixed":  # rk4 has no fixed-point port here
        for dt in (0.01, 0.01 * (1 + 0.1 * (np.arange(len(x)) % 3))):
            want = ac.integrate_rates(x, dt, "rk4", precision=precision)  # type: ignore[arg-type]
            out = np.full_like(want, np.nan)
            assert ac.integrate_rates(x, dt, "rk4", precision=precision, out=out) is out  # type: ignore[arg-type]
            np.testing.assert_array_equal(out, want)


@pytest.mark.parametrize("precision", ["f64", "f32"])
def test_out_is_validated(precision: str) -> None:
    """A wrong ``out`` is rejected by name before any work, with the expected
    shape or dtype in the message."""
    dtype, other = (np.float32, np.float64) if precision == "f32" else (np.float64, np.float32)
    name = np.dtype(dtype).name
    x = D.astype(dtype)  # 30 increments: rv3 gives 10 updates, rk4 (30 - 1) // 2 = 14
    cases = [
        (np.empty((11, 4), dtype), InvalidArgument, r"^out must have shape \(10, 4\) .*got \(11, 4\)$"),
        (np.empty((10, 3), dtype), InvalidArgument, r"^out must have shape \(10, 4\)"),
        (np.empty(40, dtype), InvalidArgument, r"^out must have shape \(10, 4\)"),
        (np.empty((10, 4), other), InvalidType, rf"^out must have dtype {name} for precision='{precision}'"),
        (np.empty((10, 4), np.int64), InvalidType, rf"^out must have dtype {name}"),
        (np.empty((10, 8), dtype)[:, :4], InvalidArgument, r"^out must be C-contiguous"),
        (np.empty((4, 10), dtype).T, InvalidArgument, r"^out must be C-contiguous"),
        ([[0.0] * 4] * 10, InvalidType, r"^out must be a numpy.ndarray, got list$"),
    ]
    ro = np.empty((10, 4), dtype)
    ro.flags.writeable = False
    cases.append((ro, InvalidArgument, r"^out is read-only$"))
    for out, exc, msg in cases:
        with pytest.raises(exc, match=msg):
            ac.integrate(x, "rv3", precision=precision, out=out)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match=r"^out must have shape \(14, 4\)"):
        ac.integrate_rates(x, 0.01, "rk4", precision=precision, out=np.empty((15, 4), dtype))  # type: ignore[arg-type]
    with pytest.raises(InvalidType, match=r"^out must have dtype"):
        ac.integrate_rates(x, 0.01, "rv1", precision=precision, out=np.empty((30, 4), other))  # type: ignore[arg-type]
    # the output may not alias the input: rv1 writes 4 values per 3 read
    buf = np.zeros((30, 4), dtype)
    with pytest.raises(InvalidArgument, match=r"^out must not share memory with dtheta$"):
        ac.integrate(buf[:, :3], "rv1", precision=precision, out=buf)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match=r"^out must not share memory with omega$"):
        ac.integrate_rates(buf[:, :3], 0.01, "rv1", precision=precision, out=buf)  # type: ignore[arg-type]
    # the integration's own errors still name the sample; out is the caller's
    bad = x.copy()
    bad[7, 1] = np.nan
    with pytest.raises(NonFiniteError, match=r"^dtheta: sample 7 holds NaN or Inf$"):
        ac.integrate(bad, "rv3", precision=precision, out=np.empty((10, 4), dtype))  # type: ignore[arg-type]
