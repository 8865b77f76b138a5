"""Analog front ends of the aided board (issue 26): sensor → volts → TLC2543 codes.

Two three-axis parts wired straight to TLC2543 inputs, every one of them, the
sensors and the ADC's REF+ on one supply rail ``supply_v`` (V) — so the codes
are *ratiometric*: a change of the supply changes none of them.

**Ratiometric MEMS accelerometer** (:class:`RatiometricAccel`, ADXL335-class)::

    v = Vs · (1/2 + z + (S/Vs_spec) · clip(K a, ±range)) + n(t)      clipped to [swing, Vs − swing]

``a`` the specific force in g; ``K = diag(1 + s) C`` sensitivity errors ``s``
and cross-axis coupling ``C`` (unit diagonal); ``z`` the zero-g error as a
fraction of Vs (the zero-g output is Vs/2 nominally at any supply);
``S/Vs_spec`` the sensitivity as a fraction of the supply per g (S is quoted at
the data sheet's supply Vs_spec); ``n`` the output noise, *absolute* in volts
(density N·S at Vs_spec), through the first-order filter of the output
resistor and the user's capacitor, f = 1/(2π R C).

**AMR bridge magnetometer with set/reset and an instrumentation amplifier**
(:class:`AmrMagnetometer`, HMC1043-class bridge + AD623-class amplifier)::

    bridge   v_b = Vs · (σ · S (1 + s) · (C h) + o)         σ = +1 after a set pulse, −1 after a reset
    amp      v   = Vs/2 + G · (v_b + v_os) + n(t)            clipped to [swing, Vs − swing]

``h`` the field in gauss; ``S`` the bridge sensitivity (V/V/gauss), ``o`` the
bridge offset (V/V), ``v_os`` the amplifier's input offset (V), ``G`` its
gain, its REF pin at Vs/2. A set/reset pulse flips the sign of the
sensitivity and of nothing else, so the difference of a set and a reset
conversion cancels both offsets: :func:`flip_code` turns the two codes into the
one code the board sends, ``(c_set + 4095 − c_reset) // 2`` — 2047.5 + the field
term, every offset gone (the floor costs −0.25 code on average, part of the zero
the calibration measures).

Each figure of a preset carries its source (``sources``) with the tags of
:mod:`.accelmag`: ``datasheet`` (seen in a copy), ``datasheet†`` (from memory,
not checked here), ``assumption`` (ours, with the reason). docs/simulation.md
and docs/sensor.md tabulate them. The simulator's chain does not use these
stages yet (the aided chain of ``attitude simulate`` is the next issue); the
calibration tests and ``attitude calibrate`` do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import Any, Literal

import numpy as np

from ..errors import InvalidArgument
from .accelmag import G0, SensorErrors, white_noise
from .adc import AdcModel

__all__ = [
    "ACCEL_FRONTENDS",
    "FLIP_ZERO",
    "MAG_FRONTENDS",
    "AmrErrors",
    "AmrMagnetometer",
    "RatiometricAccel",
    "flip_code",
    "tlc2543_codes",
]

_GAUSS_UT = 100.0  # µT per gauss
_FULL = 4096  # TLC2543: 12-bit codes, code = round(v / REF+ · 4096)
_MAX_CODE = _FULL - 1
#: The :func:`flip_code` of zero field: (c_set + 4095 − c_reset) / 2 with c_set = c_reset.
FLIP_ZERO = _MAX_CODE / 2

Flip = Literal[1, -1]


def _check(part: Any, *nonzero: str) -> None:
    """Every number of a part (its float fields) finite and >= 0; those named > 0."""
    for f in fields(part):
        v = getattr(part, f.name)
        if f.type != "float":
            continue
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
            raise InvalidArgument(f"{part.name}: {f.name} must be a finite number >= 0, got {v!r}")
        if f.name in nonzero and v == 0:
            raise InvalidArgument(f"{part.name}: {f.name} must be > 0")


def _draw(rng: np.random.Generator, zero_sigma: float, gain_sigma: float, cross_sigma: float) -> SensorErrors:
    """Zero (fraction of Vs or V/V), gain and cross-axis errors: 12 normal draws, always in that order."""
    e = rng.standard_normal(12)
    c = np.eye(3)
    c[~np.eye(3, dtype=bool)] = e[6:12] * cross_sigma
    return SensorErrors(e[0:3] * zero_sigma, e[3:6] * gain_sigma, c)


def tlc2543_codes(volts: np.ndarray, supply_v: float, backend: Literal["tlc2543", "ideal"] = "tlc2543") -> np.ndarray:
    """Voltages (k, 3) → 12-bit codes (k, 3) of a TLC2543 whose REF+ is the supply
    rail: through the C driver and device model, or the ``ideal`` quantizer."""
    return AdcModel(vref=supply_v, bits=12, backend=backend).convert(np.asarray(volts, dtype=float))


@dataclass(frozen=True)
class RatiometricAccel:
    """A ratiometric analog three-axis accelerometer (see the module docstring).

    ``range_g`` output clip (± g); ``sens_v_per_g`` sensitivity at ``vs_spec``
    (V per g); ``supply_v`` the board's rail (the part's Vs = the ADC's REF+);
    ``zero_sigma_v`` 1σ zero-g output error at ``vs_spec`` (V; it scales with
    the supply); ``sens_sigma`` 1σ sensitivity error (fraction);
    ``cross_sigma`` 1σ cross-axis sensitivity per off-diagonal element
    (fraction); ``noise_density_g`` output noise at ``vs_spec`` (g/√Hz; absolute
    in volts); ``r_filt_ohm``, ``c_filt_f`` the output filter; ``swing_v`` how
    close to the rails the output can go."""

    name: str
    range_g: float
    sens_v_per_g: float
    vs_spec: float
    supply_v: float
    zero_sigma_v: float
    sens_sigma: float
    cross_sigma: float
    noise_density_g: float
    r_filt_ohm: float
    c_filt_f: float
    swing_v: float = 0.1
    sources: dict[str, str] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        _check(self, "range_g", "sens_v_per_g", "vs_spec", "supply_v", "r_filt_ohm", "c_filt_f")

    @property
    def ratio_per_g(self) -> float:
        """Output change per g as a fraction of the supply (ratiometric sensitivity)."""
        return self.sens_v_per_g / self.vs_spec

    @property
    def codes_per_g(self) -> float:
        """Nominal TLC2543 codes per g (REF+ = the supply): ratio_per_g · 4096."""
        return self.ratio_per_g * _FULL

    @property
    def units_per_code(self) -> float:
        """Nominal m/s² per code: what ``acc-scale`` starts from."""
        return G0 / self.codes_per_g

    @property
    def bandwidth_hz(self) -> float:
        """−3 dB of the output filter, 1/(2π R C)."""
        return 1.0 / (2 * math.pi * self.r_filt_ohm * self.c_filt_f)

    @property
    def tau(self) -> float:
        """Time constant of the output filter (s): a moving body's specific force goes
        through it first (``accelmag.filtered(fn, t, part.tau)``) before :meth:`volts`."""
        return 1.0 / (2 * math.pi * self.bandwidth_hz)

    @property
    def noise_sigma_codes(self) -> float:
        """1σ of the filtered output noise in codes at ``supply_v`` (N·S·√(π/2·f_c) V over REF+/4096)."""
        v = self.noise_density_g * self.sens_v_per_g * math.sqrt(math.pi / 2 * self.bandwidth_hz)
        return v / self.supply_v * _FULL

    def at_supply(self, supply_v: float) -> RatiometricAccel:
        """The same part and board on another rail."""
        return replace(self, supply_v=supply_v)

    def without_errors(self) -> RatiometricAccel:
        """No zero, sensitivity, cross-axis or noise error (range, rails and filter kept)."""
        return replace(self, zero_sigma_v=0.0, sens_sigma=0.0, cross_sigma=0.0, noise_density_g=0.0)

    def draw_errors(self, rng: np.random.Generator) -> SensorErrors:
        """This part's errors: ``bias`` the zero-g error as a fraction of Vs, ``scale``,
        ``misalignment`` the cross-axis matrix C."""
        return _draw(rng, self.zero_sigma_v / self.vs_spec, self.sens_sigma, self.cross_sigma)

    def volts(self, specific_force: np.ndarray, errors: SensorErrors, dt: float,
              rng: np.random.Generator) -> np.ndarray:
        """Specific force (k, 3) m/s² (already through the output filter for a moving
        body) → output voltages (k, 3) at samples spaced ``dt`` s."""
        a = np.asarray(specific_force, dtype=float) / G0
        y = np.clip(a @ errors.matrix.T, -self.range_g, self.range_g)
        vs = self.supply_v
        v = vs * (0.5 + errors.bias + self.ratio_per_g * y)
        v = v + white_noise(len(v), dt, self.noise_density_g * self.sens_v_per_g, self.bandwidth_hz, rng)
        return np.clip(v, self.swing_v, vs - self.swing_v)


@dataclass(frozen=True)
class AmrErrors:
    """One AMR magnetometer's errors: ``bridge`` (``bias`` bridge offset V/V,
    ``scale`` sensitivity and gain error, ``misalignment`` cross-axis C) and the
    amplifier's input offset ``amp_offset_v`` (3,) V."""

    bridge: SensorErrors
    amp_offset_v: np.ndarray


