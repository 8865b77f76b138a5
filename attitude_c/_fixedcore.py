"""The fixed-point integrator's binding: Q2.30 conversions, the batch
integrator and the streaming state (C ``att_fx_integ``, ``attitude/fixed.h``).

Below :mod:`attitude_c.core`, which runs ``Integrator(..., precision="fixed")``
on :class:`_Stream`; :mod:`attitude_c.fixedpoint` is the public module (it
re-exports these and adds the primitives). The formats' constants and limits
come from the library (:data:`attitude_c.names.C`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._lib import ffi_lib
from .errors import InvalidArgument, InvalidType, NonFiniteError, RangeError
from .names import INCREMENT_METHODS, C, Method, raise_for_status

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
