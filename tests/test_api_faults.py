"""The API never returns a silent wrong number, and says which thread-safety
it gives (issue 17, items 8 and 9).

Each test is a fault reproduced on the code before the fix: a finite input
outside the function's documented domain that used to come back as NaN, Inf
or a plausible but meaningless number. Truth here is the documented limit
(csrc/include/attitude/quat.h, integrator.h, fixed.h), never the code.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
import threading
import warnings

import numpy as np
import pytest

import attitude_c as ac
from attitude_c import core, denoise
from attitude_c import fixedpoint as fx
from attitude_c.errors import InvalidArgument, InvalidType, RangeError
from attitude_c.sensor import Sensor

PRECISIONS = ("f64", "f32")


# ---- item 8: inputs and outputs checked -----------------------------------

@pytest.mark.parametrize("precision", PRECISIONS)
def test_rotvec_to_quat_huge_is_refused_not_nan(precision: str) -> None:
    # before: [nan nan nan nan] (|phi|^2 overflows)
    with pytest.raises(RangeError) as ei:
        core.rotvec_to_quat([[0.1, 0, 0], [1e300 if precision == "f64" else 1e30, 0, 0]], precision)
    assert ei.value.index == 1
    # the documented limit itself (2^16 rad) passes, just above fails
    q = core.rotvec_to_quat([65536.0, 0, 0], precision)
    assert np.all(np.isfinite(q))
    with pytest.raises(RangeError):
        core.rotvec_to_quat([65536.0 * 1.01, 0, 0], precision)


@pytest.mark.parametrize("precision", PRECISIONS)
def test_quat_multiply_overflow_is_refused_not_inf(precision: str) -> None:
    big = 1e200 if precision == "f64" else 1e30  # squares overflow the type (1.8e308, 3.4e38)
    a = np.array([[1.0, 0, 0, 0], [big, 0, 0, 0]])
    with pytest.raises(RangeError) as ei:
        core.quat_multiply(a, a, precision)  # before: [inf, 0, 0, 0]
    assert ei.value.index == 1


@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("C", [np.zeros((3, 3)), 2 * np.eye(3), np.diag([1.0, 1.0, -1.0]),
                               np.full((3, 3), 0.5)],
                         ids=["zero", "scaled", "reflection", "garbage"])
def test_dcm_to_quat_of_no_rotation_is_refused(C: np.ndarray, precision: str) -> None:
    # before: the zero matrix gave the identity quaternion
    with pytest.raises(InvalidArgument, match="not a rotation matrix"):
        core.dcm_to_quat(C, precision)


def test_dcm_to_quat_accepts_nearly_orthogonal() -> None:
    # an integrated matrix 0.3 % off orthogonal: still the quaternion of the nearby rotation
    C = core.euler_to_dcm([0.3, -0.2, 0.1]) * np.array([1.003, 1.0, 1.0])[:, None]
    q = core.dcm_to_quat(C)
    ref = core.euler_to_quat([0.3, -0.2, 0.1])
    # first-order error of a 0.3 % row scaling on the angle: ≤ 0.003 rad
    assert np.linalg.norm(q - ref) < 3e-3


@pytest.mark.parametrize("precision", ("f64", "f32", "fixed"))
@pytest.mark.parametrize("method", core.INCREMENT_METHODS)
def test_integrate_refuses_increments_beyond_pi(method: str, precision: str) -> None:
    # before: 1e20 rad per sample (f64) returned a finite quaternion
    d = np.full((12, 3), 0.01)
    d[7] = [1e20, 0.0, 0.0]
    with pytest.raises(RangeError) as ei:
        core.integrate(d, method, precision=precision)
    assert ei.value.index == 7  # the offending sample, not the end of its frame
    if precision == "fixed":
        return  # its own, tighter limit (0.4 rad per component): tests/test_fixed.py
    d[7] = [0.0, 3.2, 0.0]  # just above pi
    with pytest.raises(RangeError) as ei:
        core.integrate(d, method, precision=precision)
    assert ei.value.index == 7
    d[7] = [0.0, 3.1, 0.0]  # just below: accepted
    assert np.all(np.isfinite(core.integrate(d, method, precision=precision)))


def test_streaming_integrator_names_the_sample_and_keeps_its_state() -> None:
    it = core.Integrator("rv3")
    it.update(np.full((2, 3), 0.01))
    before = (it.q.copy(), it.pending, it.updates)
    with pytest.raises(RangeError) as ei:
        it.update(np.array([[0.01, 0, 0], [0.01, 0, 0], [4.0, 0, 0]]))
    assert ei.value.index == 2
    assert (it.q.tolist(), it.pending, it.updates) == (before[0].tolist(), before[1], before[2])


def test_rk4_refuses_rates_beyond_pi_per_half_step() -> None:
    omega = np.tile([0.0, 0.0, 1.0], (5, 1))
    omega[3] = [0.0, 700.0, 0.0]  # 700 rad/s × 0.005 s = 3.5 rad between rows > pi
    with pytest.raises(RangeError) as ei:
        core.integrate_rates(omega, 0.005, "rk4")
    assert ei.value.index == 3


def test_raw_q30_entry_refuses_wrap_and_truncation() -> None:
    one = [[5, 0, 0]] * 3
    # before: 2**32 + 5 wrapped to 5 (the same attitudes as `one`)
    with pytest.raises(RangeError) as ei:
        fx.integrate_q30(np.array([[5, 0, 0], [2**32 + 5, 0, 0], [5, 0, 0]]), "rv1")
    assert ei.value.index == 1
    # before: 0.3 truncated to 0
    with pytest.raises(InvalidArgument, match="non-integer"):
        fx.integrate_q30(np.array([[0.3, 0, 0]] * 3), "rv1")
    with pytest.raises(InvalidType):
        fx.integrate_q30(np.array([["a", "b", "c"]]), "rv1")
    # the fixed-point limit itself: ATT_FX_DTHETA_MAX passes, one LSB more fails
    lim = round(fx.DTHETA_MAX * fx.Q30_ONE)
    fx.integrate_q30(np.array([[lim, 0, 0]]), "rv1")
    with pytest.raises(RangeError):
        fx.integrate_q30(np.array([[lim + 1, 0, 0]]), "rv1")
    with pytest.raises(RangeError):
        fx.integrate_q30(np.array(one), "rv1", q0_q30=np.array([2**31 + 5, 0, 0, 0], dtype=np.int64))
    # integers given as floats holding integers are still accepted
    assert np.array_equal(fx.integrate_q30(np.array(one, dtype=float), "rv1"), fx.integrate_q30(one, "rv1"))


# ---- issue 29 item 13: edge types get the library's own error -----------------

def _imu(n: int = 20) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n samples at rest, level, field north and down (a valid 9-axis input)."""
    return (np.tile([0.001, 0.0, 0.0], (n, 1)), np.tile([0.0, 0.0, 9.81], (n, 1)),
            np.tile([0.0, 20.0, -40.0], (n, 1)))


