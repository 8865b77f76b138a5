"""Stage 8 of the simulator (docs/architecture.md): the attitude estimator.

Today the rotation-vector integrator of the library (:func:`attitude_c.integrate`,
any method, f64/f32/fixed); an estimator that also reads other sensors (a
filter) is a stage of the same shape: it takes the host's :class:`Decoded`
samples and the initial attitude and returns an :class:`Estimate`, the
attitude at known times.

Increment methods get the increments; an update that consumes increments
k−2…k is the attitude at the end of period k. ``rk4`` integrates rates: it
gets the mean rates Δθ/h corrected to midpoint rates (``ω_mid ≈ m_k −
(m_{k+1} − 2m_k + m_{k−1})/24``: a mean over h equals the midpoint value plus
h²ω''/24), as rows t, t+h/2, t+h of 2h steps; its outputs fall at period
midpoints.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..core import Method, Precision, integrate, integrate_rates
from ..names import samples_per_update
from .host import Decoded

__all__ = ["Estimate", "Integrate"]


@dataclass
class Estimate:
    """Estimated attitudes ``q`` (M, 4) at times ``t`` (M,) (s)."""

    t: np.ndarray
    q: np.ndarray


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
