"""The public Python API of the libattitude core (C library through CFFI).

Rotation math (vectorized over leading axes) and the rotation-vector
attitude integrator of docs/integrator.md, in two builds of the same C
source: ``precision="f64"`` (double) and ``precision="f32"`` (float); the
integrator also in the Q-format port, ``precision="fixed"``
(:mod:`attitude_c.fixedpoint`), with the same contract.

Conventions (docs/conventions.md): quaternions ``[λ, p1, p2, p3]`` scalar
first, rotating body vectors into the ENU navigation frame; attitude
matrices ``C = C_b^n`` (…, 3, 3); Euler angles ``[yaw ψ, pitch θ, roll γ]``
of the z-x-y sequence, radians.

Output dtypes: with ``precision="f64"`` (the default) every function
returns float64 arrays; with ``precision="f32"`` float32 arrays (the float
build's own results, not widened); ``integrate(..., precision="fixed")``
returns float64 (the Q2.30 results converted exactly: float32 cannot hold
their 30 fraction bits). ``quat_conj`` returns float64. ``Integrator.q``
and ``Integrator.update`` follow the integrator's precision (float64 for
"fixed").

Method names, their numbers and the samples each consumes per update come
from the library (:mod:`attitude_c.names`); :data:`Method` spells the names
out for type checkers (tests/test_names.py proves they are the library's).
"""

from __future__ import annotations

import math
import threading
from typing import Any, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import names
from ._lib import ffi_lib
from ._validate import real_array as _as_real  # the shared array check (its one place)
from .errors import InvalidArgument, InvalidType, NonFiniteError, RangeError
from .names import INCREMENT_METHODS, METHODS, Method, raise_for_status

__all__ = [
    "INCREMENT_METHODS",
    "METHODS",
    "PRECISIONS",
    "FloatPrecision",
    "Integrator",
    "Method",
    "Precision",
    "dcm_to_euler",
    "dcm_to_quat",
    "euler_to_dcm",
    "euler_to_quat",
    "heading",
    "integrate",
    "integrate_rates",
    "method_code",
    "quat_conj",
    "quat_multiply",
    "quat_normalize",
    "quat_to_dcm",
    "quat_to_euler",
    "quat_to_rotvec",
    "rotvec_to_quat",
]

# Method, METHODS, INCREMENT_METHODS: spelled in attitude_c.names (below the fixed-point
# binding, which core runs for precision="fixed"), the same objects here.
#: Numeric precisions: the two float builds and the fixed-point port.
Precision = Literal["f64", "f32", "fixed"]
PRECISIONS: tuple[Precision, ...] = get_args(Precision)
#: The precisions of the float builds (the rotation functions).
FloatPrecision = Literal["f64", "f32"]

_DTYPES = {"f64": np.float64, "f32": np.float32, "fixed": np.float64}

#: float64, or float32 for ``precision="f32"`` (see the module docstring).
FloatArray = NDArray[np.floating[Any]]


# --------------------------------------------------------------------------
# argument checking (one place for every public function)
# --------------------------------------------------------------------------

def _check_precision(precision: Any, allow_fixed: bool = False) -> Any:
    """Validate ``precision``; the single place where it is checked."""
    if not isinstance(precision, str):
        raise InvalidType(f"precision must be a str, got {type(precision).__name__}")
    allowed = PRECISIONS if allow_fixed else PRECISIONS[:2]
    if precision not in allowed:
        raise InvalidArgument(f"precision must be one of {allowed!r}, got {precision!r}")
    return precision


def _check_method(method: Any, allowed: tuple[str, ...] = METHODS) -> Any:
    if not isinstance(method, str):
        raise InvalidType(f"method must be a str, got {type(method).__name__}")
    if method not in allowed:
        raise InvalidArgument(f"method must be one of {allowed!r}, got {method!r}")
    return method