@dataclass(frozen=True)
class AmrMagnetometer:
    """Three AMR bridges, set/reset straps and an instrumentation amplifier per axis
    (see the module docstring).

    ``range_gauss`` the bridges' linear range; ``sens_v_per_v_gauss`` bridge
    sensitivity; ``sens_sigma`` its 1σ error (fraction, with the amplifier's
    gain error); ``offset_sigma_v_per_v`` 1σ bridge offset; ``cross_sigma``
    cross-axis (fraction); ``noise_density_v`` noise at the amplifier's input,
    bridge and amplifier together (V/√Hz, absolute); ``gain`` the amplifier
    gain; ``amp_offset_sigma_v`` 1σ amplifier input offset (V);
    ``bandwidth_hz`` the output filter; ``supply_v`` the rail (bridge supply,
    2 × the amplifier's REF, the ADC's REF+); ``swing_v`` the amplifier's
    output swing to the rails."""

    name: str
    range_gauss: float
    sens_v_per_v_gauss: float
    sens_sigma: float
    offset_sigma_v_per_v: float
    cross_sigma: float
    noise_density_v: float
    gain: float
    amp_offset_sigma_v: float
    bandwidth_hz: float
    supply_v: float
    swing_v: float = 0.05
    sources: dict[str, str] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        _check(self, "range_gauss", "sens_v_per_v_gauss", "gain", "bandwidth_hz", "supply_v")

    @property
    def codes_per_ut(self) -> float:
        """Nominal codes per µT of one set (or reset) conversion, and of a :func:`flip_code`:
        G · S · 4096 / 100 (ratiometric: the supply cancels)."""
        return self.gain * self.sens_v_per_v_gauss * _FULL / _GAUSS_UT

    @property
    def units_per_code(self) -> float:
        """Nominal µT per code: what ``mag-scale`` starts from."""
        return 1.0 / self.codes_per_ut

    @property
    def tau(self) -> float:
        """Time constant of the output filter (s), for a moving body's field (as the accelerometer's)."""
        return 1.0 / (2 * math.pi * self.bandwidth_hz)

    @property
    def noise_sigma_codes(self) -> float:
        """1σ of one conversion's noise in codes (G · density · √(π/2·f_c) over REF+/4096)."""
        return self.gain * self.noise_density_v * math.sqrt(math.pi / 2 * self.bandwidth_hz) / self.supply_v * _FULL

    def at_supply(self, supply_v: float) -> AmrMagnetometer:
        return replace(self, supply_v=supply_v)

    def without_errors(self) -> AmrMagnetometer:
        return replace(self, sens_sigma=0.0, offset_sigma_v_per_v=0.0, cross_sigma=0.0, noise_density_v=0.0,
                       amp_offset_sigma_v=0.0)

    def draw_errors(self, rng: np.random.Generator) -> AmrErrors:
        """Bridge offset, sensitivity, cross-axis (12 draws), then the amplifier offsets (3)."""
        bridge = _draw(rng, self.offset_sigma_v_per_v, self.sens_sigma, self.cross_sigma)
        return AmrErrors(bridge, rng.standard_normal(3) * self.amp_offset_sigma_v)

    def volts(self, field_ut: np.ndarray, errors: AmrErrors, flip: Flip, dt: float,
              rng: np.random.Generator) -> np.ndarray:
        """Field (k, 3) µT → amplifier outputs (k, 3) after a set (``flip`` = 1) or a
        reset (−1) pulse, at samples spaced ``dt`` s."""
        if flip not in (1, -1):
            raise InvalidArgument(f"flip must be 1 (set) or -1 (reset), got {flip!r}")
        h = np.clip(np.asarray(field_ut, dtype=float) / _GAUSS_UT @ errors.bridge.misalignment.T,
                    -self.range_gauss, self.range_gauss)
        vs = self.supply_v
        sens = self.sens_v_per_v_gauss * (1.0 + errors.bridge.scale)
        bridge = vs * (flip * sens * h + errors.bridge.bias)
        v = vs / 2 + self.gain * (bridge + errors.amp_offset_v)
        v = v + white_noise(len(v), dt, self.gain * self.noise_density_v, self.bandwidth_hz, rng)
        return np.clip(v, self.swing_v, vs - self.swing_v)

    def set_reset_codes(self, field_ut: np.ndarray, errors: AmrErrors, dt: float, rng: np.random.Generator,
                        backend: Literal["tlc2543", "ideal"] = "tlc2543") -> tuple[np.ndarray, np.ndarray]:
        """The codes (k, 3) of a set and of a reset conversion of each sample (the two
        conversions of a sample a few µs apart: the same field, independent noise)."""
        c_set = tlc2543_codes(self.volts(field_ut, errors, 1, dt, rng), self.supply_v, backend)
        c_reset = tlc2543_codes(self.volts(field_ut, errors, -1, dt, rng), self.supply_v, backend)
        return c_set, c_reset


