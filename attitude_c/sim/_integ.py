"""Adapter to the integrator (attitude_c.integrate / integrate_rates).

Gives, for every method, the attitude after each update and the index of the
last increment that update consumed, so that the chain can put a time on it.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..core import METHODS, PRECISIONS, Method, Precision
from ..names import samples_per_update
from ..errors import InvalidArgument


def check_method(method: str) -> None:
    if method not in METHODS:
        raise InvalidArgument(f"method must be one of {METHODS}, got {method!r}")


def check_precision(precision: str) -> None:
    if precision not in PRECISIONS:
        raise InvalidArgument(f"precision must be one of {PRECISIONS}, got {precision!r}")


def precision_available(precision: Precision) -> bool:
    """Whether the installed core supports ``precision`` (fixed lands later)."""
    import attitude_c

    try:
        attitude_c.integrate(np.zeros((3, 3)), method="rv3", precision=precision)
    except (ImportError, AttributeError, ValueError, TypeError, NotImplementedError):
        return False
    return True


def run_integrator(dtheta: np.ndarray, method: Method, q0_at: Callable[[float], np.ndarray],
                   precision: Precision, h: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Integrate increments (n, 3) of period h.

    ``q0_at(offset)`` gives the initial attitude ``offset`` periods after the
    first increment starts. Returns ``(quats (M, 4), last (M,), offset)``:
    output j is the attitude at ``(last[j] + offset)`` periods, ``last[j]``
    the index of the newest increment it used (offset 1: the end of that
    increment). ``rk4`` takes the mean rates Δθ/h, corrected to the rates at
    the interval midpoints (second-difference term), as rate samples (rows t, t+h/2, t+h of a 2h step), so it starts half
    a period in and its outputs fall at midpoints (offset 0.5).
    """
    import attitude_c

    check_method(method)
    check_precision(precision)
    dtheta = np.ascontiguousarray(dtheta, dtype=float)
    n = len(dtheta)
    empty = (np.zeros((0, 4)), np.zeros(0, dtype=int), 1.0)
    if method == "rk4":
        if n < 3:
            return empty
        # mean rate over an interval = midpoint rate + h²ω''/24 + O(h⁴): remove
        # the second-order term with the second difference of the means
        mean = dtheta / h
        w = mean.copy()
        if n >= 3:
            w[1:-1] -= (mean[2:] - 2 * mean[1:-1] + mean[:-2]) / 24
            w[0] -= (mean[2] - 2 * mean[1] + mean[0]) / 24
            w[-1] -= (mean[-1] - 2 * mean[-2] + mean[-3]) / 24
        q = attitude_c.integrate_rates(w, h, method="rk4", q0=q0_at(0.5),
                                       precision=precision)
        q = np.asarray(q, dtype=float)
        last = 2 * np.arange(1, len(q) + 1)
        return q, last, 0.5
    k = samples_per_update(method)  # increments consumed per update
    n_use = (n // k) * k
    if n_use == 0:
        return empty
    q = np.asarray(attitude_c.integrate(dtheta[:n_use], method=method, q0=q0_at(0.0),
                                        precision=precision), dtype=np.float64)
    m = len(q)
    if m * k == n_use:
        last = np.arange(1, m + 1) * k - 1
    else:  # pragma: no cover - defensive: unexpected output count
        raise RuntimeError(f"integrate({method!r}) returned {m} updates for {n_use} increments")
    return q, last, 1.0
