"""The attitude filter (AHRS): gyro + accelerometer (+ magnetometer) → attitude.

Python side of ``csrc/include/attitude/ahrs.h``: an error-state Kalman filter
(attitude error and gyro bias) on top of the rotation-vector integrator, with
accelerometer aiding that survives linear acceleration, heading-only
magnetometer aiding with disturbance rejection and rest detection. See
docs/ahrs.md for the design and the measured accuracy.

Units: gyro rad/s, specific force m/s² (+g upward at rest), field in any
unit (µT typical; only its direction, norm ratios and dip are used).
Quaternions scalar first, body → ENU (docs/conventions.md).

* :class:`Ahrs` — streaming: one sample ``(3,)`` or a block ``(N, 3)`` per call;
  :meth:`Ahrs.update_vel` gives it a GNSS velocity (ENU, m/s) time-stamped on its clock
  :attr:`Ahrs.time`;
* :func:`ahrs` — batch: ``(N, 3)`` arrays in, ``(N, 4)`` quaternions out; GNSS velocities
  with their own times (``gnss_t``, ``gnss_vel``).

Settings are keyword arguments named as the C struct's fields
(:data:`SETTINGS`; ``method`` by name, e.g. ``"rv3-reuse"``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _settings, names
from ._lib import ffi_lib
from ._validate import integer, real, real_array, time_steps
from .errors import InvalidArgument, InvalidType, NonFiniteError
from .names import raise_for_status

__all__ = ["SETTINGS", "Ahrs", "ahrs", "check_settings", "default_settings", "parse_setting", "setting_option"]

FloatArray = NDArray[np.float64]
Precision = Literal["f64", "f32"]

def _method(name: str, v: Any) -> int:
    if not isinstance(v, str):
        raise InvalidType(f"{name} must be a method name (str), got {type(v).__name__}")
    code = names.method_code(v)
    if code == names.C["ATT_METHOD_RK4"]:
        raise InvalidArgument(f"{name}: the filter needs an increment method, not 'rk4'")
    return code


_SPEC = _settings.SettingsSpec(
    "att_ahrs_settings", "att_ahrs_default_settings", "att_ahrs_check_settings", label="filter",
    domain="ahrs.h: noises and times > 0, '0 = off' fields ≥ 0, |sensor_delay| ≤ 1 s, "
    "|acc_delay|, |mag_delay| ≤ 0.05 s, 0 ≤ mag_ref_window ≤ mag_ref_tau, gnss_vel_sigma, "
    "gnss_timeout, gnss_max_latency > 0, the other gnss_ fields ≥ 0",
    choices={"method": _settings.Choice(_method, lambda code: names.method_names()[code])},
    field_fn="att_ahrs_check_settings_field")

#: The real-valued settings (field names of ``att_ahrs_settings``, read from the
#: library on first use), besides ``method``.
SETTINGS: Sequence[str] = _settings.SettingNames(_SPEC, "real")



def parse_setting(text: str, option: str = "--set") -> tuple[str, Any]:
    """A filter setting as every command takes it, ``NAME=VALUE`` (``acc_tau=3``,
    ``method=rv1``): the one parser of ``attitude ahrs --set``, ``simulate
    --ahrs-setting`` and ``view --ahrs-setting``. ValueError naming ``option``
    for a malformed text, an unknown name or a value that is not a number."""
    return _settings.parse_assignment(_SPEC, text, option)


def check_settings(settings: Mapping[str, Any]) -> None:
    """Raise as :class:`Ahrs` would for ``settings`` (InvalidArgument/InvalidType naming
    the setting: unknown, of the wrong type, outside the domain), without a filter."""
    ffi, lib = ffi_lib("f64")
    _settings.fill(ffi, lib, _SPEC, settings)


def setting_option(option: str) -> Callable[[str], tuple[str, Any]]:
    """:func:`parse_setting` for ``option`` (an argparse ``type=``)."""
    def conv(text: str) -> tuple[str, Any]:
        return parse_setting(text, option)

    conv.__name__ = "setting"
    return conv


_DTYPES = {"f64": np.float64, "f32": np.float32}


def _check_precision(precision: Any) -> str:
    if precision not in _DTYPES:
        raise InvalidArgument(f"precision must be 'f64' or 'f32', got {precision!r}")
    return str(precision)


def default_settings() -> dict[str, Any]:
    """The library's defaults (``att_ahrs_default_settings``), ``method`` by name."""
    return _settings.defaults(_SPEC)


