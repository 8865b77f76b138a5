"""The argument checks every public function shares: real and integer scalars, real arrays.

One place, so that every entry point refuses the same inputs with the same words — an
:class:`~attitude_c.errors.InvalidType` or :class:`~attitude_c.errors.InvalidArgument`
naming the argument — and none of them lets through a NumPy or Python error from inside
(a ``TypeError`` of ``np.isfinite``, an ``OverflowError`` of ``float()``), a number
silently changed (a complex value's imaginary part dropped, a string parsed) or a
masked array's mask ignored:

* :func:`real` — a real scalar (``int``, ``float`` or a NumPy real; not ``bool``, ``str``
  or complex) as a finite ``float``, optionally within a range (NaN/Inf:
  :class:`~attitude_c.errors.NonFiniteError`; an int beyond float64:
  :class:`~attitude_c.errors.RangeError`; both are ``InvalidArgument``);
* :func:`integer` — an integer scalar (``int`` or a NumPy integer; not ``bool``), within
  a range (a C field's type: :data:`C_INT_RANGES`);
* :func:`real_array` — an array of real numbers (integer or float dtype; a list of Python
  ints beyond int64 is converted to float64 when it fits); a masked array only when
  nothing is masked.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidArgument, InvalidType, NonFiniteError, RangeError

__all__ = ["C_INT_RANGES", "integer", "real", "real_array", "time_steps"]

#: The range of each C integer type a settings field or argument may have (LP64, as the
#: library is built on every host it supports).
C_INT_RANGES = {"int": (-(2**31), 2**31 - 1), "unsigned int": (0, 2**32 - 1), "long": (-(2**63), 2**63 - 1),
                "unsigned long": (0, 2**64 - 1), "short": (-(2**15), 2**15 - 1),
                "unsigned short": (0, 2**16 - 1)}

_REAL_TYPES = (int, float, np.integer, np.floating)


def _shown(v: Any) -> str:
    """``v`` for a message: a huge integer by its size, not its 400 digits."""
    if isinstance(v, (int, np.integer)) and abs(int(v)) >= 2**64:
        return f"an integer of {int(v).bit_length()} bits"
    return repr(v) if not isinstance(v, (float, np.floating)) else f"{float(v):g}"


def _domain(lo: float, hi: float, lo_open: bool) -> str:
    if lo == -math.inf and hi == math.inf:
        return "finite"
    if hi == math.inf:
        return f"finite and {'>' if lo_open else '>='} {lo:g}"
    return f"finite and in {'(' if lo_open else '['}{lo:g}, {hi:g}]"


def real(v: Any, name: str, unit: str = "", *, lo: float = -math.inf, hi: float = math.inf,
         lo_open: bool = False, domain: str | None = None) -> float:
    """``v`` as a finite float within [lo, hi] ((lo, hi] with ``lo_open``); the errors name
    ``name``, the ``unit`` and the ``domain`` (a description of the range; by default
    written from lo and hi)."""
    u = f" ({unit})" if unit else ""
    if isinstance(v, bool) or not isinstance(v, _REAL_TYPES):
        raise InvalidType(f"{name} must be a real number{u}, got {type(v).__name__}")
    want = f"{name} must be {domain or _domain(lo, hi, lo_open)}{u}, got {_shown(v)}"
    try:
        f = float(v)
    except OverflowError:  # an int beyond float64
        raise RangeError(want + " (beyond float64)") from None
    if not math.isfinite(f):
        raise NonFiniteError(want)
    if not ((f > lo if lo_open else f >= lo) and f <= hi):
        raise InvalidArgument(want)
    return f


def integer(v: Any, name: str, lo: int, hi: int, what: str = "") -> int:
    """``v`` as an int in lo..hi (a C field: :data:`C_INT_RANGES`); ``what`` is added to
    the range error (e.g. "C unsigned int")."""
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
        raise InvalidType(f"{name} must be an integer, got {type(v).__name__}")
    i = int(v)
    if not lo <= i <= hi:
        raise InvalidArgument(f"{name} must be in {lo}..{hi}{f' ({what})' if what else ''}, got {_shown(i)}")
    return i


def real_array(x: ArrayLike, name: str) -> NDArray[Any]:
    """Array of a real numeric dtype (bool, complex, object, str rejected), as given (no
    copy when possible); Python ints too large for int64 become float64 (RangeError
    beyond float64); a masked array with a masked value is refused."""
    if isinstance(x, np.ma.MaskedArray):
        masked = int(np.ma.getmaskarray(x).sum())
        if masked:
            raise InvalidArgument(f"{name} is a masked array with {masked} masked value(s): the mask "
                                  "would be ignored; fill them (.filled()) or leave those samples out")
        x = np.ma.getdata(x)
    try:
        a = np.asarray(x)
    except Exception as exc:  # ragged lists and the like
        raise InvalidArgument(f"{name} cannot be converted to an array: {exc}") from exc
    if a.dtype.kind == "O" and a.size and all(type(v) in (int, float) for v in a.flat):
        try:
            a = a.astype(np.float64)
        except OverflowError:
            raise RangeError(f"{name} holds an integer beyond float64's range") from None
    if a.dtype.kind not in "iuf":
        raise InvalidType(f"{name} must hold real numbers (integer or float dtype), got dtype {a.dtype}")
    return a


def time_steps(dt: ArrayLike | None, n: int, rate: float | None, dtype: Any) -> NDArray[Any]:
    """A streaming filter's steps for n samples: ``dt`` (a scalar or n values, s), or
    1/``rate`` when ``dt`` is None; contiguous in ``dtype`` (the C build's att_real)."""
    if dt is None:
        if rate is None:
            raise InvalidArgument("dt is required when the filter has no rate")
        return np.array([1.0 / rate], dtype=dtype)
    d = real_array(dt, "dt").astype(np.float64).ravel()
    if d.size not in (1, n):
        raise InvalidArgument(f"dt must be a scalar or have one value per sample ({n}), got {d.size}")
    return np.ascontiguousarray(d, dtype=dtype)
