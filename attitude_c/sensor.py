"""Sensor words to body rates and increments, through the C library.

A thin typed layer over ``att_sensor_*`` (``csrc/include/attitude/sensor.h``,
docs/sensor.md): the one implementation of the host's codes → rates step,
shared with ``attitude-rx``. For body axis i reading channel ``axes[i]``::

    value_i = signs[i] · (word / n − zero) · scale      (a gyro: rad/s)
    out     = matrix · (value − bias)                   (default: I, 0)
    Δθ_i    = out_i · period

``n`` is the number of conversions summed into each word (1, or the
stream's OVERSAMPLE report, docs/block.md). ``matrix`` (3 × 3,
dimensionless: misalignment and scale-factor correction, soft iron) and
``bias`` (output units: m/s², µT — hard iron) are the 3x3 correction; a
magnetometer calibration ``m_cal = S (m − h)`` (:mod:`attitude_c.magcal`,
fitted to this sensor's uncorrected values) is ``matrix=S, bias=h``
(:meth:`Sensor.with_magcal`). The NumPy reference is
:func:`attitude_c.reference.sensor_values`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import magcal, names
from ._lib import ffi_lib
from ._validate import integer, real, real_array
from .core import FloatPrecision
from .errors import InvalidArgument, InvalidType, NonFiniteError, RangeError
from .names import raise_for_status

__all__ = ["Sensor", "adc_words"]

_IDENTITY = np.eye(3)

_DTYPES = {"f64": np.float64, "f32": np.float32}


def _triple(x: ArrayLike, name: str) -> NDArray[np.float64]:
    a = real_array(x, name).astype(np.float64)
    if a.shape == ():
        a = np.full(3, float(a))
    if a.shape != (3,):
        raise InvalidArgument(f"{name} must be a number or 3 numbers (X, Y, Z), got shape {a.shape}")
    if not np.isfinite(a).all():
        raise NonFiniteError(f"{name} holds NaN or Inf: {a.tolist()}")
    return a


def adc_words(words: ArrayLike, name: str = "words") -> NDArray[np.uint16]:
    """Check ADC words (M, 3) (integer dtype, 0..65535) and return them as a C-contiguous
    uint16 array; InvalidType, InvalidArgument (shape) or RangeError naming the sample."""
    w = np.asarray(words)
    if w.dtype.kind not in "iu":
        raise InvalidType(f"{name} must be integer ADC words, got dtype {w.dtype}")
    if w.ndim != 2 or w.shape[1] != 3:
        raise InvalidArgument(f"{name} must have shape (M, 3), got {w.shape}")
    if w.size and (w.min() < 0 or w.max() > 0xFFFF):
        i = int(np.argmax(((w < 0) | (w > 0xFFFF)).any(axis=1)))
        raise RangeError(f"{name}: sample {i} = {w[i].tolist()} is not a 16-bit word")
    return np.ascontiguousarray(w, dtype=np.uint16)


class Sensor:
    """One three-axis sensor's calibration (an ``att_sensor``).

    ``zero``: the reading at zero input per channel, in codes of one conversion
    (0..65535; fractional after a calibration); ``scale``: units per code per
    channel (a gyro: rad/s per code; non-zero); ``axes``: the channel each body
    axis reads (a permutation of 0, 1, 2); ``signs``: +1 or −1 per body axis;
    ``precision``: the float build that converts; ``matrix`` (3, 3) and
    ``bias`` (3,): the correction ``out = matrix · (value − bias)`` (``None``:
    identity, zero), |det matrix| ≥ 1 / ``ATT_SENSOR_DET_RECIP`` (1/1000).
    """

    def __init__(self, zero: ArrayLike, scale: ArrayLike, axes: ArrayLike = (0, 1, 2),
                 signs: ArrayLike = (1, 1, 1), precision: FloatPrecision = "f64", *,
                 matrix: ArrayLike | None = None, bias: ArrayLike | None = None) -> None:
        if precision not in _DTYPES:
            raise InvalidArgument(f"precision must be one of {tuple(_DTYPES)}, got {precision!r}")
        self.zero = _triple(zero, "zero")
        self.scale = _triple(scale, "scale")
        self.axes = tuple(int(a) for a in np.asarray(axes).reshape(-1))
        self.signs = tuple(int(s) for s in np.asarray(signs).reshape(-1))
        self.precision: FloatPrecision = precision
        self._ffi, self._lib = ffi_lib(precision)
        self._s: Any = self._ffi.new("att_sensor *")
        if len(self.axes) != 3 or sorted(self.axes) != [0, 1, 2]:
            raise InvalidArgument(f"axes must name each channel 0, 1, 2 once, got {self.axes}")
        if any(s not in (1, -1) for s in self.signs) or len(self.signs) != 3:
            raise InvalidArgument(f"signs must be three of +1 / -1, got {self.signs}")
        st = self._lib.att_sensor_init(self._s, self.zero.tolist(), self.scale.tolist(), list(self.axes),
                                       list(self.signs))
        if st == self._lib.ATT_E_ARG:
            raise InvalidArgument(f"zero must be 0..65535 and scale non-zero, got zero {self.zero.tolist()}, "
                                  f"scale {self.scale.tolist()}")
        raise_for_status(st, "Sensor(zero, scale)")
        self.matrix = _matrix(matrix)
        self.bias = np.zeros(3) if bias is None else _triple(bias, "bias")
        st = self._lib.att_sensor_set_correction(self._s, self.matrix.reshape(9).tolist(), self.bias.tolist())
        if st == self._lib.ATT_E_ARG:
            det_min = 1.0 / names.C["ATT_SENSOR_DET_RECIP"]
            raise InvalidArgument(f"matrix must be invertible, |det| >= {det_min:g}, got det "
                                  f"{np.linalg.det(self.matrix):.6g}: {self.matrix.tolist()}")
        raise_for_status(st, "Sensor(matrix, bias)")

    def with_magcal(self, cal: magcal.Calibration) -> Sensor:
        """This sensor with a magnetometer calibration ``m_cal = S (m − h)`` fitted
        to its uncorrected values as its correction: ``matrix = S``, ``bias = h``
        (replacing any correction it had)."""
        if not isinstance(cal, magcal.Calibration):
            raise InvalidType(f"cal must be an attitude_c.magcal.Calibration, got {type(cal).__name__}")
        return Sensor(self.zero, self.scale, self.axes, self.signs, self.precision, matrix=cal.S, bias=cal.h)

    def increments(self, words: ArrayLike, n: int = 1, period: float = 1.0) -> NDArray[Any]:
        """Words (M, 3) of ``n`` conversions each, sampled every ``period`` s → values
        × period (M, 3) (a gyro: angle increments, rad), in the precision's dtype.
        A word above n × 4095 raises :class:`RangeError` naming the sample."""
        n = integer(n, "n", 0, 255, "C uint8_t")  # the C call checks 1..ATT_BLOCK_OVERSAMPLE_MAX
        period = real(period, "period", "s")  # and period > 0
        w = adc_words(words)
        out = np.empty(w.shape, dtype=_DTYPES[self.precision])
        ffi, lib = self._ffi, self._lib
        err = ffi.new("size_t *")
        st = lib.att_sensor_increments(self._s, ffi.cast("uint16_t *", ffi.from_buffer(w)), w.shape[0], int(n),
                                       float(period), ffi.cast("att_real *", ffi.from_buffer(out)), err)
        if st == lib.ATT_E_RANGE:
            i = int(err[0])
            raise RangeError(f"words: sample {i} = {w[i].tolist()} is above {int(n)} × 4095 (sums of {int(n)} "
                             "12-bit codes), or its value is not finite")
        if st == lib.ATT_E_ARG:
            raise InvalidArgument(f"n must be 1..16 and period > 0, got n={n}, period={period!r}")
        raise_for_status(st, "Sensor.increments")
        return out

    def convert(self, words: ArrayLike, n: int = 1) -> NDArray[Any]:
        """Words (M, 3) of ``n`` conversions each → body values (M, 3) (a gyro: rad/s)."""
        return self.increments(words, n, 1.0)

    def __repr__(self) -> str:
        return (f"Sensor(zero={self.zero.tolist()}, scale={self.scale.tolist()}, axes={self.axes}, "
                f"signs={self.signs}, precision={self.precision!r}, matrix={self.matrix.tolist()}, "
                f"bias={self.bias.tolist()})")


def _matrix(x: ArrayLike | None) -> NDArray[np.float64]:
    if x is None:
        return _IDENTITY.copy()
    a = real_array(x, "matrix").astype(np.float64)
    if a.shape == (9,):
        a = a.reshape(3, 3)
    if a.shape != (3, 3):
        raise InvalidArgument(f"matrix must have shape (3, 3) (or 9 numbers, row-major), got shape {a.shape}")
    if not np.isfinite(a).all():
        raise NonFiniteError(f"matrix holds NaN or Inf: {a.tolist()}")
    return a