def method_code(method: str, lib: Any = None) -> int:
    """The ``att_method`` value of ``method`` ("rv3-reuse" → ``ATT_METHOD_RV3_REUSE``),
    read from the compiled library (``lib``: a build to read it from; the
    table of :mod:`attitude_c.names` by default)."""
    _check_method(method)
    name = "ATT_METHOD_" + method.upper().replace("-", "_")
    return int(getattr(lib, name)) if lib is not None else names.C[name]


def _first_bad(flat_ok: Any) -> int:
    """Index of the first False in a boolean array."""
    return int(np.argmin(np.asarray(flat_ok, dtype=bool)))


def _shaped(x: ArrayLike, name: str, tail: tuple[int, ...], what: str,
            allow_empty: bool = True) -> tuple[NDArray[Any], tuple[int, ...]]:
    """Check dtype and shape (..., *tail); return the records (n, prod(tail))
    in their own dtype (no copy when possible) and the leading shape."""
    a = _as_real(x, name)
    nt = len(tail)
    if a.ndim < nt or a.shape[a.ndim - nt:] != tail:
        want = "(..., " + ", ".join(str(t) for t in tail) + ")"
        raise InvalidArgument(f"{name} must have shape {want} ({what}), got {a.shape}")
    lead = a.shape[: a.ndim - nt]
    a = a.reshape(-1, int(np.prod(tail)))
    if a.shape[0] == 0 and not allow_empty:
        raise InvalidArgument(f"{name} is empty: at least one {what} is needed")
    return a, lead


def _nonfinite(name: str, i: int, lead: tuple[int, ...]) -> NonFiniteError:
    where = np.unravel_index(i, lead) if len(lead) > 1 else i
    return NonFiniteError(f"{name}: sample {where} holds NaN or Inf", index=i)


def _records(x: ArrayLike, name: str, tail: tuple[int, ...], what: str,
             allow_empty: bool = True) -> NDArray[np.float64]:
    """Check shape (..., *tail) and finiteness; return float64 (n, prod(tail))."""
    a, lead = _shaped(x, name, tail, what, allow_empty)
    a = np.asarray(a, dtype=np.float64)
    ok = np.isfinite(a).all(axis=1)
    if not ok.all():
        raise _nonfinite(name, _first_bad(ok), lead)
    return a


def _rows(x: ArrayLike, name: str, width: int, what: str) -> NDArray[np.float64]:
    """Strictly (N, width) real and finite; return float64 (N, width). Errors name
    ``name`` (and the first non-finite sample)."""
    shape = np.shape(x)
    if len(shape) != 2 or shape[1] != width:
        raise InvalidArgument(f"{name} must have shape (N, {width}), got {shape}")
    return _records(x, name, (width,), what)


def _to_c(a: NDArray[np.float64], precision: str, name: str) -> NDArray[Any]:
    dt = _DTYPES[precision]
    if dt is np.float32:
        with np.errstate(over="ignore"):
            b = np.ascontiguousarray(a, dtype=np.float32)
        ok = np.isfinite(b).all(axis=1) if b.ndim == 2 else np.isfinite(b)
        if not np.all(ok):
            i = _first_bad(np.atleast_1d(np.asarray(ok, dtype=bool)))
            raise RangeError(f"{name}: sample {i} overflows float32 (precision='f32')", index=i)
        return b
    return np.ascontiguousarray(a, dtype=np.float64)


def _ptr(ffi: Any, a: NDArray[Any]) -> Any:
    return ffi.cast("att_real *", ffi.from_buffer(a))


def _raise(status: int, what: str, index: int | None = None) -> None:
    raise_for_status(status, what, index=index)


# --------------------------------------------------------------------------
# rotation math
# --------------------------------------------------------------------------

#: What ATT_E_ARG means for each conversion's input (quat.h).
_ARG_MEANING = {"att_dcm_to_quat_n": "is not a rotation matrix (|CᵀC − I| above 0.01, or det C ≤ 0)"}


