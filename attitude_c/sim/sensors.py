"""Gyro, analog conditioning, ADC and increment-formation models.

The signal path of one axis, as on the paper's acquisition board (sec. 2,
Fig. 1–3): gyro (rate → voltage) → analog conditioning (offset and gain to
the ADC input range) → TLC2543 12-bit ADC → the AT89S51 sums ``oversample``
conversions per sample period and sends the sum (one 16-bit word per axis) →
the host subtracts the calibrated zero-rate sum and scales to an angle
increment. Every figure below that comes from a paper says which; the
others are marked as assumptions in docs/simulation.md.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any, Callable, Literal

import numpy as np

from ..errors import InvalidArgument
from .trajectory import Trajectory

__all__ = [
    "GYRO_PRESETS",
    "AdcModel",
    "Board",
    "Calibration",
    "Conditioning",
    "GyroModel",
    "gyro_preset",
    "quantize_ideal",
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
    calibration (fraction).
    """

    name: str
    range_dps: float
    scale_v_per_dps: float
    null_v: float
    bias_dps: float
    noise_density: float
    bandwidth_hz: float | None
    scale_error: float = 0.0

    def without(self, *, noise: bool = False, bias: bool = False, bandwidth: bool = False,
                scale: bool = False) -> GyroModel:
        """A copy with the named error sources switched off."""
        kw: dict[str, Any] = {}
        if noise:
            kw["noise_density"] = 0.0
        if bias:
            kw["bias_dps"] = 0.0
        if bandwidth:
            kw["bandwidth_hz"] = None
        if scale:
            kw["scale_error"] = 0.0
        return replace(self, **kw)

    @property
    def tau(self) -> float:
        """Time constant of the output filter (s); 0 without one."""
        return 0.0 if not self.bandwidth_hz else 1.0 / (2 * math.pi * self.bandwidth_hz)

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


@dataclass(frozen=True)
class Conditioning:
    """Analog conditioning between gyro and ADC (the paper's "signal
    processing" of Fig. 2 and the thesis's AD623 follower, sec. 4.4).

    ``v_adc = vref/2 + gain · (v_gyro − null_v)`` with the gain chosen so that
    the gyro's full range uses ``span`` of the ADC half-range (default 0.9:
    10 % headroom before the ADC clips). ``vref`` = TLC2543 REF+ (V), REF− = 0.
    """

    vref: float = 5.0
    span: float = 0.9

    def gain(self, gyro: GyroModel) -> float:
        return self.span * (self.vref / 2) / (gyro.range_dps * gyro.scale_v_per_dps)


def quantize_ideal(v: np.ndarray, vref: float, bits: int = 12) -> np.ndarray:
    """Ideal unipolar ADC: code = round(v / vref · 2^bits) clipped to the code
    range (TLC2543 straight binary; beyond the rails it clips)."""
    full = 1 << bits
    c = np.floor(np.asarray(v, dtype=float) / vref * full + 0.5)
    return np.clip(c, 0, full - 1).astype(np.int64)


@dataclass
class AdcModel:
    """The ADC stage: ``backend`` ``"tlc2543"`` converts through the C TLC2543
    driver against its device model (attitude_c.tlc2543); ``"ideal"`` is the
    vectorized quantizer above (same transfer, no protocol)."""

    vref: float = 5.0
    bits: int = 12
    backend: Literal["tlc2543", "ideal"] = "tlc2543"

    def convert(self, volts: np.ndarray, progress: Callable[[int], None] | None = None) -> np.ndarray:
        """(n, 3) voltages of channels X, Y, Z → (n, 3) integer codes."""
        volts = np.asarray(volts, dtype=float)
        if self.backend == "ideal":
            return quantize_ideal(volts, self.vref, self.bits)
        if self.backend == "tlc2543":
            from ._tlc import convert_tlc2543

            return convert_tlc2543(volts, self.vref, self.bits, progress)
        raise InvalidArgument(f"adc backend must be 'tlc2543' or 'ideal', got {self.backend!r}")


