"""The MEMS AHRS paper's nine-state filter with GNSS-velocity aiding (``csrc/include/attitude/ahrs_gnss9.h``).

A strapdown attitude and horizontal velocity, and a low-order Kalman filter
on their errors: X = [δψ, δV_E, δV_N, φ_E, φ_N, φ_U, ε_x, ε_y, ε_z]
(the magnetic heading's Markov error, the velocity errors, the misalignment,
the gyro drifts), measured by the SINS velocity minus the GNSS velocity and
by the SINS heading minus the magnetic heading, with feedback (MEMS AHRS
paper, sec. 1 and 3.3, eq. 7–8). It is the paper's design with its limits;
the choices it leaves open are tabled in docs/gnss-paper-filter.md.

Units: gyro rad/s, specific force m/s² (+g up at rest), velocity m/s
(east, north), heading rad from north toward east, time s. Quaternions
scalar first, body → ENU.

* :class:`Gnss9` — streaming: IMU samples, then :meth:`Gnss9.gnss` and
  :meth:`Gnss9.heading` when a measurement arrives;
* :func:`ahrs_gnss9` — batch: IMU samples with their time stamps, GNSS
  samples with their own (``t_gnss``, ``v_gnss``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _settings
from ._lib import ffi_lib
from ._validate import real, real_array, time_steps
from .core import _rows
from .errors import InvalidArgument
from .names import raise_for_status

__all__ = ["SETTINGS", "Gnss9", "Gnss9Result", "ahrs_gnss9", "default_settings", "gnss_schedule"]

FloatArray = NDArray[np.float64]
Precision = Literal["f64", "f32"]

_SPEC = _settings.SettingsSpec(
    "att_g9_settings", "att_g9_default_settings", "att_g9_check_settings", label="GNSS nine-state",
    domain=("ahrs_gnss9.h: noises, mag_tau, init sigmas (but init_drift_sigma) > 0; drift_noise, "
            "init_drift_sigma, max_gnss_age >= 0; kf_period 1..1000"),
    field_fn="att_g9_check_settings_field")

#: Settings (fields of ``att_g9_settings``, read from the library on first use).
SETTINGS: Sequence[str] = _settings.SettingNames(_SPEC)

_DTYPES = {"f64": np.float64, "f32": np.float32}


def default_settings() -> dict[str, Any]:
    """The library's defaults (``att_g9_default_settings``)."""
    return _settings.defaults(_SPEC)


def _check_precision(precision: Any) -> Precision:
    if precision not in _DTYPES:
        raise InvalidArgument(f"precision must be 'f64' or 'f32', got {precision!r}")
    return precision  # type: ignore[no-any-return]


def _vec(x: ArrayLike | None, name: str, n: int) -> list[float] | None:
    if x is None:
        return None
    a = real_array(x, name).astype(np.float64).ravel()
    if a.shape != (n,):
        raise InvalidArgument(f"{name} must have shape ({n},), got {a.shape}")
    return [float(v) for v in a]


@dataclass(frozen=True)
class Gnss9Result:
    """Output of :func:`ahrs_gnss9`."""

    q: FloatArray       #: (N, 4) attitude after each IMU sample and its aiding (body → ENU)
    v: FloatArray       #: (N, 2) SINS velocity (east, north), m/s
    drift: FloatArray   #: (3,) final gyro-drift estimate, rad/s, body axes
    gnss_used: int      #: GNSS samples applied
    gnss_skipped: int   #: GNSS samples outside the IMU time span (not applied)