def flip_code(c_set: np.ndarray, c_reset: np.ndarray) -> np.ndarray:
    """The board's magnetometer code from a set and a reset conversion:
    ``(c_set + 4095 − c_reset) // 2`` (0..4095; 2047.5 + the field term, every
    offset cancelled; the floor is −0.25 code on average)."""
    s = np.asarray(c_set, dtype=np.int64)
    r = np.asarray(c_reset, dtype=np.int64)
    if s.shape != r.shape or s.size and (min(s.min(), r.min()) < 0 or max(s.max(), r.max()) > _MAX_CODE):
        raise InvalidArgument(f"c_set and c_reset must be 12-bit codes of one shape, got shapes {s.shape}, {r.shape}")
    return (s + _MAX_CODE - r) // 2


# ---------------------------------------------------------------------------
# presets (tags as in accelmag: datasheet, datasheet†, assumption)
# ---------------------------------------------------------------------------

ACCEL_FRONTENDS: dict[str, RatiometricAccel] = {
    "adxl335": RatiometricAccel(
        "adxl335", range_g=3.6, sens_v_per_g=0.300, vs_spec=3.0, supply_v=3.3, zero_sigma_v=0.050,
        sens_sigma=0.033, cross_sigma=0.005, noise_density_g=150e-6, r_filt_ohm=32e3, c_filt_f=0.1e-6,
        swing_v=0.1,
        sources={
            "ratiometric": "datasheet: ADXL335 Rev. B p. 12, 'Use with operating voltages other than 3 V': "
                           "sensitivity proportional to Vs (360 mV/g at 3.6 V, 195 mV/g at 2 V), zero g output "
                           "nominally Vs/2 at all supplies, noise absolute in volts",
            "range_g": "datasheet†: Table 1 measurement range ±3.6 g typical (±3 g minimum)",
            "sens_v_per_g": "datasheet†: Table 1 sensitivity 270/300/330 mV/g (min/typ/max) at Vs = 3 V",
            "sens_sigma": "assumption: the ±10 % min/max of Table 1 taken as ±3σ (3.3 %)",
            "zero_sigma_v": "assumption: Table 1's X/Y 0 g voltage 1.35/1.5/1.65 V taken as ±3σ (50 mV)",
            "cross_sigma": "assumption: Table 1's cross-axis sensitivity ±1 % taken as ±2σ (0.5 %)",
            "noise_density_g": "datasheet†: Table 1 noise density X/Y 150 µg/√Hz at Vs = 3 V (Z: 300; "
                               "the preset uses the X/Y figure on all axes)",
            "r_filt_ohm": "datasheet†: the 32 kΩ output resistor (Figure 1; ±15 % tolerance)",
            "c_filt_f": "assumption: 0.1 µF per axis, the data sheet's test condition: 50 Hz",
            "supply_v": "assumption: one 3.3 V rail for the part (1.8-3.6 V) and the TLC2543's REF+",
            "swing_v": "assumption: 0.1 V from each rail",
        }),
}

