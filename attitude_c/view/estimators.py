"""Attitude estimators a source of raw inertial samples can run (the serial
port's gyro codes, a BROAD recording): one registry, chosen by name with
``attitude view --estimator NAME``.

An estimator takes one sample at a time -- body rate ``gyr`` (rad/s) over
``dt`` seconds, and the accelerometer and magnetometer when the source has
them -- and returns the attitude quaternion (scalar first, body -> ENU)
when the sample completes an attitude update, else None (an rv3 frame
being filled).

The registry holds the strapdown integrator (``integrator``: every
:data:`attitude_c.core.METHODS`) and the attitude filter (``ahrs``:
:class:`attitude_c.Ahrs`, docs/ahrs.md, with the library's default
settings; it needs the accelerometer, so ``needs_acc`` makes the sources
without one, such as the legacy serial link, refuse it with a clear
message). Another estimator plugs in by one :func:`register` call with a
factory building an object with this ``update``.

``"auto"`` (:data:`AUTO`, ``attitude view``'s default) is not an estimator but a
rule, :func:`choose`: the attitude filter for a source that delivers both the
accelerometer and the magnetometer (a BROAD trial), else the integrator.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import core
from ..errors import InvalidArgument

__all__ = ["AUTO", "ESTIMATORS", "AhrsEstimator", "Estimator", "EstimatorSpec", "IntegratorEstimator", "choose",
           "make_estimator", "register"]


class Estimator(Protocol):
    """What a source calls per sample."""

    label: str  #: shown on the page, e.g. ``"integrator rv3"``

    def update(self, gyr: NDArray[np.float64], dt: float, acc: NDArray[np.float64] | None = None,
               mag: NDArray[np.float64] | None = None) -> NDArray[np.float64] | None:
        """Feed one sample; the attitude (4,) if it completed an update, else None."""
        ...


@dataclass(frozen=True)
class EstimatorSpec:
    name: str
    summary: str
    needs_acc: bool
    #: factory(method=..., q0=..., rate=..., settings=...) -> Estimator; keywords it does not use are ignored
    make: Callable[..., Estimator]


class IntegratorEstimator:
    """The strapdown integrator (:class:`attitude_c.Integrator`): increments
    ``gyr * dt`` for the increment methods, rates with ``dt`` for ``rk4``."""

    def __init__(self, method: core.Method = "rv3", q0: ArrayLike | None = None,
                 settings: Mapping[str, Any] | None = None, **_: Any) -> None:
        if settings:
            raise InvalidArgument(f"filter settings ({', '.join(settings)}) are for the ahrs estimator, "
                                  "not the integrator")
        self.integ = core.Integrator(method, q0)
        self.method = method
        self.label = f"integrator {method}"

    def update(self, gyr: NDArray[np.float64], dt: float, acc: NDArray[np.float64] | None = None,
               mag: NDArray[np.float64] | None = None) -> NDArray[np.float64] | None:
        g = np.asarray(gyr, dtype=np.float64)
        if self.method == "rk4":
            out = self.integ.update(g.reshape(1, 3), dt=dt)
        else:
            out = self.integ.update(g * dt)
        return out[-1].astype(np.float64) if len(out) else None


class AhrsEstimator:
    """The attitude filter (:class:`attitude_c.Ahrs`, the library's default settings
    but ``settings``: ``attitude view --ahrs-setting``; its own increment method,
    so ``method`` is not used): one attitude per sample.
    Six-axis for a sample whose field is absent or not finite; a sample whose
    rate or specific force is not finite is skipped (None)."""

    def __init__(self, q0: ArrayLike | None = None, rate: float | None = None,
                 settings: Mapping[str, Any] | None = None, **_: Any) -> None:
        from ..ahrs_filter import Ahrs

        self.filter = Ahrs(rate=rate, q0=q0, **dict(settings or {}))
        self.label = f"ahrs ({self.filter.settings['method']})"

    def update(self, gyr: NDArray[np.float64], dt: float, acc: NDArray[np.float64] | None = None,
               mag: NDArray[np.float64] | None = None) -> NDArray[np.float64] | None:
        if acc is None:
            raise InvalidArgument("the ahrs estimator needs the accelerometer sample (acc)")
        g = np.asarray(gyr, dtype=np.float64)
        a = np.asarray(acc, dtype=np.float64)
        if not (np.isfinite(g).all() and np.isfinite(a).all()):
            return None
        m = None if mag is None or not np.isfinite(mag).all() else np.asarray(mag, dtype=np.float64)
        return np.asarray(self.filter.update(g, a, m, dt=dt), dtype=np.float64)


ESTIMATORS: dict[str, EstimatorSpec] = {}


def register(spec: EstimatorSpec) -> None:
    """Add (or replace) an estimator under ``spec.name``."""
    ESTIMATORS[spec.name] = spec


register(EstimatorSpec("integrator", "strapdown integrator of the gyro rates (--method)", False,
                       IntegratorEstimator))
register(EstimatorSpec("ahrs", "the attitude filter: gyro + accelerometer (+ magnetometer), default settings "
                       "(docs/ahrs.md)", True, AhrsEstimator))


#: The name that asks :func:`choose` to pick the estimator from what the source delivers.
AUTO = "auto"


def choose(name: str, *, has_acc: bool, has_mag: bool, method_given: bool = False) -> tuple[str, str]:
    """The estimator to run for ``name`` and why: ``(name, "")`` for a name given,
    for :data:`AUTO` the attitude filter (``"ahrs"``) when the source delivers the
    accelerometer and the magnetometer, else ``"integrator"``; a ``method_given``
    (an integrator method asked for) keeps the integrator."""
    if name != AUTO:
        return name, ""
    if method_given:
        return "integrator", "auto: an integrator method was given"
    if has_acc and has_mag:
        return "ahrs", "auto: the source has accelerometer and magnetometer data"
    return "integrator", "auto: the source has no accelerometer and magnetometer data"


def make_estimator(name: str, *, has_acc: bool, **kw: Any) -> Estimator:
    """Build estimator ``name`` for a source (``has_acc``: the source delivers
    accelerometer samples). Raises :class:`InvalidArgument` for an unknown
    name or one the source cannot feed."""
    spec = ESTIMATORS.get(name)
    if spec is None:
        raise InvalidArgument(f"estimator must be one of {', '.join(sorted(ESTIMATORS))}, got {name!r}")
    if spec.needs_acc and not has_acc:
        raise InvalidArgument(f"estimator {name!r} needs accelerometer samples, which this source does "
                              "not deliver")
    return spec.make(**kw)