def _vectors(x: ArrayLike | None, name: str, optional: bool = False) -> NDArray[np.float64] | None:
    if x is None:
        if optional:
            return None
        raise InvalidArgument(f"{name} is required")
    a = real_array(x, name)
    if a.ndim not in (1, 2) or a.shape[-1] != 3:
        raise InvalidArgument(f"{name} must have shape (3,) or (N, 3), got {a.shape}")
    a = np.asarray(a, dtype=np.float64).reshape(-1, 3)
    if not np.isfinite(a).all():  # the per-row search only on failure (it costs ~10x the check)
        i = int(np.argmin(np.isfinite(a).all(axis=1)))
        raise NonFiniteError(f"{name}: sample {i} holds NaN or Inf", index=i)
    return a


_F64, _ND = np.dtype(np.float64), np.ndarray  # the fast path of Ahrs.update takes these


class Ahrs:
    """Streaming attitude filter (one ``att_ahrs`` state).

    ``rate`` (Hz) gives the default time step; ``dt`` given to :meth:`update`
    overrides it per call (scalar or one per sample). ``q0`` (body → ENU)
    sets the initial attitude; without it the first sample aligns the filter
    (roll/pitch from the specific force, heading from the field, or 0).
    """

    def __init__(self, rate: float | None = None, q0: ArrayLike | None = None,
                 precision: Precision = "f64", **settings: Any) -> None:
        self.precision = _check_precision(precision)
        self.rate = None if rate is None else real(rate, "rate", "Hz", lo=0.0, lo_open=True)
        self._ffi, self._lib = ffi_lib(self.precision)
        self._set = _settings.fill(self._ffi, self._lib, _SPEC, settings)
        self._s = self._ffi.new("att_ahrs *")
        q = self._ffi.NULL
        if q0 is not None:
            qa = real_array(q0, "q0").astype(np.float64)
            if qa.shape != (4,):
                raise InvalidArgument(f"q0 must have shape (4,), got {qa.shape}")
            q = self._ffi.new("att_real[4]", [float(v) for v in qa])
        st = self._lib.att_ahrs_init(self._s, self._set, q)
        if st != 0:
            raise_for_status(st, "q0")
        # the one-sample fast path's buffers (see update), reused by every call (f64 only)
        self._in1 = [self._ffi.new("att_real[3]") for _ in range(3)] if self.precision == "f64" else None
        self._q1 = np.empty(4, dtype=_DTYPES[self.precision])
        self._q1p = self._ffi.from_buffer("att_real[]", self._q1)
        self._step = None if self.rate is None else 1.0 / self.rate
        self._upd, self._move = self._lib.att_ahrs_update, self._ffi.memmove

    @property
    def settings(self) -> dict[str, Any]:
        return _settings.read(_SPEC, self._set)

    @property
    def q(self) -> FloatArray:
        """Current reported attitude (4,), float64: the state's, levelled by ``tilt_tau``'s
        low-pass, without the ``sensor_delay`` prediction (raises before alignment)."""
        out = self._ffi.new("att_real[4]")
        st = self._lib.att_ahrs_attitude(self._s, out)
        if st != 0:
            raise_for_status(st, "q (the filter is not aligned yet)")
        return np.array(list(out), dtype=np.float64)

    @property
    def bias(self) -> FloatArray:
        """Gyro-bias estimate (3,), rad/s, body frame."""
        out = self._ffi.new("att_real[3]")
        self._lib.att_ahrs_bias(self._s, out)
        return np.array(list(out), dtype=np.float64)

    @property
    def sigma(self) -> tuple[FloatArray, FloatArray]:
        """1σ of the attitude error per ENU axis (rad) and of the bias (rad/s)."""
        a = self._ffi.new("att_real[3]")
        b = self._ffi.new("att_real[3]")
        self._lib.att_ahrs_sigma(self._s, a, b)
        return np.array(list(a)), np.array(list(b))

    def _covariance(self) -> tuple[FloatArray, FloatArray]:
        a = self._ffi.new("att_real[9]")
        b = self._ffi.new("att_real[9]")
        self._lib.att_ahrs_covariance(self._s, a, b)
        return np.array(list(a)).reshape(3, 3), np.array(list(b)).reshape(3, 3)

    @property
    def covariance(self) -> FloatArray:
        """Attitude error covariance (3, 3), rad², float64: of the rotation vector δθ about the
        fixed ENU axes with q_true = exp(δθ) ⊗ q (``att_ahrs_covariance``; [2, 2] is the heading
        variance). ``covariance.ravel()`` is ROS's ``sensor_msgs/Imu.orientation_covariance``
        layout (row-major). docs/ahrs.md, "Uncertainty"."""
        return self._covariance()[0]

    @property
    def bias_covariance(self) -> FloatArray:
        """Gyro-bias error covariance (3, 3), (rad/s)², body frame."""
        return self._covariance()[1]

    @property
    def heading_sigma(self) -> float:
        """1σ of the heading error (rad): the square root of ``covariance[2, 2]``."""
        return float(np.sqrt(max(self._covariance()[0][2, 2], 0.0)))

    @property
    def heading_observable(self) -> bool:
        """False in six-axis mode and once :attr:`heading_sigma` has grown past the setting
        ``heading_sigma_max`` without a magnetometer update (``ATT_AHRS_F_NO_HEADING``)."""
        return not self.flags & names.C["ATT_AHRS_F_NO_HEADING"]

    @property
    def flags(self) -> int:
        """``ATT_AHRS_F_*`` bits of the last sample."""
        return int(self._lib.att_ahrs_flags(self._s))

    @property
    def time(self) -> float:
        """The filter's clock (s): the sum of the time steps of every sample so far
        (``att_ahrs_time``); GNSS velocities are time-stamped on it."""
        return float(self._lib.att_ahrs_time(self._s))

    def update_vel(self, t: float, vel_enu: ArrayLike, sigma: float = 0.0, pdop: float = 0.0,
                   has_up: bool = False, fix_type: int = 3) -> None:
        """Give the filter one GNSS velocity (``att_ahrs_update_vel``; docs/ahrs.md, "GNSS
        velocity aiding"): ``t`` its time of validity on :attr:`time` (the receiver's latency
        subtracted), ``vel_enu`` (2,) or (3,) m/s east, north (, up: used with ``has_up``),
        ``sigma`` its 1σ per component (m/s; 0: the setting ``gnss_vel_sigma``), ``pdop`` (0:
        unknown), ``fix_type`` as :class:`attitude_c.gnss` (2 2-D, 3 3-D, 4 GNSS + dead
        reckoning are used). A refused sample (quality, jump, gate) is not an error: the next
        sample's :attr:`flags` carry ``ATT_AHRS_F_GNSS_REJECTED``."""
        tt = real(t, "t", "s")
        v = real_array(vel_enu, "vel_enu").astype(np.float64)
        if v.shape not in ((2,), (3,)):
            raise InvalidArgument(f"vel_enu must have shape (2,) or (3,), got {v.shape}")
        if not isinstance(has_up, (bool, np.bool_)):
            raise InvalidType(f"has_up must be True or False, got {type(has_up).__name__}")
        if has_up and v.shape != (3,):
            raise InvalidArgument("has_up=True needs vel_enu of shape (3,) (east, north, up)")
        if not np.isfinite(v[:3 if has_up else 2]).all():
            raise NonFiniteError("vel_enu holds NaN or Inf")
        rec = self._ffi.new("att_ahrs_vel *")
        rec.t = tt
        rec.vel = [float(v[0]), float(v[1]), float(v[2]) if has_up else 0.0]
        rec.sigma = real(sigma, "sigma", "m/s", lo=0.0)
        rec.pdop = real(pdop, "pdop", lo=0.0)
        rec.has_up = int(bool(has_up))
        rec.fix_type = integer(fix_type, "fix_type", 0, 255)
        st = self._lib.att_ahrs_update_vel(self._s, rec)
        if st == self._lib.ATT_E_ARG:
            raise InvalidArgument(
                f"t: {tt:g} s is outside the filter's window: its clock is {self.time:g} s; t must be "
                f"at most one step later, at most gnss_max_latency = {self.settings['gnss_max_latency']:g} s "
                "earlier, and after the previous velocity's t")
        if st != 0:
            raise_for_status(st, "update_vel")

    def _dt(self, dt: ArrayLike | None, n: int) -> NDArray[Any]:
        return time_steps(dt, n, self.rate, _DTYPES[self.precision])

    @overload
    def update(self, gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None = ...,
               dt: ArrayLike | None = ..., covariance: Literal[False] = ...) -> FloatArray: ...

    @overload
    def update(self, gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None = ...,
               dt: ArrayLike | None = ..., *, covariance: Literal[True]) -> tuple[FloatArray, FloatArray]: ...

    @overload
    def update(self, gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None = ...,
               dt: ArrayLike | None = ..., *, covariance: bool) -> FloatArray | tuple[FloatArray, FloatArray]: ...

    def update(self, gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None = None,
               dt: ArrayLike | None = None, covariance: bool = False) -> Any:
        """Feed one sample ((3,) each → (4,)) or a block ((N, 3) → (N, 4)). With
        ``covariance=True`` also the attitude covariance after each sample ((3, 3) or
        (N, 3, 3), rad², as :attr:`covariance`): returns ``(q, cov)``."""
        # The fast path (precision f64): one sample of (3,) float64 arrays, dt None or a float:
        # the rows copied into reused buffers (sizes checked here: memmove does not, and it
        # refuses strided arrays), one C call, the attitude copied out. The C call checks every
        # value (finite, dt > 0, units) and leaves the state untouched when it fails: the
        # general path below then repeats it and names the bad argument.
        step = self._step if dt is None else dt if isinstance(dt, float) else None
        bufs = self._in1
        if (not covariance and step is not None and bufs is not None and type(gyr) is _ND and type(acc) is _ND
                and gyr.shape == (3,) and acc.shape == (3,) and gyr.dtype == _F64 and acc.dtype == _F64
                and (mag is None or type(mag) is _ND and mag.shape == (3,) and mag.dtype == _F64)):
            g, a, m = bufs
            move = self._move
            try:
                move(g, gyr, 24)
                move(a, acc, 24)
                if mag is None:
                    m = self._ffi.NULL
                else:
                    move(m, mag, 24)
                if self._upd(self._s, g, a, m, step, self._q1p) == 0:
                    return self._q1.copy()
            except ValueError:
                pass
        single = np.ndim(gyr) == 1
        g = _vectors(gyr, "gyr")
        a = _vectors(acc, "acc")
        m = _vectors(mag, "mag", optional=True)
        assert g is not None and a is not None
        n = g.shape[0]
        if a.shape[0] != n or (m is not None and m.shape[0] != n):
            raise InvalidArgument(f"gyr, acc and mag must have the same number of samples, got "
                                  f"{n}, {a.shape[0]}" + ("" if m is None else f", {m.shape[0]}"))
        d = self._dt(dt, n)
        dtype = _DTYPES[self.precision]
        ffi = self._ffi
        gc = np.ascontiguousarray(g, dtype=dtype)
        ac = np.ascontiguousarray(a, dtype=dtype)
        mc = None if m is None else np.ascontiguousarray(m, dtype=dtype)
        out = np.empty((n, 4), dtype=dtype)
        err = ffi.new("size_t *")

        def p(x: NDArray[Any] | None) -> Any:
            return ffi.NULL if x is None else ffi.cast("att_real *", ffi.from_buffer(x))

        if covariance:
            cov = np.empty((n, 3, 3), dtype=dtype)
            st = self._lib.att_ahrs_batch_cov(self._s, p(gc), p(ac), p(mc), n, p(d), d.size, p(out), p(cov), err)
        else:
            st = self._lib.att_ahrs_batch(self._s, p(gc), p(ac), p(mc), n, p(d), d.size, p(out), err)
        if st != 0:
            i = int(err[0])
            if st == self._lib.ATT_E_AHRS_DT:
                raise InvalidArgument(f"dt: sample {i}: the time step must be finite and > 0")
            raise_for_status(st, "ahrs", index=i)
        if covariance:
            return (out[0], cov[0]) if single else (out, cov)
        return out[0] if single else out  # float64 for f64 (no copy), float32 for f32

    def update_sparse(self, gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None = None,
                      dt: ArrayLike | None = None) -> FloatArray:
        """:meth:`update` for a stream whose aiding comes on some samples only (the aided
        board's plan): a row of ``acc`` or ``mag`` that is all NaN means "not in this
        sample" and is passed to ``att_ahrs_update`` as NULL, as attitude-rx does; one C
        call per sample. Blocks (N, 3) → (N, 4)."""
        g = _vectors(gyr, "gyr")
        assert g is not None
        n = g.shape[0]
        rows = [self._sparse(x, name, n) for x, name in ((acc, "acc"), (mag, "mag"))]
        d = np.broadcast_to(self._dt(dt, n), (n,))
        dtype = _DTYPES[self.precision]
        ffi = self._ffi
        out = np.empty((n, 4), dtype=dtype)
        q = ffi.new("att_real[4]")
        for i in range(n):
            vec = [ffi.NULL if r is None or (v := r[i]) is None else [float(x) for x in v] for r in rows]
            st = self._lib.att_ahrs_update(self._s, list(map(float, g[i])), vec[0], vec[1], float(d[i]), q)
            if st != 0:
                raise_for_status(st, "ahrs", index=i)
            out[i] = list(q)
        return out

    @staticmethod
    def _sparse(x: ArrayLike | None, name: str, n: int) -> list[NDArray[np.float64] | None] | None:
        """Rows of ``x`` (N, 3), None where a row is all NaN (absent); None for no ``x``."""
        if x is None:
            return None
        a = real_array(x, name).astype(np.float64).reshape(-1, 3)
        if a.shape[0] != n:
            raise InvalidArgument(f"gyr and {name} must have the same number of samples, got {n}, {a.shape[0]}")
        absent = np.isnan(a).all(axis=1)
        present = _vectors(a[~absent], name)
        assert present is not None
        rows: list[NDArray[np.float64] | None] = [None] * n
        for i, row in zip(np.flatnonzero(~absent), present):
            rows[int(i)] = row
        return rows

    def __repr__(self) -> str:
        return f"Ahrs(rate={self.rate}, precision={self.precision!r})"