@dataclass(frozen=True)
class Board:
    """Increment formation on the acquisition board: ``oversample``
    conversions per axis per sample period at the midpoints of equal
    sub-intervals (delayed by the gyro filter's group delay when
    ``delay_comp``), summed into one 16-bit word per axis."""

    oversample: int = 16
    delay_comp: bool = True
    sample_at: Literal["mid", "start"] = "mid"  # "mid": sub-interval midpoints; "start": their starts

    def check(self, bits: int) -> None:
        if self.sample_at not in ("mid", "start"):
            raise InvalidArgument(f"sample_at must be 'mid' or 'start', got {self.sample_at!r}")
        if not (isinstance(bits, int) and 1 <= bits <= 16):
            raise InvalidArgument(f"ADC bits must be 1..16 (16-bit link words), got {bits!r}")
        if not 1 <= self.oversample <= (1 << (16 - bits)):
            raise InvalidArgument(
                f"oversample must be 1..{1 << (16 - bits)} so that the sum of {bits}-bit codes "
                f"fits the link's 16-bit word, got {self.oversample}")


# Gauss–Laguerre nodes for the first-order filter y(t) = ∫ ω(t−s) e^{−s/τ}/τ ds:
# 16 nodes integrate e^{−x}·(polynomial of degree 31) exactly; for rates of
# ≤ 1 Hz and τ ≤ 5 ms the remainder is far below 1e-12 rad/s.
_GLA_X, _GLA_W = np.polynomial.laguerre.laggauss(16)


def filtered_rate(traj: Trajectory, t: np.ndarray, tau: float) -> np.ndarray:
    """True body rate seen through a first-order low-pass of time constant tau."""
    if tau <= 0:
        return traj.omega(t)
    tt = np.asarray(t, dtype=float)[..., None] - tau * _GLA_X
    return np.einsum("j,...jk->...k", _GLA_W, traj.omega(tt))


def rate_noise(n: int, dt: float, gyro: GyroModel, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) rate noise (rad/s) at a spacing dt: white noise of the gyro's
    density through its first-order filter (an exact AR(1) sequence), or,
    without a filter, the equivalent of exactly integrated white noise."""
    nd = gyro.noise_density * DEG
    if nd == 0 or n == 0:
        return np.zeros((n, 3))
    e = rng.standard_normal((n, 3))
    if not gyro.bandwidth_hz:
        return e * nd / math.sqrt(dt)
    # one-sided density nd²: variance through a first-order filter = nd²·π/2·f_c
    sigma = nd * math.sqrt(math.pi / 2 * gyro.bandwidth_hz)
    a = math.exp(-dt / gyro.tau)
    out = np.empty((n, 3))
    x = e[0] * sigma
    out[0] = x
    b = sigma * math.sqrt(1 - a * a)
    for i in range(1, n):  # n is at most a few 10^4: a plain loop is fine
        x = a * x + b * e[i]
        out[i] = x
    return out


def gyro_volts(rate: np.ndarray, gyro: GyroModel, bias: np.ndarray) -> np.ndarray:
    """Measured rate (rad/s, incl. noise) → gyro output voltage, with
    scale-factor error, turn-on bias and saturation at ±range."""
    dps = rate / DEG * (1 + gyro.scale_error) + bias / DEG
    dps = np.clip(dps, -gyro.range_dps, gyro.range_dps)
    return gyro.null_v + gyro.scale_v_per_dps * dps


@dataclass
class Calibration:
    """What the host knows: zero-rate code sum per axis and rad/s per code."""

    zero_sum: np.ndarray  # (3,) expected word at zero rate (oversample codes summed)
    rad_per_s_per_code: float
    oversample: int

    def increments(self, words: np.ndarray, h: float) -> np.ndarray:
        """(n, 3) words → (n, 3) angle increments (rad)."""
        w = np.asarray(words, dtype=float)
        return (w - self.zero_sum) * self.rad_per_s_per_code * (h / self.oversample)

    def to_dict(self) -> dict[str, Any]:
        return {"zero_code": (self.zero_sum / self.oversample).tolist(),
                "rad_per_s_per_code": self.rad_per_s_per_code, "oversample": self.oversample}