def _convert(cname: str, x: ArrayLike, name: str, tail_in: tuple[int, ...],
             tail_out: tuple[int, ...], what: str, precision: str) -> FloatArray:
    precision = _check_precision(precision)
    a0 = _as_real(x, name)
    recs = _records(a0, name, tail_in, what)
    lead = a0.shape[: a0.ndim - len(tail_in)]
    ffi, lib = ffi_lib(precision)
    a = _to_c(recs, precision, name)
    n = a.shape[0]
    out = np.empty((n, int(np.prod(tail_out)) if tail_out else 1), dtype=_DTYPES[precision])
    if n:
        err = ffi.new("size_t *")
        st = getattr(lib, cname)(_ptr(ffi, a), _ptr(ffi, out), n, err)
        if st != 0:
            i = int(err[0])
            where = np.unravel_index(i, lead) if len(lead) > 1 else i
            if st == lib.ATT_E_ARG:
                raise InvalidArgument(f"{name}: sample {where} "
                                      f"{_ARG_MEANING.get(cname, 'is a zero quaternion')}")
            if st == lib.ATT_E_RANGE and cname == "att_rotvec_to_quat_n":
                raise RangeError(f"{name}: sample {where}: |phi| above {float(lib.att_rotvec_max()):g} rad "
                                 "(quat.h: the input's own rounding would make the quaternion noise)",
                                 index=i)
            _raise(st, name, i)
    return out.reshape(lead + tail_out)