class _Gnss:
    """The batch's GNSS velocities, checked: times of validity, when each is given to the
    filter (delivered), ENU velocities with has_up, sigmas, fix types."""

    def __init__(self, gnss_t: ArrayLike, gnss_vel: ArrayLike, gnss_sigma: ArrayLike | None,
                 gnss_delivered: ArrayLike | None, gnss_fix: ArrayLike | None) -> None:
        self.t = real_array(gnss_t, "gnss_t").astype(np.float64).reshape(-1)
        m = self.t.size
        v = real_array(gnss_vel, "gnss_vel").astype(np.float64)
        if v.ndim != 2 or v.shape[0] != m or v.shape[1] not in (2, 3):
            raise InvalidArgument(f"gnss_vel must have shape ({m}, 2) or ({m}, 3) (one row per gnss_t), "
                                  f"got {v.shape}")
        self.up = np.zeros(m, bool) if v.shape[1] == 2 else np.isfinite(v[:, 2])
        self.vel = np.zeros((m, 3))
        self.vel[:, :v.shape[1]] = v
        self.vel[~self.up, 2] = 0.0
        self.sigma = self._column(gnss_sigma, "gnss_sigma", m, 0.0)
        self.delivered = self._column(gnss_delivered, "gnss_delivered", m, None)
        self.fix = np.round(self._column(gnss_fix, "gnss_fix", m, 3.0)).astype(int)
        ok = self.fix >= 2
        if not np.isfinite(self.t).all():
            raise NonFiniteError("gnss_t holds NaN or Inf")
        if not np.isfinite(self.vel[ok, :2]).all():
            raise NonFiniteError("gnss_vel: a row used (gnss_fix >= 2) holds NaN or Inf")
        self.vel[~ok] = 0.0  # no fix: the velocity is not read (the filter refuses the fix type)
        self.up &= ok
        if np.any(np.diff(self.delivered) < 0):
            raise InvalidArgument("gnss_t (or gnss_delivered) must be in time order")

    def _column(self, x: ArrayLike | None, name: str, m: int, default: float | None) -> NDArray[np.float64]:
        if x is None:
            return self.t.copy() if default is None else np.full(m, default)
        a = real_array(x, name).astype(np.float64).reshape(-1)
        if a.size != m:
            raise InvalidArgument(f"{name} must have one value per gnss_t ({m}), got {a.size}")
        if not np.isfinite(a).all():
            raise NonFiniteError(f"{name} holds NaN or Inf")
        return a

    def give(self, f: Ahrs, i: int) -> None:
        f.update_vel(float(self.t[i]), self.vel[i], sigma=float(self.sigma[i]), has_up=bool(self.up[i]),
                     fix_type=int(self.fix[i]))


