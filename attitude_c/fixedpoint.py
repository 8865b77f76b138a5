"""Fixed-point (integer Q-format) attitude core, exposed with float boundaries.

The C module ``csrc/src/fixed*.c`` (header ``attitude/fixed.h``) does every
computation in integer arithmetic. This wrapper converts at the boundary:

* inputs (float64, radians / unit quaternions) → Q2.30 integers with
  round-to-nearest (ties toward +inf, like the C code): ``round(x · 2^30)``;
  a value outside the format's documented range raises :class:`RangeError`
  naming the argument and the sample, NaN/Inf raises :class:`NonFiniteError`;
* outputs Q2.30 (quaternions, matrices) or Q4.28 (angles) → float64 by an
  exact division by 2^30 or 2^28.

So ``integrate(dtheta, "rv3")`` here and ``attitude_c.core.integrate(...,
precision="fixed")`` answer the same question as the float builds, with the
accuracy of the Q formats (docs/fixed-point.md); :class:`Integrator` is
``attitude_c.core.Integrator(..., precision="fixed")`` (one contract for
every precision). The ``*_q30`` functions take and return the raw integers
for bit-exact work (tests, firmware vectors). The formats' constants and
limits come from the library (:data:`attitude_c.names.C`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._lib import ffi_lib
from .core import INCREMENT_METHODS
from .core import Integrator as _Integrator
from .errors import InvalidArgument, InvalidType, NonFiniteError, RangeError, raise_for_status
from .names import C, samples_per_update
from .sensor import adc_words

if TYPE_CHECKING:
    from .core import Method

__all__ = [
    "DTHETA_MAX",
    "METHODS",
    "Q28_ONE",
    "Q30_ONE",
    "AdcConverter",
    "Integrator",
    "atan2",
    "dcm_to_euler",
    "from_q28",
    "from_q30",
    "heading",
    "integrate",
    "integrate_q30",
    "quat_multiply",
    "quat_normalize",
    "quat_to_dcm",
    "quat_to_euler",
    "rotation_vectors",
    "rotvec_to_quat",
    "to_q30",
]

#: 1.0 in Q2.30 and in Q4.28 (ATT_FX_Q30_ONE, ATT_FX_Q28_ONE).
Q30_ONE = C["ATT_FX_Q30_ONE"]
Q28_ONE = C["ATT_FX_Q28_ONE"]
_DTHETA_MAX_Q30 = C["ATT_FX_DTHETA_MAX"]
_QUAT_MAX_Q30 = C["ATT_FX_QUAT_MAX"]
#: Largest accepted |Δθ| component (rad): ATT_FX_DTHETA_MAX / 2^30 ≈ 0.4.
DTHETA_MAX = _DTHETA_MAX_Q30 / Q30_ONE

#: Methods with a fixed-point port: every increment method of the float
#: integrator (the att_fx_method value of each is ATT_FX_<NAME>, equal to
#: its att_method value; tests/test_names.py checks both).
METHODS: tuple[str, ...] = INCREMENT_METHODS


def _lib() -> tuple[Any, Any]:
    # the fixed-point module is the same in both builds; use the f64 one
    return ffi_lib("f64")


def _check(status: int, what: str) -> None:
    raise_for_status(status, what)


def _as_float(x: ArrayLike, name: str, last: tuple[int, ...] | None = None) -> NDArray[np.float64]:
    try:
        a = np.asarray(x)
    except Exception as exc:  # pragma: no cover - numpy raises on odd objects
        raise InvalidType(f"{name}: cannot be converted to an array ({exc})") from exc
    if a.dtype.kind not in "biuf":
        raise InvalidType(f"{name}: expected a real numeric array, got dtype {a.dtype}")
    a = np.asarray(a, dtype=np.float64)
    if last is not None and a.shape[a.ndim - len(last):] != last:
        raise InvalidArgument(f"{name}: expected shape (..., {', '.join(map(str, last))}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        bad = np.argwhere(~np.isfinite(a.reshape(-1, *last) if last else a.reshape(-1)))[0][0]
        raise NonFiniteError(f"{name}: non-finite value (NaN or Inf) in sample {int(bad)}", int(bad))
    return a


def to_q30(x: ArrayLike, name: str = "x", limit: float = 2.0) -> NDArray[np.int32]:
    """Float → Q2.30 integers, round to nearest (ties up); |x| must stay below ``limit``."""
    a = _as_float(x, name)
    q = np.floor(a * Q30_ONE + 0.5)
    lim = np.floor(limit * Q30_ONE + 0.5)
    over = np.abs(q) > min(lim, 2**31 - 1)
    if np.any(over):
        idx = np.unravel_index(int(np.argmax(over.reshape(-1))), a.shape)
        raise RangeError(f"{name}: value {a[idx]!r} at index {tuple(int(i) for i in idx)} "
                         f"outside the Q2.30 range ±{limit}", index=int(np.argmax(over.reshape(-1))))
    return q.astype(np.int32)


def from_q30(q: ArrayLike) -> NDArray[np.float64]:
    """Q2.30 integers → float64 (exact)."""
    return np.asarray(q, dtype=np.float64) / Q30_ONE


def from_q28(q: ArrayLike) -> NDArray[np.float64]:
    """Q4.28 integers → float64 (exact)."""
    return np.asarray(q, dtype=np.float64) / Q28_ONE


def _method(method: str) -> int:
    if not isinstance(method, str):
        raise InvalidType(f"method: expected a string, got {type(method).__name__}")
    if method not in METHODS:
        raise InvalidArgument(
            f"method: {method!r} is not available in fixed point; choose one of {sorted(METHODS)}")
    return C["ATT_FX_" + method.upper().replace("-", "_")]


def _dtheta_q30(dtheta: ArrayLike, name: str = "dtheta") -> NDArray[np.int32]:
    a = _as_float(dtheta, name, (3,))
    if a.ndim != 2:
        raise InvalidArgument(f"{name}: expected shape (N, 3), got {a.shape}")
    q = np.floor(a * Q30_ONE + 0.5)
    over = np.any(np.abs(q) > _DTHETA_MAX_Q30, axis=1)
    if np.any(over):
        i = int(np.argmax(over))
        raise RangeError(f"{name}: increment {i} = {a[i].tolist()} exceeds the fixed-point "
                         f"limit |Δθ| ≤ {DTHETA_MAX:.6f} rad per component", index=i)
    return np.ascontiguousarray(q.astype(np.int32))


def _q0_q30(q0: ArrayLike | None) -> NDArray[np.int32] | None:
    if q0 is None:
        return None
    a = _as_float(q0, "q0", (4,))
    if a.shape != (4,):
        raise InvalidArgument(f"q0: expected shape (4,), got {a.shape}")
    n = float(np.sqrt(np.dot(a, a)))
    if n == 0.0:
        raise InvalidArgument("q0: zero quaternion")
    return np.ascontiguousarray(np.floor(a / n * Q30_ONE + 0.5).astype(np.int32))


def _raw_q30(x: ArrayLike, name: str, limit: int, what: str) -> NDArray[np.int32]:
    """Raw Q2.30 integers, refused (never wrapped or truncated) unless every
    value is an integer (integer dtype, or a float holding an integer) with
    |value| ≤ ``limit``; :class:`RangeError` names the first bad record."""
    try:
        a = np.asarray(x)
    except Exception as exc:  # ragged lists and the like
        raise InvalidType(f"{name}: cannot be converted to an array ({exc})") from exc
    if a.dtype.kind == "f":
        recs = a.reshape(a.shape[0], -1) if a.ndim else a.reshape(1, 1)
        ok = np.isfinite(recs) & (recs == np.floor(recs))
        if not ok.all():
            i = int(np.argmin(ok.all(axis=1)))
            raise InvalidArgument(f"{name}: record {i} = {recs[i].tolist()} holds a non-integer: raw "
                                  f"Q2.30 values are integers (use {what} for radians)")
    elif a.dtype.kind not in "iu":
        raise InvalidType(f"{name}: raw Q2.30 values must be integers, got dtype {a.dtype}")
    flat = np.abs(a.astype(np.float64)).reshape(max(a.shape[0], 1) if a.ndim else 1, -1)
    big_rec = (flat > limit).any(axis=1)  # float64: exact below 2^53, far above the limit beyond
    if big_rec.any():
        i = int(np.argmax(big_rec))
        shown = a.reshape(flat.shape)[i].tolist()
        raise RangeError(f"{name}: record {i} = {shown} outside |value| ≤ {limit} "
                         f"({limit / Q30_ONE:.6f} in Q2.30)", index=i)
    return np.ascontiguousarray(a.astype(np.int32))


def integrate_q30(dtheta_q30: ArrayLike, method: str = "rv3",
                  q0_q30: ArrayLike | None = None) -> NDArray[np.int32]:
    """Bit-exact integer form of :func:`integrate`: Q2.30 in, (M, 4) Q2.30 out.

    The raw inputs are checked, never wrapped or truncated: integers (an
    integer dtype, or floats holding integers), increments within
    ``±ATT_FX_DTHETA_MAX`` (:data:`DTHETA_MAX` rad) per component, ``q0_q30``
    within ``±ATT_FX_QUAT_MAX``; else :class:`RangeError` (``.index``: the
    record) or :class:`InvalidArgument`/:class:`InvalidType`."""
    ffi, lib = _lib()
    m = _method(method)
    d = _raw_q30(dtheta_q30, "dtheta_q30", _DTHETA_MAX_Q30, "integrate()")
    if d.ndim != 2 or d.shape[1] != 3:
        raise InvalidArgument(f"dtheta_q30: expected shape (N, 3), got {d.shape}")
    s = ffi.new("att_fx_integ *")
    if q0_q30 is None:
        _check(lib.att_fx_integ_init(s, m, ffi.NULL), "q0")
    else:
        q0 = _raw_q30(q0_q30, "q0_q30", _QUAT_MAX_Q30, "integrate(q0=...)")
        if q0.shape != (4,):
            raise InvalidArgument(f"q0_q30: expected shape (4,), got {q0.shape}")
        _check(lib.att_fx_integ_init(s, m, ffi.cast("int32_t *", q0.ctypes.data)), "q0_q30")
    n = d.shape[0]
    mo = lib.att_fx_integ_outputs(s, n)
    out = np.empty((mo, 4), dtype=np.int32)
    n_out = ffi.new("size_t *")
    err = ffi.new("size_t *")
    st = lib.att_fx_integ_batch(s, ffi.cast("int32_t *", d.ctypes.data), n,
                                ffi.cast("int32_t *", out.ctypes.data), n_out, err)
    if st != 0:
        raise_for_status(st, "dtheta_q30", index=int(err[0]))
    return out[: int(n_out[0])]


def integrate(dtheta: ArrayLike, method: Method = "rv3", q0: ArrayLike | None = None) -> NDArray[np.float64]:
    """Integrate body-frame angle increments (rad, shape (N, 3)) in fixed point.

    Same contract as the float builds: returns the attitude quaternion after
    each update as an (M, 4) float64 array (M = N for rv1 and the reuse forms, N // 2
    for rv2, N // 3 for rv3/rv3-coning). Increments are rounded to Q2.30
    (|Δθ| ≤ :data:`DTHETA_MAX` per component, else :class:`RangeError`
    naming the sample); ``q0`` (default identity) is normalized in float,
    rounded to Q2.30 and normalized again in integers.
    """
    d = _dtheta_q30(dtheta)
    q0i = _q0_q30(q0)
    return from_q30(integrate_q30(d, method, q0i))


class _Stream:
    """One ``att_fx_integ`` state: the fixed-point backend of
    ``core.Integrator(..., precision="fixed")`` (use that class, or :class:`Integrator`)."""

    def __init__(self, method: Method, q0: ArrayLike | None) -> None:
        self._ffi, self._lib_ = _lib()
        self._m = _method(method)
        self._s = self._ffi.new("att_fx_integ *")
        self.updates = 0
        self.reset(q0)

    def reset(self, q0: ArrayLike | None = None) -> None:
        q = _q0_q30(q0)
        ptr = self._ffi.NULL if q is None else self._ffi.cast("int32_t *", q.ctypes.data)
        _check(self._lib_.att_fx_integ_init(self._s, self._m, ptr), "q0")
        self.updates = 0

    def outputs(self, n: int) -> int:
        return int(self._lib_.att_fx_integ_outputs(self._s, int(n)))

    @property
    def pending(self) -> int:
        return int(self._s.nbuf)

    @property
    def q_q30(self) -> NDArray[np.int32]:
        return np.array(list(self._s.q), dtype=np.int32)

    def update(self, dtheta: NDArray[np.float64], out: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        """(n, 3) float64 increments (checked finite) -> the (M, 4) attitudes they complete;
        on an error nothing is consumed (the C batch leaves the state as it was)."""
        d = _dtheta_q30(dtheta)
        n = d.shape[0]
        qo = np.empty((max(self.outputs(n), 1), 4), dtype=np.int32)
        n_out = self._ffi.new("size_t *")
        err = self._ffi.new("size_t *")
        if n:
            st = self._lib_.att_fx_integ_batch(self._s, self._ffi.cast("int32_t *", d.ctypes.data), n,
                                               self._ffi.cast("int32_t *", qo.ctypes.data), n_out, err)
            raise_for_status(st, "dtheta", index=int(err[0]))
        m = int(n_out[0]) if n else 0
        self.updates += m
        res = from_q30(qo[:m])
        if out is None:
            return res
        out[...] = res
        return out


class Integrator(_Integrator):
    """Streaming fixed-point integrator: ``attitude_c.core.Integrator(method, q0,
    precision="fixed")`` (same contract: :meth:`update` returns the (M, 4)
    attitudes, float64), plus the raw Q2.30 attitude :attr:`q_q30`."""

    def __init__(self, method: Method = "rv3", q0: ArrayLike | None = None) -> None:
        super().__init__(method, q0, precision="fixed")

    @property
    def q_q30(self) -> NDArray[np.int32]:
        """Current attitude quaternion (raw Q2.30)."""
        with self._lock:
            return self._fx.q_q30


# -- primitives (vectorized over leading axes by a loop over records) -------

def _records(a: NDArray[np.int32], width: int) -> tuple[NDArray[np.int32], tuple[int, ...]]:
    lead = a.shape[:-1]
    return np.ascontiguousarray(a.reshape(-1, width).astype(np.int32)), lead


def _ptr(ffi: Any, a: NDArray[Any], i: int, width: int, ctype: str = "int32_t *") -> Any:
    return ffi.cast(ctype, a.ctypes.data + a.itemsize * width * i)


def rotation_vectors(dtheta: ArrayLike, method: Method = "rv3") -> NDArray[np.float64]:
    """Φ of every update of ``method`` (M, 3) from increments (N, 3), oldest first,
    from a fresh state (the reuse forms' first two updates use their start-up
    forms), each computed in Q2.30 by ``att_fx_phi`` (round to nearest: the
    integrator itself dithers, docs/fixed-point.md)."""
    ffi, lib = _lib()
    m = _method(method)
    d = _dtheta_q30(dtheta)
    if method in ("rv3-reuse", "rv3-reuse-poly"):
        windows = [(max(0, k - 2), k + 1) for k in range(d.shape[0])]
    else:
        frame = samples_per_update(method)
        windows = [(k, k + frame) for k in range(0, d.shape[0] - frame + 1, frame)]
    out = np.empty((len(windows), 3), dtype=np.int32)
    for j, (a, b) in enumerate(windows):
        w = np.ascontiguousarray(d[a:b])
        _check(lib.att_fx_phi(m, ffi.cast("int32_t *", w.ctypes.data), b - a,
                              ffi.cast("int32_t *", out[j:].ctypes.data)), f"dtheta: update {j}")
    return from_q30(out)


def rotvec_to_quat(phi: ArrayLike) -> NDArray[np.float64]:
    """q(Φ) of eq. (3) for rotation vectors (..., 3) with |Φ|² ≤ 9.6."""
    ffi, lib = _lib()
    a, lead = _records(to_q30(_as_float(phi, "phi", (3,)), "phi"), 3)
    out = np.empty((a.shape[0], 4), dtype=np.int32)
    for i in range(a.shape[0]):
        _check(lib.att_fx_rotvec_to_quat(_ptr(ffi, a, i, 3), _ptr(ffi, out, i, 4)), f"phi[{i}]")
    return from_q30(out).reshape(*lead, 4)


def _quat_q30(q: ArrayLike, name: str) -> NDArray[np.int32]:
    return to_q30(_as_float(q, name, (4,)), name, _QUAT_MAX_Q30 / Q30_ONE)


def quat_multiply(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """a ⊗ b in Q2.30 (components |x| ≤ 1.25), broadcast over leading axes."""
    ffi, lib = _lib()
    qa, qb = np.broadcast_arrays(_quat_q30(a, "a"), _quat_q30(b, "b"))
    ra, lead = _records(qa, 4)
    rb, _ = _records(qb, 4)
    out = np.empty_like(ra)
    for i in range(ra.shape[0]):
        _check(lib.att_fx_quat_mul(_ptr(ffi, ra, i, 4), _ptr(ffi, rb, i, 4), _ptr(ffi, out, i, 4)),
               f"quat_multiply record {i}")
    return from_q30(out).reshape(*lead, 4)


def _quat_map(q: ArrayLike, fn: str, width: int, ctype: str = "int32_t *") -> tuple[NDArray[np.int32], tuple[int, ...]]:
    ffi, lib = _lib()
    a, lead = _records(_quat_q30(q, "q"), 4)
    out = np.empty((a.shape[0], width), dtype=np.int32)
    f = getattr(lib, fn)
    for i in range(a.shape[0]):
        _check(f(_ptr(ffi, a, i, 4), _ptr(ffi, out, i, width)), f"q[{i}]")
    return out, lead


def quat_normalize(q: ArrayLike) -> NDArray[np.float64]:
    """q/|q| computed in integers (no division, no float)."""
    out, lead = _quat_map(q, "att_fx_quat_normalize", 4)
    return from_q30(out).reshape(*lead, 4)


def quat_to_dcm(q: ArrayLike) -> NDArray[np.float64]:
    """Attitude matrix of eq. (1) (..., 3, 3), Q2.30."""
    out, lead = _quat_map(q, "att_fx_quat_to_dcm", 9)
    return from_q30(out).reshape(*lead, 3, 3)


def quat_to_euler(q: ArrayLike) -> NDArray[np.float64]:
    """[yaw ψ, pitch θ, roll γ] (rad) by CORDIC, Q4.28."""
    out, lead = _quat_map(q, "att_fx_quat_to_euler", 3)
    return from_q28(out).reshape(*lead, 3)


def heading(q: ArrayLike) -> NDArray[np.float64]:
    """Heading (−ψ) mod 2π in [0, 2π) (rad), Q4.28."""
    out, lead = _quat_map(q, "att_fx_quat_heading", 1)
    return from_q28(out).reshape(lead)


def dcm_to_euler(C: ArrayLike) -> NDArray[np.float64]:
    """Euler angles of attitude matrices (..., 3, 3) given as floats (→ Q2.30)."""
    ffi, lib = _lib()
    a = _as_float(C, "C", (3, 3))
    ci, _ = _records(to_q30(a.reshape(*a.shape[:-2], 9), "C"), 9)
    lead = a.shape[:-2]
    out = np.empty((ci.shape[0], 3), dtype=np.int32)
    for i in range(ci.shape[0]):
        _check(lib.att_fx_dcm_to_euler(_ptr(ffi, ci, i, 9), _ptr(ffi, out, i, 3)), f"C[{i}]")
    return from_q28(out).reshape(*lead, 3)


def atan2(y: ArrayLike, x: ArrayLike) -> NDArray[np.float64]:
    """CORDIC atan2 of Q2.30 inputs (floats |v| < 2), result in (−π, π]."""
    _, lib = _lib()
    yy, xx = np.broadcast_arrays(to_q30(y, "y"), to_q30(x, "x"))
    out = np.array([lib.att_fx_atan2(int(a), int(b)) for a, b in zip(yy.reshape(-1), xx.reshape(-1))],
                   dtype=np.int64)
    return from_q28(out).reshape(yy.shape)


class AdcConverter:
    """ADC codes → Q2.30 increments (the 8051's "simple data processing").

    ``zero_code`` (codes, per axis, may be fractional: kept as code × 256),
    ``scale`` (rad/s per code, per axis, 0 < scale < 1: kept as scale × 2^32)
    and ``period`` (s, kept in ns) are rounded to the integers the C code
    takes; the gain scale·period is then formed exactly in integers.
    """

    def __init__(self, zero_code: ArrayLike, scale: ArrayLike, period: float) -> None:
        ffi, lib = _lib()
        z = np.broadcast_to(_as_float(zero_code, "zero_code"), (3,))
        sc = np.broadcast_to(_as_float(scale, "scale"), (3,))
        p = float(_as_float(period, "period"))
        if np.any(z < 0) or np.any(z >= 65536):
            raise InvalidArgument(f"zero_code: expected codes in [0, 65536), got {z.tolist()}")
        if np.any(sc <= 0) or np.any(sc >= 1):
            raise InvalidArgument(f"scale: expected 0 < scale < 1 rad/s per code, got {sc.tolist()}")
        if not (0 < p < 4.29):
            raise InvalidArgument(f"period: expected 0 < period < 4.29 s, got {p}")
        self.zero_q8 = np.floor(z * 256 + 0.5).astype(np.int32)
        self.scale_q32 = np.floor(sc * 2**32 + 0.5).astype(np.uint32)
        self.period_ns = round(p * 1e9)
        self._ffi, self._lib_ = ffi, lib
        self._a = ffi.new("att_fx_adc *")
        _check(lib.att_fx_adc_init(self._a, ffi.new("int32_t[3]", self.zero_q8.tolist()),
                                   ffi.new("uint32_t[3]", self.scale_q32.tolist()), self.period_ns),
               "AdcConverter(zero_code, scale, period)")

    def convert_q30(self, codes: ArrayLike) -> NDArray[np.int32]:
        """Codes (N, 3) → Q2.30 increments (N, 3); RangeError names the sample."""
        cc = adc_words(codes, "codes")
        out = np.empty(cc.shape, dtype=np.int32)
        for i in range(cc.shape[0]):
            st = self._lib_.att_fx_adc_convert(self._a, _ptr(self._ffi, cc, i, 3, "uint16_t *"),
                                               _ptr(self._ffi, out, i, 3))
            _check(st, f"codes: sample {i}")
        return out

    def convert(self, codes: ArrayLike) -> NDArray[np.float64]:
        """Codes (N, 3) → increments in rad (float64 of the Q2.30 results)."""
        return from_q30(self.convert_q30(codes))
