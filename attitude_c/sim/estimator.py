"""Stage 8 of the simulator (docs/architecture.md): the attitude estimator.

Two estimators, one shape: :class:`Integrate` — the rotation-vector
integrator of the library (:func:`attitude_c.integrate`, any method,
f64/f32/fixed; the paper's system) — and :class:`AhrsFilter` — the attitude
filter (:class:`attitude_c.Ahrs`, docs/ahrs.md) fed the gyro rates and the
accelerometer (and magnetometer) readings of ``Decoded.aux``. Each takes the
host's :class:`Decoded` samples and the initial attitude and returns an
:class:`Estimate`, the attitude at known times.

Increment methods get the increments; an update that consumes increments
k−2…k is the attitude at the end of period k. ``rk4`` integrates rates: it
gets the mean rates Δθ/h corrected to midpoint rates (``ω_mid ≈ m_k −
(m_{k+1} − 2m_k + m_{k−1})/24``: a mean over h equals the midpoint value plus
h²ω''/24), as rows t, t+h/2, t+h of 2h steps; its outputs fall at period
midpoints.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Literal, get_args

import numpy as np

from ..core import Method, Precision, integrate, integrate_rates
from ..errors import InvalidArgument
from ..names import C, samples_per_update
from .host import Decoded

__all__ = ["ESTIMATORS", "AhrsFilter", "Estimate", "EstimatorName", "Integrate", "check_ahrs_settings",
           "to_period_end"]

EstimatorName = Literal["integrator", "ahrs"]
ESTIMATORS: tuple[EstimatorName, ...] = get_args(EstimatorName)


@dataclass
class Estimate:
    """Estimated attitudes ``q`` (M, 4) at times ``t`` (M,) (s); a filter adds
    its gyro-bias estimate ``bias`` (K, 3) rad/s (body) at times ``bias_t``
    (K,) (s), its attitude covariance ``cov`` (M, 3, 3) rad² (ENU, at ``t``;
    ``Ahrs.covariance``) and ``info`` for the summary."""

    t: np.ndarray
    q: np.ndarray
    bias_t: np.ndarray | None = None
    bias: np.ndarray | None = None
    info: dict[str, Any] = field(default_factory=dict)
    cov: np.ndarray | None = None


@dataclass(frozen=True)
class Integrate:
    """The integrator as the estimator stage: ``method`` and ``precision`` of
    :func:`attitude_c.integrate`."""

    method: Method = "rv3"
    precision: Precision = "f64"

    @property
    def backend(self) -> str:
        return f"attitude_c.integrate ({self.precision})"

    def run(self, decoded: Decoded, q0_at: Callable[[float], np.ndarray], t0: float, period: float) -> Estimate:
        """Integrate the increments of ``decoded`` (sample k spans [t0 + k h, t0 + (k+1) h]).

        ``q0_at(t)`` is the true attitude at time t (s): the start, at the
        beginning of the first delivered sample (rk4: half a period later)."""
        inc = np.ascontiguousarray(decoded.increments, dtype=float)
        idx = decoded.sample_index
        n = len(inc)
        first = int(idx[0]) if n else 0
        h = period
        empty = Estimate(np.zeros(0), np.zeros((0, 4)))
        if self.method == "rk4":
            if n < 3:
                return empty
            # mean rate over an interval = midpoint rate + h²ω''/24 + O(h⁴): remove
            # the second-order term with the second difference of the means
            mean = inc / h
            w = mean.copy()
            w[1:-1] -= (mean[2:] - 2 * mean[1:-1] + mean[:-2]) / 24
            w[0] -= (mean[2] - 2 * mean[1] + mean[0]) / 24
            w[-1] -= (mean[-1] - 2 * mean[-2] + mean[-3]) / 24
            q = np.asarray(integrate_rates(w, h, method="rk4", q0=q0_at(t0 + (first + 0.5) * h),
                                           precision=self.precision), dtype=float)
            last = 2 * np.arange(1, len(q) + 1)
            return Estimate(t0 + (idx[last] + 0.5) * h, q)
        k = samples_per_update(self.method)
        n_use = (n // k) * k
        if n_use == 0:
            return empty
        q = np.asarray(integrate(inc[:n_use], method=self.method, q0=q0_at(t0 + first * h),
                                 precision=self.precision), dtype=np.float64)
        last = np.arange(1, len(q) + 1) * k - 1
        return Estimate(t0 + (idx[last] + 1.0) * h, q)


def check_ahrs_settings(settings: dict[str, Any]) -> dict[str, Any]:
    """``settings`` checked against the filter's (:data:`attitude_c.ahrs_filter.SETTINGS`
    and ``method``): names, types and domains (InvalidArgument naming the bad one).
    Returns the filter's full settings with these applied."""
    from ..ahrs_filter import Ahrs

    return Ahrs(**settings).settings