def _ahrs_gnss(f: Ahrs, gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None, dt: ArrayLike | None,
               covariance: bool, gn: _Gnss) -> Any:
    """The batch with GNSS: the samples in blocks, each velocity given after the last sample
    whose time ((k + 1) dt, or the sum of the steps so far) is at or before its delivery time."""
    g = _vectors(gyr, "gyr")
    assert g is not None
    n = g.shape[0]
    d = time_steps(dt, n, f.rate, np.float64)  # the steps as given (not rounded to f32's)
    times = (np.arange(n) + 1.0) * d[0] if d.size == 1 else np.cumsum(d)  # sample k at (k + 1) dt
    cut = np.searchsorted(times, gn.delivered, side="right")
    a = np.asarray(acc)
    m = None if mag is None else np.asarray(mag)
    step = None if dt is None or np.ndim(dt) == 0 else np.asarray(dt)
    outs, covs, k0 = [], [], 0
    for i, k in enumerate([*cut, n]):
        if k > k0:
            r = f.update(g[k0:k], a[k0:k], None if m is None else m[k0:k],
                         dt=dt if step is None else step[k0:k], covariance=covariance)
            outs.append(r[0] if covariance else r)
            if covariance:
                covs.append(r[1])
            k0 = k
        if i < len(cut):
            gn.give(f, i)
    q = np.concatenate(outs) if outs else np.empty((0, 4))
    return (q, np.concatenate(covs)) if covariance else q


