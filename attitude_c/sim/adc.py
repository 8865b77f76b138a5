"""Stage 4 of the simulator (docs/architecture.md): the ADC.

Input voltages (k, 3) → integer codes (k, 3). ``backend="tlc2543"`` (the
paper's) converts through the C TLC2543 driver — the source SDCC builds for
the AT89S51 — against its C device model (:func:`attitude_c.tlc2543.convert`:
one X, Y, Z scan per row, the power-up self-test first, every protocol rule
checked); ``"ad7927"`` (the UAV thesis's, sec. 4.5) through the C AD7927
driver against its C twin (:func:`attitude_c.ad7927.convert`: power-up, one
channel write per conversion, the returned channel address checked on every
frame), with the thesis's wiring (REFIN 2.5 V, RANGE = 0: 0..2·REFIN = 0–5 V;
gyro x, y, z on VIN0–2, accelerometer x, y, z on VIN4–6,
``attitude_c.ad7927.THESIS_BOARD``); ``"ideal"`` is a vectorized quantizer
with the TLC2543's transfer and no protocol.

The two parts' transfers differ by half an LSB: the TLC2543 (and ``ideal``)
round, ``code = round(v/vref · 4096)``; the AD7927's code c covers
[c, c + 1) LSB (``floor``). :meth:`AdcModel.nominal_code` gives the code a
voltage reads as, for the host's nominal zero.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Callable, Literal

import numpy as np

from ..errors import InvalidArgument

__all__ = ["ADC_BACKENDS", "AdcBackend", "AdcModel", "quantize_ideal"]

AdcBackend = Literal["tlc2543", "ad7927", "ideal"]
ADC_BACKENDS: tuple[str, ...] = ("tlc2543", "ad7927", "ideal")


def quantize_ideal(v: np.ndarray, vref: float, bits: int = 12) -> np.ndarray:
    """Ideal unipolar ADC: code = round(v / vref · 2^bits) clipped to the code
    range (TLC2543 straight binary; beyond the rails it clips)."""
    full = 1 << bits
    c = np.floor(np.asarray(v, dtype=float) / vref * full + 0.5)
    return np.clip(c, 0, full - 1).astype(np.int64)


@dataclass
class AdcModel:
    """The ADC stage: full-scale input ``vref`` (V, from 0; the TLC2543's REF+,
    the AD7927's 2·REFIN), ``bits`` per code, ``backend``."""

    vref: float = 5.0
    bits: int = 12
    backend: AdcBackend = "tlc2543"

    def convert(self, volts: np.ndarray, progress: Callable[[int], None] | None = None,
                channels: Sequence[int] | None = None) -> np.ndarray:
        """(k, 3) voltages → (k, 3) integer codes (int64). ``channels``: the inputs
        the three columns are wired to (the AD7927's VIN numbers; default 0, 1, 2)."""
        volts = np.asarray(volts, dtype=float)
        if self.backend == "ideal":
            return quantize_ideal(volts, self.vref, self.bits)
        if self.backend in ("tlc2543", "ad7927") and self.bits != 12:
            raise InvalidArgument(f"the {self.backend} backend converts 12-bit codes, got bits={self.bits}: "
                                  "use the ideal ADC for other resolutions")
        if self.backend == "tlc2543":
            from ..tlc2543 import convert

            return np.asarray(convert(volts, vref_plus=self.vref, length=12, progress=progress), dtype=np.int64)
        if self.backend == "ad7927":
            from ..ad7927 import convert as convert_ad7927

            chans = [0, 1, 2] if channels is None else list(channels)
            return np.asarray(convert_ad7927(volts, self.vref / 2, channels=chans, range_double=True,
                                             progress=progress), dtype=np.int64)
        raise InvalidArgument(f"adc backend must be one of {ADC_BACKENDS}, got {self.backend!r}")

    def nominal_code(self, v: float) -> float:
        """The (fractional) code an input of v volts reads as, on average: v/vref · 2^bits,
        less half an LSB for the AD7927 (its code c covers [c, c + 1) LSB)."""
        c = v / self.vref * (1 << self.bits)
        return c - 0.5 if self.backend == "ad7927" else c