def _masked(a: np.ndarray) -> np.ma.MaskedArray:
    out = np.ma.masked_array(a.copy())
    out[min(3, len(out) - 1)] = np.ma.masked
    return out


G_, A_, M_ = _imu()
BIG = 10**400  # an int beyond float64 (float() raises OverflowError)
CPLX = np.complex128(0.01 + 1e-3j)  # as an array: NumPy's float cast drops the 1e-3j
Q1 = np.tile([1.0, 0.0, 0.0, 0.0], (20, 1))

#: (call, error class, the argument the message must name); every one raised a NumPy or
#: Python error from inside, or was accepted with a value changed, before (issue 29 item 13)
EDGE_CASES = {
    "Ahrs(rate=10**400)": (lambda: ac.Ahrs(rate=BIG), InvalidArgument, "rate"),
    "ahrs_thesis(rate=10**400)": (lambda: ac.ahrs_thesis(G_, A_, M_, rate=BIG), InvalidArgument, "rate"),
    "aiding_delay(rate=10**400)": (lambda: ac.aiding_delay(G_, M_, Q1, BIG), InvalidArgument, "rate"),
    "Ahrs.update(dt=10**400)": (lambda: ac.Ahrs().update(G_[0], A_[0], M_[0], dt=BIG), InvalidArgument, "dt"),
    "ahrs(dt=10**400)": (lambda: ac.ahrs(G_, A_, M_, dt=BIG), InvalidArgument, "dt"),
    "ahrs_thesis(dt=10**400)": (lambda: ac.ahrs_thesis(G_, A_, M_, dt=BIG), InvalidArgument, "dt"),
    "integrate_rates(dt=10**400)": (lambda: ac.integrate_rates(G_, BIG, "rv1"), InvalidArgument, "dt"),
    "Ahrs.update(dt=complex)": (lambda: ac.Ahrs().update(G_[0], A_[0], M_[0], dt=CPLX), InvalidType, "dt"),
    "ahrs(dt=complex array)": (lambda: ac.ahrs(G_, A_, M_, dt=np.full(20, CPLX)), InvalidType, "dt"),
    "ahrs_thesis(dt=complex array)": (lambda: ac.ahrs_thesis(G_, A_, M_, dt=np.full(20, CPLX)), InvalidType,
                                      "dt"),
    "ahrs(dt='0.01')": (lambda: ac.ahrs(G_, A_, M_, dt="0.01"), InvalidType, "dt"),
    "Ahrs.update(dt='0.01')": (lambda: ac.Ahrs().update(G_[0], A_[0], M_[0], dt="0.01"), InvalidType, "dt"),
    "ahrs_thesis(dt='0.01')": (lambda: ac.ahrs_thesis(G_, A_, M_, dt="0.01"), InvalidType, "dt"),
    "Ahrs(q0=strings)": (lambda: ac.Ahrs(q0=["1", "0", "0", "0"]), InvalidType, "q0"),
    "align(declination=10**400)": (lambda: ac.align(A_, M_, BIG), InvalidArgument, "declination"),
    "triad(declination=10**400)": (lambda: ac.triad(A_, M_, BIG), InvalidArgument, "declination"),
    "gauss_newton(declination=10**400)": (lambda: ac.gauss_newton(A_, M_, None, BIG), InvalidArgument,
                                          "declination"),
    "align_static(declination=10**400)": (lambda: ac.align_static(A_, M_, declination=BIG), InvalidArgument,
                                          "declination"),
    "gauss_newton(tol_step=10**400)": (lambda: ac.gauss_newton(A_, M_, tol_step=BIG), InvalidArgument,
                                       "tol_step"),
    "align_static(min_samples=2**64)": (lambda: ac.align_static(A_, M_, min_samples=2**64), InvalidArgument,
                                        "min_samples"),
    "align_static(max_acc_spread=10**400)": (lambda: ac.align_static(A_, M_, max_acc_spread=BIG),
                                             InvalidArgument, "max_acc_spread"),
    "magcal.fit(min_samples=2**64)": (lambda: ac.magcal.fit(M_, min_samples=2**64), InvalidArgument,
                                      "min_samples"),
    "magcal.fit(min_span=10**400)": (lambda: ac.magcal.fit(M_, min_span=BIG), InvalidArgument, "min_span"),
    "Ahrs(acc_tau=10**400)": (lambda: ac.Ahrs(rate=100.0, acc_tau=BIG), InvalidArgument, "acc_tau"),
    "Sensor.increments(n=2**64)": (lambda: Sensor(zero=2048, scale=0.01).increments(np.full((2, 3), 2048), n=2**64),
                                   InvalidArgument, "n"),
    "denoise.universal_threshold(n=2**64)": (lambda: denoise.universal_threshold(1.0, 2**64),
                                             InvalidArgument, "n"),
    "ahrs(masked gyr)": (lambda: ac.ahrs(_masked(G_), A_, M_, rate=100.0), InvalidArgument, "gyr"),
    "Ahrs.update(masked row)": (lambda: ac.Ahrs(rate=100.0).update(G_[0], _masked(A_[0]), M_[0]),
                                InvalidArgument, "acc"),
    "integrate(masked)": (lambda: ac.integrate(_masked(G_), "rv1"), InvalidArgument, "dtheta"),
    "align(masked)": (lambda: ac.align(_masked(A_), M_), InvalidArgument, "f"),
    "quat_to_euler(masked)": (lambda: ac.quat_to_euler(_masked(Q1)), InvalidArgument, "q"),
}


