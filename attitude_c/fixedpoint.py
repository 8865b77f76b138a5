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

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._fixedcore import (
    _QUAT_MAX_Q30,
    DTHETA_MAX,
    METHODS,
    Q28_ONE,
    Q30_ONE,
    _as_float,
    _check,
    _dtheta_q30,
    _lib,
    _method,
    from_q28,
    from_q30,
    integrate,
    integrate_q30,
    to_q30,
)
from .core import Integrator as _Integrator
from .errors import InvalidArgument
from .names import Method, samples_per_update
from .sensor import adc_words

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