MAG_FRONTENDS: dict[str, AmrMagnetometer] = {
    "hmc1043-ad623": AmrMagnetometer(
        "hmc1043-ad623", range_gauss=6.0, sens_v_per_v_gauss=1.0e-3, sens_sigma=0.07,
        offset_sigma_v_per_v=0.42e-3, cross_sigma=0.01, noise_density_v=60e-9, gain=200.0,
        amp_offset_sigma_v=67e-6, bandwidth_hz=50.0, supply_v=3.3, swing_v=0.05,
        sources={
            "set_reset": "datasheet: set/reset straps flip the polarity of the bridge output (HMC1001/1002/"
                         "1021/1022 data sheet, 'Set/Reset Straps'); (set − reset)/2 removes the offset "
                         "(HMC5883L data sheet, 'H-Bridge for Set/Reset Strap Drive')",
            "range_gauss": "datasheet†: HMC1043 field range ±6 gauss",
            "sens_v_per_v_gauss": "datasheet†: HMC1043 sensitivity 0.8/1.0/1.2 mV/V/gauss (min/typ/max)",
            "sens_sigma": "assumption: the ±20 % min/max taken as ±3σ, the amplifier's gain error (RG "
                          "tolerance, ~0.5 %) included",
            "offset_sigma_v_per_v": "assumption: HMC1043 bridge offset ±1.25 mV/V (datasheet†) as ±3σ",
            "cross_sigma": "assumption: 1 % (the HMC104x cross-axis effect, datasheet† ±3 % FS, mostly "
                           "removed by set/reset)",
            "noise_density_v": "assumption: bridge 50 nV/√Hz at 1 Hz (HMC1043, datasheet†) with the AD623's "
                               "input noise (35 nV/√Hz, datasheet†) in quadrature, taken as white",
            "gain": "assumption: G = 200 (AD623, RG ≈ 503 Ω): 0.5 gauss → 0.33 V at 3.3 V; the worst "
                    "bridge offset (±1.25 mV/V → ±0.83 V) still leaves ±1.2 gauss of range",
            "amp_offset_sigma_v": "assumption: AD623A input offset 200 µV max (datasheet†) taken as ±3σ",
            "bandwidth_hz": "assumption: an RC of 50 Hz after the amplifier",
            "supply_v": "assumption: one 3.3 V rail: bridge supply, amplifier REF = Vs/2 by a divider, "
                        "TLC2543 REF+",
            "swing_v": "assumption: 50 mV from each rail (AD623 rail-to-rail output)",
        }),
}