@pytest.mark.parametrize("case", list(EDGE_CASES))
def test_edge_types_get_the_librarys_error_naming_the_argument(case: str) -> None:
    call, exc, name = EDGE_CASES[case]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a ComplexWarning is a value silently changed
        with pytest.raises(exc, match=rf"^{name}\b"):
            call()


def test_rate_beyond_int64_is_a_number() -> None:
    """2**64 Hz is finite and > 0 (the documented domain): taken as the float it is,
    not a NumPy TypeError (np.isfinite of a Python int beyond uint64)."""
    assert ac.Ahrs(rate=2**64).rate == 2.0**64
    assert ac.ahrs(G_, A_, M_, rate=2**64).shape == (20, 4)
    assert ac.ahrs_thesis(G_, A_, M_, rate=2**64).shape == (20, 4)


def test_masked_array_with_nothing_masked_is_its_data() -> None:
    q = ac.ahrs(G_, A_, M_, rate=100.0)
    assert np.array_equal(ac.ahrs(np.ma.masked_array(G_), A_, np.ma.masked_array(M_), rate=100.0), q)
    assert np.array_equal(ac.integrate(np.ma.masked_array(G_), "rv1"), ac.integrate(G_, "rv1"))


# ---- item 9: thread safety -----------------------------------------------

