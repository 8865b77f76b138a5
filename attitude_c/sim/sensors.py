"""Stage 2 of the simulator (docs/architecture.md): the sensors.

A sensor stage maps the truth (a :class:`~attitude_c.sim.trajectory.Trajectory`)
at the conversion instants to the sensor's output voltages, (k, 3) for the
three axes. The gyro is :class:`Gyro` (a :class:`GyroModel` from the paper's
and the thesis's figures, its turn-on bias and its noise stream); sensors of
other quantities (accelerometer, magnetometer) are stages of the same shape
beside it, each reading its own truth method of the trajectory.

Per conversion instant: the true rate through the gyro's first-order
low-pass, the white noise through the same filter, the scale-factor error and
the turn-on bias, clipped at the range, to volts (``v = null + scale ·
rate``). Every figure that comes from a paper says which; the others are
marked as assumptions in docs/simulation.md.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ..errors import InvalidArgument
from .accelmag import ar1, drift, filtered, switched_off
from .trajectory import Trajectory

__all__ = [
    "DEG",
    "GYRO_PRESETS",
    "Gyro",
    "GyroModel",
    "filtered_rate",
    "gyro_preset",
    "gyro_volts",
    "rate_noise",
]

DEG = math.pi / 180.0


@dataclass(frozen=True)
class GyroModel:
    """One single-axis rate gyro (the three axes share the model).

    Attributes (units in the names): ``range_dps`` saturation (±°/s);
    ``scale_v_per_dps`` nominal scale factor (V per °/s); ``null_v`` zero-rate
    output (V); ``bias_dps`` 1-σ turn-on bias (°/s, drawn per axis from the
    seed, removed by calibration up to noise); ``noise_density`` white rate
    noise (°/s/√Hz); ``bandwidth_hz`` first-order low-pass −3 dB bandwidth
    (None = no filter); ``scale_error`` residual scale-factor error after
    calibration (fraction); ``bias_instability_dps`` flicker bias B (°/s: the
    Allan deviation's floor is 0.664 B) and ``rate_random_walk`` K
    (°/s/√s), 0 = none (in-run bias drift, docs/noise.md).
    """

    name: str
    range_dps: float
    scale_v_per_dps: float
    null_v: float
    bias_dps: float
    noise_density: float
    bandwidth_hz: float | None
    scale_error: float = 0.0
    bias_instability_dps: float = 0.0
    rate_random_walk: float = 0.0

    def without(self, *, noise: bool = False, bias: bool = False, bandwidth: bool = False,
                scale: bool = False) -> GyroModel:
        """A copy with the named error sources switched off."""
        return switched_off(self, noise_density=noise, bias_dps=bias, bandwidth_hz=bandwidth, scale_error=scale)

    @property
    def tau(self) -> float:
        """Time constant of the output filter (s); 0 without one."""
        return 0.0 if not self.bandwidth_hz else 1.0 / (2 * math.pi * self.bandwidth_hz)

    @property
    def span_v(self) -> float:
        """Output swing from null to full range (V) — what the conditioning maps."""
        return self.range_dps * self.scale_v_per_dps

    @property
    def volts_per_rad_s(self) -> float:
        """Nominal output change per rad/s (V)."""
        return self.scale_v_per_dps / DEG

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


GYRO_PRESETS: dict[str, GyroModel] = {
    # ADXRS150 (UAV thesis, sec. 4.3.3 and table 2.2): ±150 °/s, 12.5 mV/(°/s),
    # null 2.50 V, −3 dB bandwidth 40 Hz, rate noise 0.05 °/s/√Hz; turn-on
    # bias: the table's 5 mV temperature drift = 0.4 °/s.
    "adxrs150": GyroModel("adxrs150", range_dps=150.0, scale_v_per_dps=0.0125, null_v=2.50,
                          bias_dps=0.4, noise_density=0.05, bandwidth_hz=40.0),
    # CG-L53 (the paper's gyro, sec. 1.2 and 2): ±90 °/s measuring range
    # (NEC TOKIN catalogue, the paper's ref. [3]). The paper gives no noise,
    # bandwidth, bias or scale factor: the values below are ASSUMPTIONS (a
    # good ceramic/tactical-grade rate gyro), chosen so that the noise still
    # dithers the 12-bit ADC; see docs/simulation.md.
    "cg-l53": GyroModel("cg-l53", range_dps=90.0, scale_v_per_dps=0.0222, null_v=2.50,
                        bias_dps=0.5, noise_density=0.002, bandwidth_hz=100.0),
    # A perfect rate sensor (still saturates at ±300 °/s) for algorithm studies.
    "ideal": GyroModel("ideal", range_dps=300.0, scale_v_per_dps=0.0075, null_v=2.50,
                       bias_dps=0.0, noise_density=0.0, bandwidth_hz=None),
}


def gyro_preset(name: str) -> GyroModel:
    try:
        return GYRO_PRESETS[name]
    except KeyError:
        raise InvalidArgument(f"gyro must be one of {sorted(GYRO_PRESETS)}, got {name!r}") from None


def filtered_rate(traj: Trajectory, t: np.ndarray, tau: float) -> np.ndarray:
    """True body rate seen through a first-order low-pass of time constant tau."""
    return filtered(traj.omega, t, tau)


def rate_noise(n: int, dt: float, gyro: GyroModel, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) rate noise (rad/s) at a spacing dt: white noise of the gyro's
    density through its first-order filter (an exact AR(1) sequence), or,
    without a filter, the equivalent of exactly integrated white noise; plus
    the in-run drift (flicker, rate random walk) when the model has it."""
    return _white_rate(n, dt, gyro, rng) + drift(n, dt, gyro.bias_instability_dps * DEG,
                                                 gyro.rate_random_walk * DEG, rng)


def _white_rate(n: int, dt: float, gyro: GyroModel, rng: np.random.Generator) -> np.ndarray:
    nd = gyro.noise_density * DEG
    if nd == 0 or n == 0:
        return np.zeros((n, 3))
    e = rng.standard_normal((n, 3))
    if not gyro.bandwidth_hz:
        return e * nd / math.sqrt(dt)
    # one-sided density nd²: variance through a first-order filter = nd²·π/2·f_c
    sigma = nd * math.sqrt(math.pi / 2 * gyro.bandwidth_hz)
    a = math.exp(-dt / gyro.tau)
    return ar1(e, a, sigma * math.sqrt(1 - a * a), e[0] * sigma)


def gyro_volts(rate: np.ndarray, gyro: GyroModel, bias: np.ndarray) -> np.ndarray:
    """Measured rate (rad/s, incl. noise) → gyro output voltage, with
    scale-factor error, turn-on bias and saturation at ±range."""
    dps = rate / DEG * (1 + gyro.scale_error) + bias / DEG
    dps = np.clip(dps, -gyro.range_dps, gyro.range_dps)
    return gyro.null_v + gyro.scale_v_per_dps * dps


@dataclass(frozen=True)
class Gyro:
    """The gyro stage: three gyros of one :class:`GyroModel` with their turn-on
    ``bias`` (rad/s, (3,), drawn once per run).

    :meth:`volts` takes the conversion instants (s, (k,), spaced ``dt``) and a
    noise stream and returns the output voltages (k, 3); ``static`` feeds a
    zero true rate (the calibration's still gyros) instead of the trajectory's.
    """

    model: GyroModel
    bias: np.ndarray

    def volts(self, traj: Trajectory, instants: np.ndarray, dt: float, rng: np.random.Generator,
              static: bool = False) -> np.ndarray:
        k = len(instants)
        rate = np.zeros((k, 3)) if static else filtered_rate(traj, instants, self.model.tau)
        rate = rate + rate_noise(k, dt, self.model, rng)
        return gyro_volts(rate, self.model, self.bias)
