"""Static attitude from specific force and magnetic field (C library, docs/aiding.md).

:func:`align` (roll and pitch from the specific force, tilt-compensated
heading), :func:`triad`, :func:`gauss_newton` (the UAV thesis' iteration,
defects fixed) and :func:`align_static` (the averaged static window with
its moving-start check), over NumPy arrays: ``f``, ``m`` of shape (..., 3)
give quaternions (..., 4), scalar first, body → ENU (docs/conventions.md).
``precision="f32"`` runs the float build and returns float32.

Errors: a bad argument raises :class:`~attitude_c.errors.InvalidArgument` /
:class:`~attitude_c.errors.InvalidType` naming it; a sample the solver
refuses (zero vector, specific force parallel to the field, no
convergence...) raises the status' exception naming the sample, unless
``return_status=True``: then the refused samples' rows are NaN and the
per-sample C status codes come back too (0 = OK; names in
:func:`attitude_c.names.status_name`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal, get_args, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._lib import ffi_lib
from ._validate import C_INT_RANGES, integer, real, real_array
from .core import FloatArray, FloatPrecision, _check_precision, _ptr, _records, _shaped, _to_c
from .errors import InvalidArgument
from .names import raise_for_status

__all__ = [
    "GN_METHODS",
    "AlignStats",
    "GNInfo",
    "GNMethod",
    "align",
    "align_static",
    "gauss_newton",
    "triad",
]

#: Gauss–Newton variants: the full iteration (eq. 3.39) or the simplified
#: Newton of eq. 3.40 (the start's Jacobian kept).
GNMethod = Literal["gauss-newton", "simplified"]
GN_METHODS: tuple[GNMethod, ...] = get_args(GNMethod)
_DT = {"f64": np.float64, "f32": np.float32}


def _pair(f: ArrayLike, m: ArrayLike | None, precision: str) -> tuple[Any, Any, tuple[int, ...]]:
    a, lead = _shaped(f, "f", (3,), "specific-force sample")
    fa = _to_c(_records(a, "f", (3,), "specific-force sample"), precision, "f")
    if m is None:
        return fa, None, lead
    b, lead_m = _shaped(m, "m", (3,), "field sample")
    if lead_m != lead:
        raise InvalidArgument(f"f and m must have the same shape, got {np.shape(f)} and {np.shape(m)}")
    ma = _to_c(_records(b, "m", (3,), "field sample"), precision, "m")
    return fa, ma, lead


def _declination(d: Any) -> float:
    return real(d, "declination", "rad", lo=-math.pi, hi=math.pi, domain="a finite angle in [-pi, pi]")


def _finish(q: NDArray[Any], status: NDArray[np.intc], lead: tuple[int, ...], what: str,
            return_status: bool) -> Any:
    bad = status != 0
    if bad.any():
        if not return_status:
            i = int(np.argmax(bad))
            raise_for_status(int(status[i]), what, index=i)
        q[bad] = np.nan
    q = q.reshape(lead + (4,))
    if return_status:
        return q, status.reshape(lead).astype(np.int32)
    return q


def _two_vector(cname: str, what: str, f: ArrayLike, m: ArrayLike | None, declination: float,
                precision: str, return_status: bool) -> Any:
    precision = _check_precision(precision)
    d = _declination(declination)
    fa, ma, lead = _pair(f, m, precision)
    ffi, lib = ffi_lib(precision)
    n = fa.shape[0]
    q = np.zeros((n, 4), dtype=_DT[precision])
    status = np.zeros(n, dtype=np.intc)
    if n:
        mp = _ptr(ffi, ma) if ma is not None else ffi.NULL
        getattr(lib, cname)(_ptr(ffi, fa), mp, d, _ptr(ffi, q), n, ffi.cast("int *", ffi.from_buffer(status)))
    return _finish(q, status, lead, what, return_status)


@overload
def align(f: ArrayLike, m: ArrayLike | None = ..., declination: float = ...,
          precision: FloatPrecision = ..., *, return_status: Literal[False] = ...) -> FloatArray: ...
@overload
def align(f: ArrayLike, m: ArrayLike | None = ..., declination: float = ...,
          precision: FloatPrecision = ..., *, return_status: Literal[True]) -> tuple[FloatArray, NDArray[np.int32]]: ...
def align(f: ArrayLike, m: ArrayLike | None = None, declination: float = 0.0,
          precision: FloatPrecision = "f64", *, return_status: bool = False) -> Any:
    """Initial alignment (``att_align_accmag``): roll and pitch from the
    specific force ``f`` (..., 3) (any unit; at rest it points up), heading
    from the field ``m`` (..., 3) (calibrated, any unit) levelled by them,
    plus ``declination`` (rad, magnetic north east of true north positive).
    ``m=None``: six-axis, yaw 0. Returns q (..., 4)."""
    return _two_vector("att_align_accmag_n", "align", f, m, declination, precision, return_status)


@overload
def triad(f: ArrayLike, m: ArrayLike, declination: float = ..., precision: FloatPrecision = ...,
          *, return_status: Literal[False] = ...) -> FloatArray: ...
@overload
def triad(f: ArrayLike, m: ArrayLike, declination: float = ..., precision: FloatPrecision = ...,
          *, return_status: Literal[True]) -> tuple[FloatArray, NDArray[np.int32]]: ...
def triad(f: ArrayLike, m: ArrayLike, declination: float = 0.0, precision: FloatPrecision = "f64",
          *, return_status: bool = False) -> Any:
    """TRIAD with gravity the primary vector (``att_triad``): the same
    arguments and result as :func:`align` (``m`` required)."""
    if m is None:
        raise InvalidArgument("m is required by triad (use align(f) for a six-axis alignment)")
    return _two_vector("att_triad_n", "triad", f, m, declination, precision, return_status)


@dataclass(frozen=True)
class GNInfo:
    """Per-sample outcome of :func:`gauss_newton` (shapes: the samples' leading shape)."""

    status: NDArray[np.int32]
    """C status (0 = converged)."""
    iterations: NDArray[np.int32]
    """Iterations done (accepted and rejected steps)."""
    residual: NDArray[np.float64]
    """|r| at the returned (or last) iterate (unitless: unit vectors)."""


_GN_FIELDS = ("max_iter", "tol_residual", "tol_step", "accept_residual", "damping", "max_step", "singular_tol")


def gauss_newton(f: ArrayLike, m: ArrayLike, q0: ArrayLike | None = None, declination: float = 0.0,
                 method: GNMethod = "gauss-newton", precision: FloatPrecision = "f64",
                 *, return_info: bool = False, **settings: float) -> Any:
    """Gauss–Newton quaternion (``att_gn_solve``) from ``f``, ``m`` (..., 3),
    starting at ``q0`` ((..., 4) per sample, or one (4,) for all; None: the
    closed-form TRIAD attitude, from which every well-posed sample converges;
    ``[1, 0, 0, 0]`` is the thesis' cold start). ``method``: "gauss-newton" (eq. 3.39, damped) or "simplified"
    (eq. 3.40). Keyword settings (``att_gn_settings``; the defaults of
    ``att_gn_defaults``): max_iter, tol_residual, tol_step, accept_residual,
    damping, max_step, singular_tol. Returns q (..., 4), or (q, GNInfo) with
    ``return_info=True`` (then samples that fail are NaN rows, not errors)."""
    precision = _check_precision(precision)
    d = _declination(declination)
    if not isinstance(method, str) or method not in GN_METHODS:
        raise InvalidArgument(f"method must be one of {GN_METHODS!r}, got {method!r}")
    fa, ma, lead = _pair(f, m, precision)
    n = fa.shape[0]
    ffi, lib = ffi_lib(precision)
    s = ffi.new("att_gn_settings *")
    lib.att_gn_defaults(s)
    s.method = lib.ATT_GN_SIMPLIFIED if method == "simplified" else lib.ATT_GN_GAUSS_NEWTON
    for k, v in settings.items():
        if k not in _GN_FIELDS:
            raise InvalidArgument(f"unknown Gauss-Newton setting {k!r} (one of {_GN_FIELDS!r})")
        if k == "max_iter":
            fv = real(v, k)  # an integral float (20.0) is taken too
            s.max_iter = integer(int(fv) if fv.is_integer() else v, k, 1, 1000)
        else:
            setattr(s, k, real(v, k, lo=0.0))
    q0p: Any = ffi.NULL
    if q0 is not None:
        qa = real_array(q0, "q0")
        if qa.shape == (4,):
            qa = np.broadcast_to(qa, (n, 4))
        qr, _ = _shaped(qa, "q0", (4,), "start quaternion")
        if qr.shape[0] != n:
            raise InvalidArgument(f"q0 must have shape (4,) or {lead + (4,)}, got {np.shape(q0)}")
        q0a = _to_c(_records(qr, "q0", (4,), "start quaternion"), precision, "q0")
        if n and not np.all(np.any(q0a != 0, axis=1)):
            raise InvalidArgument(f"q0: sample {int(np.argmin(np.any(q0a != 0, axis=1)))} is the zero quaternion")
        q0p = _ptr(ffi, q0a)
    q = np.zeros((n, 4), dtype=_DT[precision])
    status = np.zeros(n, dtype=np.intc)
    its = np.zeros(n, dtype=np.uintc)
    res = np.zeros(n, dtype=_DT[precision])
    if n:
        st = lib.att_gn_solve_n(_ptr(ffi, fa), _ptr(ffi, ma), d, q0p, s, _ptr(ffi, q), n,
                                ffi.cast("int *", ffi.from_buffer(status)),
                                ffi.cast("unsigned int *", ffi.from_buffer(its)), _ptr(ffi, res))
        if st == lib.ATT_E_ARG and not status.any():
            raise InvalidArgument(f"Gauss-Newton settings out of range: {settings!r}")
    if not return_info:
        return _finish(q, status, lead, "gauss_newton", False)
    qo = _finish(q, status, lead, "gauss_newton", True)[0]
    return qo, GNInfo(status.reshape(lead).astype(np.int32), its.reshape(lead).astype(np.int32),
                      res.reshape(lead).astype(np.float64))


@dataclass(frozen=True)
class AlignStats:
    """What the static window measured (``att_align_window_result``)."""

    n: int
    acc_spread: float
    """rad: RMS deviation of f about its mean over |mean f|."""
    mag_spread: float
    """rad: the same for the field (0 without a field)."""
    gyr_std: float
    """rad/s: RMS deviation of the rate about its mean (0 without rates)."""
    gyr_mean: float
    """rad/s: |mean rate| (0 without rates)."""
    status: int
    """C status of the solve (0 = OK; ATT_AID_E_MOVING: a spread above its limit)."""


def align_static(acc: ArrayLike, mag: ArrayLike | None = None, gyr: ArrayLike | None = None,
                 declination: float = 0.0, precision: FloatPrecision = "f64", *,
                 min_samples: int = 50, max_acc_spread: float = 0.02, max_mag_spread: float = 0.05,
                 max_gyr_std: float = 0.05, max_gyr_mean: float = 0.2,
                 return_stats: bool = False) -> Any:
    """Average a static window (``att_align_window_*``): ``acc`` (N, 3),
    optional ``mag`` (N, 3) and ``gyr`` (N, 3, rad/s); refuse a moving start
    (ATT_AID_E_MOVING raises InvalidArgument) and return q (4,) of the
    means, or (q, AlignStats) with ``return_stats=True`` (then a refused
    window gives a NaN q and its status instead of an error). The limits
    are those of ``att_align_window_settings`` (units there)."""
    precision = _check_precision(precision)
    d = _declination(declination)
    a = _records(_shaped(acc, "acc", (3,), "specific-force sample")[0], "acc", (3,), "specific-force sample")
    n = a.shape[0]
    others: list[NDArray[Any] | None] = []
    for name, x in (("gyr", gyr), ("mag", mag)):
        if x is None:
            others.append(None)
            continue
        b = _records(_shaped(x, name, (3,), "sample")[0], name, (3,), "sample")
        if b.shape[0] != n:
            raise InvalidArgument(f"{name} must have as many rows as acc ({n}), got {b.shape[0]}")
        others.append(_to_c(b, precision, name))
    a = _to_c(a, precision, "acc")
    ffi, lib = ffi_lib(precision)
    st = ffi.new("att_align_window_settings *")
    lib.att_align_window_defaults(st)
    st.min_samples = integer(min_samples, "min_samples", 2, C_INT_RANGES["unsigned int"][1], "C unsigned int")
    for k, v in (("max_acc_spread", max_acc_spread), ("max_mag_spread", max_mag_spread),
                 ("max_gyr_std", max_gyr_std), ("max_gyr_mean", max_gyr_mean)):
        setattr(st, k, real(v, k, lo=0.0, lo_open=True))
    st.declination_rad = d
    w = ffi.new("att_align_window *")
    raise_for_status(lib.att_align_window_init(w, st), "align_static settings")
    g, mg = others
    for i in range(n):
        lib.att_align_window_add(w, _ptr(ffi, g[i]) if g is not None else ffi.NULL, _ptr(ffi, a[i]),
                                 _ptr(ffi, mg[i]) if mg is not None else ffi.NULL)
    q = np.full(4, np.nan, dtype=_DT[precision])
    status = int(lib.att_align_window_solve(w, _ptr(ffi, q)))
    if not return_stats:
        raise_for_status(status, "align_static")
        return q
    r = ffi.new("att_align_window_result *")
    if lib.att_align_window_stats(w, r) != 0:
        return q, AlignStats(n, math.nan, math.nan, math.nan, math.nan, status)
    if status != 0:
        q[:] = np.nan
    return q, AlignStats(int(r.n), float(r.acc_spread), float(r.mag_spread), float(r.gyr_std),
                         float(r.gyr_mean), status)