@overload
def ahrs(gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None = ..., rate: float | None = ...,
         dt: ArrayLike | None = ..., q0: ArrayLike | None = ..., precision: Precision = ...,
         covariance: Literal[False] = ..., gnss_t: ArrayLike | None = ..., gnss_vel: ArrayLike | None = ...,
         gnss_sigma: ArrayLike | None = ..., gnss_delivered: ArrayLike | None = ...,
         gnss_fix: ArrayLike | None = ..., **settings: Any) -> FloatArray: ...


@overload
def ahrs(gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None = ..., rate: float | None = ...,
         dt: ArrayLike | None = ..., q0: ArrayLike | None = ..., precision: Precision = ...,
         *, covariance: Literal[True], gnss_t: ArrayLike | None = ..., gnss_vel: ArrayLike | None = ...,
         gnss_sigma: ArrayLike | None = ..., gnss_delivered: ArrayLike | None = ...,
         gnss_fix: ArrayLike | None = ..., **settings: Any) -> tuple[FloatArray, FloatArray]: ...


def ahrs(gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None = None, rate: float | None = None,
         dt: ArrayLike | None = None, q0: ArrayLike | None = None, precision: Precision = "f64",
         covariance: bool = False, gnss_t: ArrayLike | None = None, gnss_vel: ArrayLike | None = None,
         gnss_sigma: ArrayLike | None = None, gnss_delivered: ArrayLike | None = None,
         gnss_fix: ArrayLike | None = None, **settings: Any) -> Any:
    """Run the filter over N samples: (N, 3) arrays → (N, 4) quaternions (body → ENU).

    ``rate`` (Hz) or ``dt`` (s, scalar or per sample) gives the time step;
    ``mag=None`` is six-axis operation (heading from the gyro only).
    ``covariance=True`` returns ``(q, cov)``, cov (N, 3, 3) the attitude error
    covariance after each sample (rad², ENU; :attr:`Ahrs.covariance`).

    GNSS velocity aiding (docs/ahrs.md, "GNSS velocity aiding"): ``gnss_t`` (M,) the
    velocities' times of validity (s, on the filter's clock: sample k, from 0, is at the sum
    of the first k + 1 steps), ``gnss_vel`` (M, 2) or (M, 3) ENU m/s (a NaN up component: not
    measured), optional ``gnss_sigma`` (M,) 1σ m/s (0: the setting), ``gnss_delivered`` (M,)
    when each reaches the filter (default ``gnss_t``: no latency), ``gnss_fix`` (M,) fix
    types (default 3; below 2 the row is a fix without velocity, refused). Velocity i is
    given after the last sample whose time is ≤ ``gnss_delivered[i]``.
    """
    if not isinstance(covariance, (bool, np.bool_)):
        raise InvalidType(f"covariance must be True or False, got {type(covariance).__name__}")
    if rate is None and dt is None:
        raise InvalidArgument("give rate (Hz) or dt (s)")
    g = np.asarray(gyr)
    if g.ndim != 2:
        raise InvalidArgument(f"gyr must have shape (N, 3), got {g.shape}")
    f = Ahrs(rate=rate, q0=q0, precision=precision, **settings)
    if gnss_t is None and gnss_vel is None:
        for name, x in (("gnss_sigma", gnss_sigma), ("gnss_delivered", gnss_delivered), ("gnss_fix", gnss_fix)):
            if x is not None:
                raise InvalidArgument(f"{name} given without gnss_t and gnss_vel")
        return f.update(gyr, acc, mag, dt=dt, covariance=bool(covariance))
    if gnss_t is None or gnss_vel is None:
        raise InvalidArgument("give both gnss_t and gnss_vel, or neither")
    gn = _Gnss(gnss_t, gnss_vel, gnss_sigma, gnss_delivered, gnss_fix)
    return _ahrs_gnss(f, gyr, acc, mag, dt, bool(covariance), gn)