def _chunks() -> list[np.ndarray]:
    rng = np.random.default_rng(17)
    return [rng.normal(0.0, 0.01, (3000, 3)) for _ in range(8)]


@pytest.mark.parametrize("precision", ("f64", "f32", "fixed"))
def test_batch_functions_bit_identical_under_8_threads(precision: str) -> None:
    """integrate and the rotation functions keep no shared state: 8 threads
    calling them at once get exactly the sequential results."""
    data = _chunks()
    expect = [(core.integrate(d, "rv3", precision=precision),
               core.quat_to_euler(core.rotvec_to_quat(d)),
               core.dcm_to_quat(core.quat_to_dcm(core.rotvec_to_quat(d)))) for d in data]
    got: list[object] = [None] * 8
    barrier = threading.Barrier(8)

    def work(k: int) -> None:
        barrier.wait()
        out = []
        for _ in range(5):
            d = data[k]
            out = [core.integrate(d, "rv3", precision=precision),
                   core.quat_to_euler(core.rotvec_to_quat(d)),
                   core.dcm_to_quat(core.quat_to_dcm(core.rotvec_to_quat(d)))]
        got[k] = out

    ts = [threading.Thread(target=work, args=(k,)) for k in range(8)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    for k in range(8):
        for a, b in zip(got[k], expect[k]):  # type: ignore[call-overload]
            assert np.array_equal(a, b)


@pytest.mark.system
def test_shared_integrator_is_consistent_under_8_threads() -> None:
    """One Integrator fed by 8 threads: before the lock this corrupted the
    heap (free(): invalid pointer: one thread sized its output for the frame
    state another thread had just changed) or left the counters off. Run in
    a child so that a crash is a failure, not the end of the test run."""
    code = textwrap.dedent("""
        import threading, numpy as np
        from attitude_c import core
        for method, dt in (("rv3", None), ("rv2", None), ("rk4", 0.001)):
            it = core.Integrator(method)
            d = np.tile([0.0, 0.0, 1e-3], (4, 1))  # 4 samples: never a whole number of frames
            def work():
                for _ in range(300):
                    it.update(d, dt) if dt else it.update(d)
            ts = [threading.Thread(target=work) for _ in range(8)]
            [t.start() for t in ts]
            [t.join() for t in ts]
            ref = core.Integrator(method)
            ref.update(np.tile(d, (8 * 300, 1)), dt) if dt else ref.update(np.tile(d, (8 * 300, 1)))
            assert (it.updates, it.pending) == (ref.updates, ref.pending), (method, it.updates, ref.updates)
            # one axis: the rotations commute, so the order of the threads does not matter
            assert np.allclose(it.q, ref.q, atol=1e-9), (method, it.q, ref.q)  # 2400 updates x ulp
        print("ok")
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                          check=False)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr[-2000:]