class Gnss9:
    """Streaming nine-state filter (one ``att_g9`` state).

    ``rate`` (Hz) gives the default IMU step; ``dt`` given to :meth:`update`
    overrides it. ``q0`` (body → ENU) sets the initial attitude; without it
    the first IMU sample sets roll and pitch and the first :meth:`heading`
    the heading. ``v0`` (east, north, m/s) the initial velocity (default 0).
    """

    def __init__(self, rate: float | None = None, q0: ArrayLike | None = None, v0: ArrayLike | None = None,
                 precision: Precision = "f64", **settings: Any) -> None:
        self.precision = _check_precision(precision)
        self.rate = None if rate is None else real(rate, "rate", "Hz", lo=0.0, lo_open=True)
        self._ffi, self._lib = ffi_lib(self.precision)
        self._set = _settings.fill(self._ffi, self._lib, _SPEC, settings)
        self._s = self._ffi.new("att_g9 *")
        q, v = _vec(q0, "q0", 4), _vec(v0, "v0", 2)
        st = self._lib.att_g9_init(self._s, self._set, self._ffi.NULL if q is None else q,
                                   self._ffi.NULL if v is None else v)
        if st != 0:
            raise_for_status(st, "q0" if q is not None else "v0")

    @property
    def settings(self) -> dict[str, Any]:
        return _settings.read(_SPEC, self._set)

    def _get(self, fn: str, n: int) -> FloatArray:
        out = self._ffi.new(f"att_real[{n}]")
        st = getattr(self._lib, fn)(self._s, out)
        if st != 0:
            raise_for_status(st, f"{fn} (the filter is not aligned yet)")
        return np.array(list(out), dtype=np.float64)

    @property
    def q(self) -> FloatArray:
        """Current attitude (4,), body → ENU (raises before alignment)."""
        return self._get("att_g9_attitude", 4)

    @property
    def v(self) -> FloatArray:
        """Current SINS velocity (east, north), m/s."""
        return self._get("att_g9_velocity", 2)

    @property
    def drift(self) -> FloatArray:
        """Gyro-drift estimate (3,), rad/s, body axes."""
        return self._get("att_g9_drift", 3)

    @property
    def error_state(self) -> tuple[FloatArray, FloatArray]:
        """The error state X (9,) and the diagonal of its covariance (9,)."""
        x = self._ffi.new("att_real[9]")
        p = self._ffi.new("att_real[9]")
        self._lib.att_g9_error_state(self._s, x, p)
        return np.array(list(x)), np.array(list(p))

    @property
    def flags(self) -> int:
        """``ATT_G9_F_*`` bits of the last call."""
        return int(self._lib.att_g9_flags(self._s))

    def _dt(self, dt: ArrayLike | None, n: int) -> NDArray[Any]:
        return time_steps(dt, n, self.rate, _DTYPES[self.precision])

    def update(self, gyr: ArrayLike, acc: ArrayLike, dt: ArrayLike | None = None) -> FloatArray:
        """IMU samples: one ((3,) each → (4,)) or a block ((N, 3) → (N, 4))."""
        if np.ndim(gyr) == 1:
            return self._run(np.atleast_2d(gyr), np.atleast_2d(acc), dt, None, None, None, None)[0][0]
        return self._run(gyr, acc, dt, None, None, None, None)[0]

    def _run(self, gyr: ArrayLike, acc: ArrayLike, dt: ArrayLike | None, heading: FloatArray | None,
             at: NDArray[np.uintp] | None, vg: FloatArray | None,
             age: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        g, a = _rows(gyr, "gyr", 3, "angular rate"), _rows(acc, "acc", 3, "specific force")
        n = g.shape[0]
        if a.shape[0] != n:
            raise InvalidArgument(f"gyr and acc must have the same number of samples, got {n}, {a.shape[0]}")
        d = self._dt(dt, n)
        dtype = _DTYPES[self.precision]
        ffi = self._ffi

        def p(x: NDArray[Any] | None, ctype: str = "att_real *") -> Any:
            return ffi.NULL if x is None else ffi.cast(ctype, ffi.from_buffer(x))

        gc, ac = np.ascontiguousarray(g, dtype=dtype), np.ascontiguousarray(a, dtype=dtype)
        h = None if heading is None else np.ascontiguousarray(heading, dtype=dtype)
        vc = None if vg is None else np.ascontiguousarray(vg, dtype=dtype)
        agc = None if age is None else np.ascontiguousarray(age, dtype=dtype)
        m = 0 if at is None else at.size
        q, v = np.empty((n, 4), dtype=dtype), np.empty((n, 2), dtype=dtype)
        err = ffi.new("size_t *")
        st = self._lib.att_g9_batch(self._s, p(gc), p(ac), n, p(d), d.size, p(h), p(at, "size_t *"), p(vc),
                                    p(agc), m, p(q), p(v), err)
        if st != 0:
            i = int(err[0])
            if st == self._lib.ATT_E_G9_DT:
                raise InvalidArgument(f"dt: sample {i}: the time step must be finite and > 0")
            raise_for_status(st, "ahrs_gnss9", index=i)
        return q.astype(np.float64), v.astype(np.float64)

    def gnss(self, v: ArrayLike, age: float = 0.0) -> None:
        """A GNSS velocity (east, north[, up]) in m/s, measured ``age`` s before the last IMU sample."""
        va = real_array(v, "v").astype(np.float64).ravel()
        if va.shape not in ((2,), (3,)):
            raise InvalidArgument(f"v must have shape (2,) or (3,), got {va.shape}")
        st = self._lib.att_g9_gnss(self._s, [float(va[0]), float(va[1])], real(age, "age", "s", lo=0.0))
        if st != 0:
            raise_for_status(st, "gnss")

    def heading(self, psi: float) -> None:
        """A magnetic heading (rad, from north toward east) at the last IMU sample."""
        st = self._lib.att_g9_heading(self._s, real(psi, "psi", "rad"))
        if st != 0:
            raise_for_status(st, "heading")

    def __repr__(self) -> str:
        return f"Gnss9(rate={self.rate}, precision={self.precision!r})"


def gnss_schedule(t: FloatArray, t_gnss: FloatArray) -> tuple[NDArray[np.intp], FloatArray, NDArray[np.bool_]]:
    """Where each GNSS sample is applied: after the first IMU sample k with
    t[k] ≥ t_gnss (its age t[k] − t_gnss); ``used`` False for a GNSS sample
    before t[0] or after t[-1]."""
    k = np.searchsorted(t, t_gnss, side="left")
    used = (t_gnss >= t[0]) & (k < t.size)
    k = np.minimum(k, t.size - 1)
    return k, t[k] - t_gnss, used


def _times(n: int, rate: float | None, t: ArrayLike | None) -> tuple[FloatArray, FloatArray]:
    """The IMU time stamps and steps (the first step equal to the second)."""
    if t is None:
        if rate is None:
            raise InvalidArgument("give rate (Hz) or t (s)")
        step = 1.0 / real(rate, "rate", "Hz", lo=0.0, lo_open=True)
        return np.arange(n, dtype=np.float64) * step, np.array([step])
    ta = real_array(t, "t").astype(np.float64).ravel()
    if ta.shape != (n,) or n < 2:
        raise InvalidArgument(f"t must have one time stamp per IMU sample ({n}, at least 2), got {ta.shape}")
    d = np.diff(ta)
    if not (d > 0).all():
        raise InvalidArgument("t must be strictly increasing")
    return ta, np.concatenate([d[:1], d])


def ahrs_gnss9(gyr: ArrayLike, acc: ArrayLike, rate: float | None = None, t: ArrayLike | None = None,
               t_gnss: ArrayLike | None = None, v_gnss: ArrayLike | None = None, heading: ArrayLike | None = None,
               q0: ArrayLike | None = None, v0: ArrayLike | None = None, precision: Precision = "f64",
               **settings: Any) -> Gnss9Result:
    """The nine-state filter over N IMU samples ((N, 3) gyr [rad/s], acc [m/s²]).

    ``rate`` (Hz; samples at k/rate) or ``t`` (N time stamps, s) times the
    IMU. ``t_gnss`` (M,) and ``v_gnss`` (M, 2 or 3; east, north[, up]) are
    the GNSS velocities with their own time stamps: each is applied after
    the first IMU sample at or after it, with the SINS velocity taken back
    to its time (ahrs_gnss9.h). ``heading`` (N,): the magnetic heading at
    each IMU sample (rad from north toward east, NaN = none). Settings:
    :data:`SETTINGS`. Returned as float64 whatever the precision.
    """
    f = Gnss9(q0=q0, v0=v0, precision=precision, **settings)
    g = _rows(gyr, "gyr", 3, "angular rate")
    n = g.shape[0]
    ts, dt = _times(n, rate, t)
    h = None if heading is None else real_array(heading, "heading").astype(np.float64).ravel()
    if h is not None and h.shape != (n,):
        raise InvalidArgument(f"heading must have one value per IMU sample ({n}), got {h.shape}")
    at = vg = age = None
    skipped = 0
    if (t_gnss is None) != (v_gnss is None):
        raise InvalidArgument("give both t_gnss and v_gnss, or neither")
    if t_gnss is not None and v_gnss is not None:
        tg = real_array(t_gnss, "t_gnss").astype(np.float64).ravel()
        va = real_array(v_gnss, "v_gnss").astype(np.float64)
        if va.ndim != 2 or va.shape[0] != tg.size or va.shape[1] not in (2, 3):
            raise InvalidArgument(f"v_gnss must have shape ({tg.size}, 2 or 3), got {va.shape}")
        if not (np.diff(tg) >= 0).all():
            raise InvalidArgument("t_gnss must be non-decreasing")
        k, ages, used = gnss_schedule(ts, tg)
        skipped = int((~used).sum())
        at, vg, age = k[used].astype(np.uintp), va[used, :2], ages[used]
    q, v = f._run(g, acc, dt, h, at, vg, age)
    return Gnss9Result(q=q, v=v, drift=f.drift, gnss_used=0 if at is None else int(at.size), gnss_skipped=skipped)
