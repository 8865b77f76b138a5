"""The UAV thesis's own EKF, for reproduction (``csrc/include/attitude/ahrs_thesis.h``).

State: the attitude quaternion and the gyro bias (7 states); time update by
the thesis's RK4 with the bias-corrected gyro; measurement: the Gauss–Newton
quaternion from the accelerometer and magnetometer (``attitude_c.gauss_newton``),
sign-aligned to the prediction (thesis sec. 3.2.3, eq. 3.45–3.57). It is the
thesis's design with its limits (no disturbance rejection, the Gauss–Newton
outliers); the library's filter is :mod:`attitude_c.ahrs`. docs/ahrs.md,
"The thesis's EKF".

Units: gyro rad/s, specific force any unit (+g up at rest), field any unit.
Quaternions scalar first, body → ENU.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _settings
from ._lib import ffi_lib
from ._validate import real, real_array
from .core import _rows
from .errors import InvalidArgument
from .names import raise_for_status

__all__ = ["SETTINGS", "ThesisEkfResult", "ahrs_thesis", "default_settings", "run"]

FloatArray = NDArray[np.float64]
Precision = Literal["f64", "f32"]

_SPEC = _settings.SettingsSpec(
    "att_tekf_settings", "att_tekf_default_settings", "att_tekf_check_settings", label="thesis-EKF",
    domain=("ahrs_thesis.h: gyr_noise, meas_noise, init_q_sigma > 0; bias_noise, init_bias_sigma >= 0; "
            "|declination| <= pi; gn_max_iter 1..1000"),
    nested={"gn": ("max_iter",)})

#: Real-valued settings (fields of ``att_tekf_settings``, read from the library on
#: first use); besides them ``gn_max_iter``, the Gauss–Newton iteration limit
#: (``settings.gn.max_iter``, 1..1000).
SETTINGS: Sequence[str] = _settings.SettingNames(_SPEC, "real")

_DTYPES = {"f64": np.float64, "f32": np.float32}


@dataclass(frozen=True)
class ThesisEkfResult:
    """Output of :func:`run`."""

    q: FloatArray          #: (N, 4) attitude after each sample (body → ENU)
    bias: FloatArray       #: (3,) final gyro-bias estimate, rad/s
    gn_skipped: int        #: samples whose measurement update was skipped (Gauss–Newton failed)


def default_settings() -> dict[str, Any]:
    """The library's defaults (``att_tekf_default_settings``)."""
    return _settings.defaults(_SPEC)


def run(gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike, rate: float | None = None,
        dt: ArrayLike | None = None, q0: ArrayLike | None = None, precision: Precision = "f64",
        **settings: Any) -> ThesisEkfResult:
    """Run the thesis's EKF over N samples; see :func:`ahrs_thesis`."""
    if precision not in _DTYPES:
        raise InvalidArgument(f"precision must be 'f64' or 'f32', got {precision!r}")
    g, a, m = _rows(gyr, "gyr", 3, "angular rate"), _rows(acc, "acc", 3, "specific force"), _rows(mag, "mag", 3, "field")
    n = g.shape[0]
    if a.shape[0] != n or m.shape[0] != n:
        raise InvalidArgument(f"gyr, acc and mag must have the same number of samples, got "
                              f"{n}, {a.shape[0]}, {m.shape[0]}")
    dtype = _DTYPES[precision]
    if dt is None:
        if rate is None:
            raise InvalidArgument("give rate (Hz) or dt (s)")
        d = np.array([1.0 / real(rate, "rate", "Hz", lo=0.0, lo_open=True)], dtype=dtype)
    else:
        d = np.ascontiguousarray(real_array(dt, "dt").astype(np.float64).ravel(), dtype=dtype)
        if d.size not in (1, n):
            raise InvalidArgument(f"dt must be a scalar or have one value per sample ({n}), got {d.size}")
    ffi, lib = ffi_lib(precision)
    s_set = _settings.fill(ffi, lib, _SPEC, settings)
    state = ffi.new("att_tekf *")
    qp = ffi.NULL
    if q0 is not None:
        qa = real_array(q0, "q0").astype(np.float64)
        if qa.shape != (4,):
            raise InvalidArgument(f"q0 must have shape (4,), got {qa.shape}")
        qp = ffi.new("att_real[4]", [float(v) for v in qa])
    st = lib.att_tekf_init(state, s_set, qp)
    if st != 0:
        raise_for_status(st, "q0")
    gc, ac, mc = (np.ascontiguousarray(x, dtype=dtype) for x in (g, a, m))
    out = np.empty((n, 4), dtype=dtype)
    err = ffi.new("size_t *")

    def p(x: NDArray[Any]) -> Any:
        return ffi.cast("att_real *", ffi.from_buffer(x))

    st = lib.att_tekf_batch(state, p(gc), p(ac), p(mc), n, p(d), d.size, p(out), err)
    if st != 0:
        i = int(err[0])
        if st == lib.ATT_E_TEKF_DT:
            raise InvalidArgument(f"dt: sample {i}: the time step must be finite and > 0")
        raise_for_status(st, "ahrs_thesis", index=i)
    b = ffi.new("att_real[3]")
    lib.att_tekf_bias(state, b)
    return ThesisEkfResult(q=out.astype(np.float64), bias=np.array(list(b), dtype=np.float64),
                           gn_skipped=int(lib.att_tekf_gn_skipped(state)))


def ahrs_thesis(gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike, rate: float | None = None,
                dt: ArrayLike | None = None, q0: ArrayLike | None = None, precision: Precision = "f64",
                **settings: Any) -> FloatArray:
    """The thesis's EKF over N samples: (N, 3) gyr [rad/s], acc, mag → (N, 4) quaternions.

    ``rate`` (Hz) or ``dt`` (s, scalar or per sample) gives the step; ``q0``
    the initial attitude (default: aligned from the first sample's acc and
    mag). Settings: :data:`SETTINGS` and ``gn_max_iter`` (ahrs_thesis.h).
    Returned as float64 whatever the precision.
    """
    return run(gyr, acc, mag, rate=rate, dt=dt, q0=q0, precision=precision, **settings).q