def to_period_end(increments: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Body-frame period means ``v`` (N, 3) of a navigation-fixed vector moved
    to the end of their periods: rotated by −Δθ/2 (Rodrigues).

    A period mean of a vector fixed in the navigation frame is, to second
    order, its value at mid-period; the gyro's attitude after the period is
    at its end, half an increment later. Read as the end's value, the mean
    lags the attitude by Δθ/2 (0.2° of heading at 5°/s and h = 0.08 s); the
    body turns by φ = Δθ/2 from mid-period to the end, so a fixed vector
    turns by −φ in the body frame: v_end = R(φ)ᵀ v_mid."""
    phi = 0.5 * np.asarray(increments, dtype=float)
    v = np.asarray(v, dtype=float)
    a = np.linalg.norm(phi, axis=1, keepdims=True)
    k = np.divide(phi, a, out=np.zeros_like(phi), where=a > 0)
    c, s = np.cos(-a), np.sin(-a)
    return v * c + np.cross(k, v) * s + k * np.sum(k * v, axis=1, keepdims=True) * (1 - c)


@dataclass(frozen=True)
class AhrsFilter:
    """The attitude filter (:class:`attitude_c.Ahrs`) as the estimator stage.

    Per sample k (the period [t0 + k h, t0 + (k+1) h]) it gets the mean rate
    Δθ_k / h, the period mean of the specific force (``aux["accel"]``, m/s²)
    and of the field (``aux["mag"]``, µT; absent: six-axis), both moved to
    the end of the period (:func:`to_period_end`: a mean is the mid-period
    value; ``align_readings=False`` feeds the means as they are), and dt = h;
    its attitude after sample k is the estimate at the end of the period. ``init``
    "truth" starts it from the true attitude (as the integrator), "align"
    lets the filter align itself on its first sample (roll and pitch from the
    specific force, heading from the field, or 0 without one). ``settings``
    are :func:`attitude_c.ahrs`'s keywords; ``declination`` (rad) and
    ``gravity`` (m/s²) default to the simulated environment's when the
    settings do not give them (``environment``: the chain passes its own).
    The bias estimate is recorded every ``bias_every`` s."""

    settings: tuple[tuple[str, Any], ...] = ()
    precision: Literal["f64", "f32"] = "f64"
    init: Literal["truth", "align"] = "truth"
    declination: float = 0.0
    gravity: float = 9.80665
    bias_every: float = 0.1
    align_readings: bool = True

    def __post_init__(self) -> None:
        if self.precision not in ("f64", "f32"):
            raise InvalidArgument(f"the ahrs estimator runs in 'f64' or 'f32', got precision {self.precision!r}")
        if self.init not in ("truth", "align"):
            raise InvalidArgument(f"init must be 'truth' or 'align', got {self.init!r}")

    def filter_settings(self) -> dict[str, Any]:
        """The keywords given to the filter (environment defaults, then ``settings``)."""
        kw: dict[str, Any] = {"declination": self.declination, "gravity": self.gravity}
        kw.update(dict(self.settings))
        return kw

    @property
    def backend(self) -> str:
        method = dict(self.settings).get("method", "rv3-reuse")
        return f"attitude_c.Ahrs ({self.precision}, {method})"

    def run(self, decoded: Decoded, q0_at: Callable[[float], np.ndarray], t0: float, period: float) -> Estimate:
        """Filter the samples of ``decoded``; ``q0_at(t)`` is the true attitude at t (s)."""
        from ..ahrs_filter import Ahrs

        if "accel" not in decoded.aux:
            raise InvalidArgument("the ahrs estimator needs an accelerometer (give --accel PART)")
        inc = np.asarray(decoded.increments, dtype=float)
        idx = np.asarray(decoded.sample_index)
        n = len(inc)
        if n == 0:
            return Estimate(np.zeros(0), np.zeros((0, 4)), np.zeros(0), np.zeros((0, 3)))
        h = period
        gyr = inc / h
        acc = np.asarray(decoded.aux["accel"], dtype=float)
        mag = decoded.aux.get("mag")
        mag = None if mag is None else np.asarray(mag, dtype=float)
        if self.align_readings:
            acc = to_period_end(inc, acc)
            mag = None if mag is None else to_period_end(inc, mag)
        q0 = q0_at(t0 + int(idx[0]) * h) if self.init == "truth" else None
        f = Ahrs(q0=q0, precision=self.precision, **self.filter_settings())
        # the aided board's stream: NaN rows are samples without that sensor's record
        sparse = bool(np.isnan(acc).any() or (mag is not None and np.isnan(mag).any()))
        update = f.update_sparse if sparse else f.update
        step = max(1, round(self.bias_every / h))
        q = np.empty((n, 4))
        cov = None if sparse else np.empty((n, 3, 3))  # update_sparse has no covariance output
        bias = []
        rest = 0
        mag_rejected = 0
        for a in range(0, n, step):
            b = min(n, a + step)
            m = None if mag is None else mag[a:b]
            if cov is None:
                q[a:b] = update(gyr[a:b], acc[a:b], m, dt=h)
            else:
                q[a:b], cov[a:b] = f.update(gyr[a:b], acc[a:b], m, dt=h, covariance=True)
            bias.append(f.bias)
            fl = f.flags
            rest += bool(fl & C["ATT_AHRS_F_REST"])
            mag_rejected += bool(fl & C["ATT_AHRS_F_MAG_DISTURBED"])
        last = np.minimum(np.arange(step, n + step, step), n) - 1
        info = {"estimator": "ahrs", "axes": 6 if mag is None else 9, "init": self.init,
                "settings": f.settings, "bias_final_rad_s": f.bias.tolist(),
                "sigma_final": {"attitude_rad": f.sigma[0].tolist(), "bias_rad_s": f.sigma[1].tolist()},
                "rest_fraction": rest / len(last), "mag_rejected_fraction": mag_rejected / len(last)}
        return Estimate(t0 + (idx + 1.0) * h, q, t0 + (idx[last] + 1.0) * h, np.array(bias), info, cov)
