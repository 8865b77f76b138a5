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

import numpy as np
import pytest

from attitude_c import core
from attitude_c import fixedpoint as fx
from attitude_c.errors import InvalidArgument, InvalidType, RangeError

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
