"""Magnetometer calibration (C library ``att_magcal_*``, docs/aiding.md).

Hard iron h and soft iron S with ``m_cal = S (m − h)``, so that the
corrected field has the same norm B in every direction:

* :func:`fit` — ellipsoid fit of raw samples (N, 3) by the streaming C fit
  (fixed-size moments, no sample buffer): ``model`` "offset" (hard iron
  only, S = I), "diagonal" (per-axis scale) or "full" (symmetric soft
  iron); refused (:class:`~attitude_c.errors.InvalidArgument`) when the
  samples do not span enough directions or are not on an ellipsoid;
* :func:`fit_minmax_2d` — the MEMS AHRS paper's 2-D min/max method for a
  level turn (offsets and scale of x and y only);
* :func:`apply` — ``S (m − h)`` over (..., 3);
* :class:`MagCal` — the streaming fit itself (add samples, solve any time).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._lib import ffi_lib
from ._validate import C_INT_RANGES, integer, real
from .core import FloatArray, FloatPrecision, _check_precision, _ptr, _records, _shaped, _to_c
from .errors import InvalidArgument, InvalidType
from .names import raise_for_status

__all__ = ["MODELS", "Calibration", "MagCal", "Model", "apply", "fit", "fit_minmax_2d"]

#: Ellipsoid models of :func:`fit`.
Model = Literal["offset", "diagonal", "full"]
MODELS: tuple[Model, ...] = get_args(Model)
_DT = {"f64": np.float64, "f32": np.float32}


@dataclass(frozen=True)
class Calibration:
    """A fitted calibration: ``m_cal = S (m − h)``, ``|m_cal| = field`` on the fit."""

    model: str
    """"offset", "diagonal", "full" or "minmax-2d"."""
    h: NDArray[np.float64]
    """Hard-iron offset (3,), input units."""
    S: NDArray[np.float64]
    """Soft-iron correction (3, 3), symmetric, det 1 (diagonal for minmax-2d)."""
    field: float
    """Field strength B (input units); the horizontal field for minmax-2d."""
    residual: float
    """Fit quality: ≈ RMS of |m_cal|/B − 1 (0 for minmax-2d)."""
    span: float
    """√(λ_min/tr) of the samples' covariance (full sphere 0.577; minmax-2d: range ratio)."""
    n: int
    """Samples used."""

    def apply(self, m: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
        """``S (m − h)`` (see :func:`apply`)."""
        return apply(self, m, precision)


def _model_code(model: Any, lib: Any) -> int:
    if not isinstance(model, str):
        raise InvalidType(f"model must be a str, got {type(model).__name__}")
    if model not in MODELS:
        raise InvalidArgument(f"model must be one of {MODELS!r}, got {model!r}")
    return int(getattr(lib, "ATT_MAGCAL_" + model.upper()))


def _result(r: Any, model: str) -> Calibration:
    return Calibration(model, np.array(list(r.h), dtype=np.float64),
                       np.array(list(r.S), dtype=np.float64).reshape(3, 3), float(r.field),
                       float(r.residual), float(r.span), int(r.n))


class MagCal:
    """The streaming ellipsoid fit (``att_magcal``): :meth:`add` raw samples
    (any unit), :meth:`solve` a model whenever enough have arrived. The state
    is the 35 moments of degree ≤ 4 (fixed size, no sample buffer)."""

    def __init__(self, min_samples: int = 20, min_span: float = 0.1, precision: FloatPrecision = "f64") -> None:
        self.precision = _check_precision(precision)
        self._ffi, self._lib = ffi_lib(self.precision)
        s = self._ffi.new("att_magcal_settings *")
        s.min_samples = integer(min_samples, "min_samples", 10, C_INT_RANGES["unsigned int"][1], "C unsigned int")
        s.min_span = real(min_span, "min_span", lo=0.0, hi=0.577)
        self._c = self._ffi.new("att_magcal *")
        raise_for_status(self._lib.att_magcal_init(self._c, s), "MagCal")

    @property
    def n(self) -> int:
        """Samples added so far."""
        return int(self._c.n)

    def add(self, m: ArrayLike) -> None:
        """Add raw samples (3,) or (N, 3); NaN/Inf raise NonFiniteError naming
        the sample (none of the batch is added then)."""
        a, _ = _shaped(m, "m", (3,), "field sample")
        a = _to_c(_records(a, "m", (3,), "field sample"), self.precision, "m")
        if a.shape[0]:
            raise_for_status(self._lib.att_magcal_add_n(self._c, _ptr(self._ffi, a), a.shape[0], self._ffi.NULL),
                             "MagCal.add")

    def solve(self, model: Model = "full") -> Calibration:
        """Fit ``model`` to the samples so far (the state is kept)."""
        code = _model_code(model, self._lib)
        r = self._ffi.new("att_magcal_result *")
        raise_for_status(self._lib.att_magcal_solve(self._c, code, r), f"magcal fit ({model})")
        return _result(r, model)


def fit(m: ArrayLike, model: Model = "full", precision: FloatPrecision = "f64", *,
        min_samples: int = 20, min_span: float = 0.1) -> Calibration:
    """Fit an ellipsoid ``model`` to raw field samples ``m`` (N, 3) (any unit).

    Raises InvalidArgument when there are fewer than ``min_samples`` samples
    (ATT_AID_E_FEW), when they do not span enough directions (span <
    ``min_span``, ATT_AID_E_SPAN: e.g. a level turn only — use
    :func:`fit_minmax_2d` for that) or do not lie on an ellipsoid
    (ATT_AID_E_FIT)."""
    mc = MagCal(min_samples, min_span, precision)
    mc.add(m)
    return mc.solve(model)


def fit_minmax_2d(m: ArrayLike, precision: FloatPrecision = "f64") -> Calibration:
    """The MEMS AHRS paper's min/max method on a level turn ``m`` (N, 3): x and
    y offsets at mid-range, the smaller range scaled up to the larger."""
    precision = _check_precision(precision)
    ffi, lib = ffi_lib(precision)
    a, _ = _shaped(m, "m", (3,), "field sample")
    a = _to_c(_records(a, "m", (3,), "field sample"), precision, "m")
    c = ffi.new("att_magcal2d *")
    lib.att_magcal2d_init(c)
    for i in range(a.shape[0]):
        lib.att_magcal2d_add(c, _ptr(ffi, a[i]))
    r = ffi.new("att_magcal_result *")
    raise_for_status(lib.att_magcal2d_solve(c, r), "magcal fit_minmax_2d")
    return _result(r, "minmax-2d")


def apply(cal: Calibration, m: ArrayLike, precision: FloatPrecision = "f64") -> FloatArray:
    """``S (m − h)`` for raw samples ``m`` (..., 3) with the C apply function."""
    precision = _check_precision(precision)
    if not isinstance(cal, Calibration):
        raise InvalidType(f"cal must be a Calibration, got {type(cal).__name__}")
    ffi, lib = ffi_lib(precision)
    a0, lead = _shaped(m, "m", (3,), "field sample")
    a = _to_c(_records(a0, "m", (3,), "field sample"), precision, "m")
    r = ffi.new("att_magcal_result *")
    r.h = [float(x) for x in cal.h]
    r.S = [float(x) for x in np.asarray(cal.S).reshape(9)]
    r.field = cal.field
    out = np.empty_like(a)
    if a.shape[0]:
        err = ffi.new("size_t *")
        st = lib.att_magcal_apply_n(r, _ptr(ffi, a), _ptr(ffi, out), a.shape[0], err)
        raise_for_status(st, "magcal apply", index=int(err[0]))
    return out.reshape(lead + (3,))