def quat_to_dcm(q: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """Attitude matrix ``C_b^n`` (…, 3, 3) of quaternions (…, 4) (eq. 1 of q/|q|)."""
    return _convert("att_quat_to_dcm_n", q, "q", (4,), (3, 3), "quaternion", precision)


def dcm_to_quat(C: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """Unit quaternion (…, 4), λ ≥ 0, of attitude matrices (…, 3, 3)."""
    return _convert("att_dcm_to_quat_n", C, "C", (3, 3), (4,), "3×3 matrix", precision)


def dcm_to_euler(C: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """Euler angles ``[ψ, θ, γ]`` (…, 3) of attitude matrices (gimbal-lock rule in docs)."""
    return _convert("att_dcm_to_euler_n", C, "C", (3, 3), (3,), "3×3 matrix", precision)


def euler_to_dcm(e: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """``C = R_z(ψ) R_x(θ) R_y(γ)`` (…, 3, 3) of Euler angles ``[ψ, θ, γ]`` (…, 3)."""
    return _convert("att_euler_to_dcm_n", e, "e", (3,), (3, 3), "[yaw, pitch, roll]", precision)


def quat_to_euler(q: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """Euler angles ``[ψ, θ, γ]`` (…, 3) of quaternions (…, 4)."""
    return _convert("att_quat_to_euler_n", q, "q", (4,), (3,), "quaternion", precision)


def euler_to_quat(e: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """Quaternion ``q_z(ψ) ⊗ q_x(θ) ⊗ q_y(γ)`` (…, 4), λ ≥ 0."""
    return _convert("att_euler_to_quat_n", e, "e", (3,), (4,), "[yaw, pitch, roll]", precision)


def heading(x: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """Heading from north, positive toward east, in [0, 2π) (rad).

    ``x`` is quaternions (…, 4) or attitude matrices (…, 3, 3) (told apart
    by the shape: last axis 4 → quaternions)."""
    a = _as_real(x, "x")
    if a.ndim >= 1 and a.shape[-1] == 4:
        return _convert("att_quat_heading_n", a, "x", (4,), (), "quaternion", precision)
    if a.ndim >= 2 and a.shape[-2:] == (3, 3):
        return _convert("att_dcm_heading_n", a, "x", (3, 3), (), "3×3 matrix", precision)
    raise InvalidArgument(
        f"x must be quaternions (..., 4) or attitude matrices (..., 3, 3), got shape {a.shape}")


def quat_multiply(a: ArrayLike, b: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """Hamilton product ``a ⊗ b`` (…, 4) (broadcast over leading axes)."""
    precision = _check_precision(precision)
    aa, bb = np.broadcast_arrays(_as_real(a, "a"), _as_real(b, "b"))
    ra = _records(aa, "a", (4,), "quaternion")
    rb = _records(bb, "b", (4,), "quaternion")
    lead = aa.shape[:-1]
    ffi, lib = ffi_lib(precision)
    ca, cb = _to_c(ra, precision, "a"), _to_c(rb, precision, "b")
    out = np.empty_like(ca)
    if ca.shape[0]:
        err = ffi.new("size_t *")
        st = lib.att_quat_mul_n(_ptr(ffi, ca), _ptr(ffi, cb), _ptr(ffi, out), ca.shape[0], err)
        if st == lib.ATT_E_RANGE:
            raise RangeError(f"a, b: the product of sample {int(err[0])} overflows {precision} "
                             "(finite inputs, infinite result)", index=int(err[0]))
        _raise(st, "a, b", int(err[0]) if st else None)
    return out.reshape(lead + (4,))


def quat_conj(q: ArrayLike) -> FloatArray:
    """Conjugate ``[λ, −p1, −p2, −p3]`` (…, 4)."""
    a = _as_real(q, "q")
    _records(a, "q", (4,), "quaternion")
    return np.asarray(a, dtype=np.float64) * np.array([1.0, -1.0, -1.0, -1.0])


def quat_normalize(q: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """``q / |q|`` (…, 4); a zero quaternion is an error."""
    return _convert("att_quat_normalize_n", q, "q", (4,), (4,), "quaternion", precision)


def rotvec_to_quat(phi: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """Rotation-vector quaternion ``q(Φ)`` of eq. (3) (…, 4) for Φ (…, 3) in rad."""
    return _convert("att_rotvec_to_quat_n", phi, "phi", (3,), (4,), "rotation vector", precision)


def quat_to_rotvec(q: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """Shortest rotation vector (…, 3), |Φ| ≤ π, of quaternions (…, 4)."""
    return _convert("att_quat_to_rotvec_n", q, "q", (4,), (3,), "quaternion", precision)


# --------------------------------------------------------------------------
# the integrator
# --------------------------------------------------------------------------

def _check_q0(q0: ArrayLike | None) -> NDArray[np.float64] | None:
    if q0 is None:
        return None
    a = _as_real(q0, "q0")
    if a.shape != (4,):
        raise InvalidArgument(f"q0 must be one quaternion of shape (4,), got {a.shape}")
    a = a.astype(np.float64)
    if not np.isfinite(a).all():
        raise NonFiniteError("q0 holds NaN or Inf", index=0)
    if not np.any(a):
        raise InvalidArgument("q0 is the zero quaternion (it has no attitude)")
    return a


class Integrator:
    """Streaming attitude integrator: one C state, of any precision.

    ``Integrator(method="rv3", q0=None, precision="f64")``. Feed angle
    increments (increment methods) or rate samples (``rk4``, with ``dt``)
    to :meth:`update`; it returns the attitude after every update completed
    by these samples, as an (M, 4) array, float64 or float32 after the
    precision (M may be 0: rv2/rv3 buffer increments until their frame is
    full, rk4 rows until a step ends). ``precision="fixed"`` runs the
    Q2.30 port (``att_fx_integ``, every increment method; float64 in and
    out, increments limited to ``fixedpoint.DTHETA_MAX``); "f64"/"f32" the
    float builds (``att_integ``).

    Thread safety: one Integrator may be shared by threads. Every method
    and property holds the object's lock for the whole call, so each
    ``update`` is applied whole, in some order, and the counters
    (``updates``, ``pending``) always agree with the samples fed. The
    order of concurrent updates is the order the threads take the lock:
    give each stream its own Integrator when the order matters (it always
    does for attitude). The batch functions (:func:`integrate`,
    :func:`integrate_rates`, the rotation functions) keep no shared state
    and are thread-safe: concurrent calls give bit-identical results to
    sequential ones (tests/test_api_faults.py).
    """

    def __init__(self, method: Method = "rv3", q0: ArrayLike | None = None,
                 precision: Precision = "f64") -> None:
        self.method: Method = _check_method(method)
        self.precision: Precision = _check_precision(precision, allow_fixed=True)
        self._dtype = _DTYPES[self.precision]
        self._lock = threading.RLock()  # the C state and the buffers below are shared by every call
        self._pending_dt: NDArray[np.float64] = np.empty(0)
        if self.precision == "fixed":
            if self.method == "rk4":
                raise InvalidArgument("precision='fixed' does not implement method 'rk4'")
            from ._fixedcore import _Stream

            _check_q0(q0)  # the float builds' checks first: the same errors in every precision
            self._fx: Any = _Stream(self.method, q0)
            return
        self._fx = None
        self._ffi, self._lib = ffi_lib(self.precision)
        self._state = self._ffi.new("att_integ *")
        self._one_in = self._ffi.new("att_real[3]")
        self._one_out = self._ffi.new("att_real[4]")
        self.reset(q0)

    def reset(self, q0: ArrayLike | None = None) -> None:
        """Back to attitude ``q0`` (None = identity), buffered samples dropped."""
        with self._lock:
            self._reset(q0)

    def _reset(self, q0: ArrayLike | None) -> None:
        if self._fx is not None:
            _check_q0(q0)
            self._fx.reset(q0)
            return
        q = _check_q0(q0)
        qp = self._ffi.NULL
        if q is not None:
            qc = _to_c(q.reshape(1, 4), self.precision, "q0")
            qp = _ptr(self._ffi, qc)
        st = self._lib.att_integ_init(self._state, method_code(self.method, self._lib), qp)
        if st == self._lib.ATT_E_ARG:
            raise InvalidArgument("q0 is the zero quaternion (it has no attitude)")
        _raise(st, "q0")
        self._pending_dt = np.empty(0)

    @property
    def q(self) -> FloatArray:
        """Current attitude quaternion (4,), float64 or float32 after the precision."""
        with self._lock:
            if self._fx is not None:
                from ._fixedcore import from_q30

                return from_q30(self._fx.q_q30)
            return np.array([float(self._state.q[i]) for i in range(4)], dtype=self._dtype)

    @property
    def pending(self) -> int:
        """Samples buffered in the state (rv2/rv3 frame, rv3-reuse history, rk4 rows)."""
        with self._lock:
            return int(self._fx.pending if self._fx is not None else self._state.nbuf)

    @property
    def updates(self) -> int:
        """Attitude updates since construction or reset (C counter, wraps)."""
        with self._lock:
            return int(self._fx.updates if self._fx is not None else self._state.updates)

    def outputs(self, n: int) -> int:
        """How many updates ``n`` more samples would complete."""
        with self._lock:
            if self._fx is not None:
                return self._fx.outputs(n)
            return int(self._lib.att_integ_outputs(self._state, int(n)))

    def update(self, x: ArrayLike, dt: ArrayLike | None = None) -> FloatArray:
        """Feed increments Δθ (rad, (3,) or (N, 3)) — or, for ``rk4``, body
        rates ω (rad/s) with ``dt`` — and return the (M, 4) attitudes of the
        updates they complete. On error (NaN/Inf, …) nothing is consumed.

        For rk4, ``dt`` is the sampling interval of the rows (s): a scalar or
        one value per row (dt[i] = time from row i to row i+1). Rows
        alternate step start/end and midpoint; the step of an update is
        h = dt[start] + dt[midpoint].
        """
        with self._lock:
            return self._update(x, dt)

    def _update(self, x: ArrayLike, dt: ArrayLike | None) -> FloatArray:
        if (self.method != "rk4" and dt is None and self._fx is None and isinstance(x, np.ndarray)
                and x.shape == (3,) and x.dtype.kind == "f"):
            return self._update_one(x)
        if self.method == "rk4":
            a, lead = _shaped(x, "omega", (3,), "3-vector per sample")
            return self._update_rates(a, lead, dt)
        if dt is not None:
            raise InvalidArgument(f"dt is only used with method 'rk4', not {self.method!r}")
        a, lead = _shaped(x, "dtheta", (3,), "3-vector per sample")
        return self._update_increments(a, lead)

    def _update_increments(self, a: NDArray[Any], lead: tuple[int, ...],
                           out: NDArray[Any] | None = None) -> FloatArray:
        """``att_integ_batch`` (``att_fx_integ_batch``) on records ``a`` (n, 3) of any real dtype."""
        if self._fx is not None:
            return self._fx.update(_records(a, "dtheta", (3,), "angle increment"), out)
        return self._batch(a, lead, "dtheta", None, out)

    def _batch(self, a: NDArray[Any], lead: tuple[int, ...], name: str,
               h: NDArray[Any] | None, out: NDArray[Any] | None = None) -> FloatArray:
        """One batch call (``att_integ_rk4_batch`` when step sizes ``h`` are
        given). The C call checks every sample (NaN/Inf, divergence) and
        leaves the state as it was on error, so the data get no second pass
        here: only the conversion to the build's dtype when they have another.
        ``out``: a buffer already checked by :func:`_check_out` for exactly
        ``self.outputs(n)`` records; it is filled and returned itself."""
        with np.errstate(over="ignore"):  # finite float64 -> inf float32: found below
            c = np.ascontiguousarray(a, dtype=self._dtype)
        n = c.shape[0]
        given = out is not None
        if out is None:
            out = np.empty((max(self.outputs(n), 1), 4), dtype=self._dtype)
        if n:
            ffi, lib = self._ffi, self._lib
            nout = ffi.new("size_t *")
            err = ffi.new("size_t *")
            if h is None:
                st = lib.att_integ_batch(self._state, _ptr(ffi, c), n, _ptr(ffi, out), nout, err)
            else:
                st = lib.att_integ_rk4_batch(self._state, _ptr(ffi, c), n, _ptr(ffi, h), h.shape[0],
                                             _ptr(ffi, out), nout, err)
            if st < 0:
                i = int(err[0])
                if st == lib.ATT_E_NONFINITE:
                    if np.isfinite(a[i]).all():  # finite as given: lost in the conversion
                        raise RangeError(f"{name}: sample {i} overflows float32 (precision='f32')", index=i)
                    raise _nonfinite(name, i, lead)
                _raise(st, name, i)
            m = int(nout[0])
        else:
            m = 0
        return out if given else out[:m]

    def _update_one(self, x: NDArray[Any]) -> FloatArray:
        """Fast path for one float increment (3,): no array conversions; the C
        call itself rejects NaN/Inf (state untouched) and we name the sample."""
        buf = self._one_in
        buf[0], buf[1], buf[2] = float(x[0]), float(x[1]), float(x[2])
        if self._dtype is np.float32 and not all(map(math.isfinite, (buf[0], buf[1], buf[2]))) \
                and all(map(math.isfinite, (float(x[0]), float(x[1]), float(x[2])))):
            raise RangeError("dtheta: sample 0 overflows float32 (precision='f32')", index=0)
        r = self._lib.att_integ_update(self._state, buf, self._one_out)
        if r == 1:
            o = self._one_out
            return np.array([[o[0], o[1], o[2], o[3]]], dtype=self._dtype)
        if r == 0:
            return np.empty((0, 4), dtype=self._dtype)
        _raise(r, "dtheta", 0)
        raise AssertionError("unreachable")  # pragma: no cover

    def _update_rates(self, a: NDArray[Any], lead: tuple[int, ...], dt: ArrayLike | None,
                      out: NDArray[Any] | None = None) -> FloatArray:
        n = a.shape[0]
        if dt is None:
            raise InvalidArgument("dt is required with method 'rk4' (sampling interval, s)")
        d = _as_real(dt, "dt").astype(np.float64)
        if d.ndim == 0:
            d1 = d.reshape(1)
            if not np.isfinite(d1).all():
                raise NonFiniteError("dt: sample 0 holds NaN or Inf", index=0)
            if n and not d1[0] > 0:
                raise InvalidArgument(f"dt must be > 0: dt[0] = {d1[0]!r}")
            if not len(self._pending_dt) or (self._pending_dt == d1[0]).all():
                # one spacing throughout: every step is h = 2 dt, one value for the C call
                q = self._batch(a, lead, "omega", _to_c((2 * d1).reshape(1, 1), self.precision, "dt")[0],
                                out)
                self._pending_dt = np.full(self.pending, d1[0])
                return q
            d = np.full(n, d1[0])
        elif d.shape != (n,):
            raise InvalidArgument(
                f"dt must be a scalar or one value per row, shape ({n},), got {d.shape}")
        if not np.isfinite(d).all():
            raise NonFiniteError(f"dt: sample {_first_bad(np.isfinite(d))} holds NaN or Inf",
                                 index=_first_bad(np.isfinite(d)))
        if n and not (d > 0).all():
            raise InvalidArgument(f"dt must be > 0: dt[{_first_bad(d > 0)}] = "
                                  f"{d[_first_bad(d > 0)]!r}")
        m = self.outputs(n)
        alld = np.concatenate([self._pending_dt, d])
        h = alld[0: 2 * m: 2] + alld[1: 2 * m: 2] if m else np.ones(1)
        hc = _to_c(h.reshape(-1, 1), self.precision, "dt").reshape(-1)
        q = self._batch(a, lead, "omega", hc, out)
        nb = self.pending
        self._pending_dt = alld[len(alld) - nb:] if nb else np.empty(0)
        return q

    def __repr__(self) -> str:
        return (f"Integrator(method={self.method!r}, precision={self.precision!r}, "
                f"q={self.q.tolist()!r}, pending={self.pending})")


def _check_out(out: Any, m: int, precision: str, source: NDArray[Any], source_name: str) -> NDArray[Any]:
    """Validate a caller's ``out`` buffer: an ndarray of shape (m, 4), the
    precision's dtype, C-contiguous, writeable, not sharing memory with the
    input. Checked before any computation, so a bad ``out`` changes nothing."""
    dtype = np.dtype(np.float64 if precision == "fixed" else _DTYPES[precision])
    if not isinstance(out, np.ndarray):
        raise InvalidType(f"out must be a numpy.ndarray, got {type(out).__name__}")
    if out.dtype != dtype:
        raise InvalidType(f"out must have dtype {dtype.name} for precision={precision!r}, "
                          f"got {out.dtype}")
    if out.shape != (m, 4):
        raise InvalidArgument(f"out must have shape ({m}, 4) (one quaternion per attitude "
                              f"update), got {out.shape}")
    if not out.flags.c_contiguous:
        raise InvalidArgument("out must be C-contiguous (np.empty((M, 4)), not a strided view)")
    if not out.flags.writeable:
        raise InvalidArgument("out is read-only")
    if np.may_share_memory(out, source):
        raise InvalidArgument(f"out must not share memory with {source_name}")
    return out


def integrate(dtheta: ArrayLike, method: Method = "rv3", q0: ArrayLike | None = None,
              precision: Precision = "f64", out: NDArray[Any] | None = None) -> FloatArray:
    """Integrate body angle increments Δθ (N, 3) (rad) from attitude q0.

    Returns the quaternion after each attitude update, (M, 4): float64, or
    float32 with ``precision="f32"`` (give float32 increments then, and no
    conversion copy is made); M = N for rv1 and rv3-reuse, N // 2 for rv2,
    N // 3 for rv3 and rv3-coning (a trailing partial frame is ignored; use
    Integrator to stream). ``precision`` is "f64", "f32" or "fixed" (float64
    results). NaN/Inf raise NonFiniteError naming the first bad sample
    (checked once, by the C call).

    ``out``: optional preallocated result array, a C-contiguous ndarray of
    shape (M, 4) and the result's dtype (float64, float32 for "f32"), not
    overlapping ``dtheta``; it is filled and returned (no allocation: reuse
    one buffer across calls). A wrong ``out`` raises InvalidType (type,
    dtype) or InvalidArgument (shape, layout, read-only, overlap) before any
    work; after an error raised by the integration itself (NaN/Inf,
    divergence) its content is unspecified.
    """
    precision = _check_precision(precision, allow_fixed=True)
    method = _check_method(method, INCREMENT_METHODS + ("rk4",))
    if method == "rk4":
        raise InvalidArgument("method 'rk4' integrates rates: use integrate_rates(omega, dt)")
    a, lead = _shaped(dtheta, "dtheta", (3,), "angle increment", allow_empty=False)
    if len(lead) != 1:
        raise InvalidArgument(f"dtheta must have shape (N, 3), got {np.shape(dtheta)}")
    k = names.samples_per_update(method)
    if a.shape[0] < k:
        raise InvalidArgument(f"method {method!r} needs at least {k} increments "
                              f"per update, got {a.shape[0]}")
    q = _check_q0(q0)
    it = Integrator(method, q, precision)
    if out is not None:
        _check_out(out, it.outputs(a.shape[0]), precision, a, "dtheta")
    with it._lock:  # a fresh object: uncontended; the lock only keeps the invariant simple
        return it._update_increments(a, lead, out)


def integrate_rates(omega: ArrayLike, dt: float | ArrayLike, method: Method = "rk4",
                    q0: ArrayLike | None = None, precision: Precision = "f64",
                    out: NDArray[Any] | None = None) -> FloatArray:
    """Integrate body rates ω (N, 3) (rad/s) sampled every ``dt`` s.

    ``dt``: scalar or one value per row (dt[i] = time from row i to row i+1).
    ``rk4``: rows are at t, t+h/2, t+h, t+3h/2, … (each step end is the
    next step's start), h = dt[2k] + dt[2k+1]; returns (N − 1) // 2
    attitudes. Increment methods: Δθ_i = ω_i · dt_i (ω_i the mean rate of
    interval i), then as :func:`integrate`. ``out``: as in :func:`integrate`
    (shape (M, 4), not overlapping ``omega``).
    """
    precision = _check_precision(precision, allow_fixed=True)
    method = _check_method(method)
    a, lead = _shaped(omega, "omega", (3,), "rate sample", allow_empty=False)
    if len(lead) != 1:
        raise InvalidArgument(f"omega must have shape (N, 3), got {np.shape(omega)}")
    q = _check_q0(q0)
    if method == "rk4" and precision == "fixed":
        raise InvalidArgument("precision='fixed' does not implement method 'rk4'")
    if method != "rk4":
        a = _records(a, "omega", (3,), "rate sample")  # checked here: not by the C rk4 call
        d = _as_real(dt, "dt").astype(np.float64)
        if d.ndim == 0:
            d = np.full(a.shape[0], float(d))
        elif d.shape != (a.shape[0],):
            raise InvalidArgument(
                f"dt must be a scalar or one value per row, shape ({a.shape[0]},), got {d.shape}")
        if not np.isfinite(d).all():
            raise NonFiniteError("dt holds NaN or Inf", index=_first_bad(np.isfinite(d)))
        if not (d > 0).all():
            raise InvalidArgument("dt must be > 0")
        if out is not None and np.may_share_memory(out, omega):
            raise InvalidArgument("out must not share memory with omega")
        return integrate(a * d[:, None], method, q, precision, out)
    if a.shape[0] < 3:
        raise InvalidArgument(f"method 'rk4' needs at least 3 rate rows (t, t+h/2, t+h), "
                              f"got {a.shape[0]}")
    it = Integrator("rk4", q, precision)
    if out is not None:
        _check_out(out, it.outputs(a.shape[0]), precision, a, "omega")
    with it._lock:
        return it._update_rates(a, lead, dt, out)
