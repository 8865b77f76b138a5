"""Stage 4 of the simulator (docs/architecture.md): the ADC.

Input voltages (k, 3) → integer codes (k, 3). ``backend="tlc2543"`` (the
paper's) converts through the C TLC2543 driver — the source SDCC builds for
the AT89S51 — against its C device model (:func:`attitude_c.tlc2543.convert`:
one X, Y, Z scan per row, the power-up self-test first, every protocol rule
checked); ``"ideal"`` is a vectorized quantizer with the same transfer and no
protocol. Another ADC is another backend of the same shape (the AD7927 of
the UAV thesis: :func:`attitude_c.ad7927.convert`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Literal

import numpy as np

from ..errors import InvalidArgument

__all__ = ["AdcBackend", "AdcModel", "quantize_ideal"]

AdcBackend = Literal["tlc2543", "ideal"]


def quantize_ideal(v: np.ndarray, vref: float, bits: int = 12) -> np.ndarray:
    """Ideal unipolar ADC: code = round(v / vref · 2^bits) clipped to the code
    range (TLC2543 straight binary; beyond the rails it clips)."""
    full = 1 << bits
    c = np.floor(np.asarray(v, dtype=float) / vref * full + 0.5)
    return np.clip(c, 0, full - 1).astype(np.int64)


@dataclass
class AdcModel:
    """The ADC stage: REF+ ``vref`` (V, REF− = 0), ``bits`` per code, ``backend``."""

    vref: float = 5.0
    bits: int = 12
    backend: AdcBackend = "tlc2543"

    def convert(self, volts: np.ndarray, progress: Callable[[int], None] | None = None) -> np.ndarray:
        """(k, 3) voltages of channels X, Y, Z → (k, 3) integer codes (int64)."""
        volts = np.asarray(volts, dtype=float)
        if self.backend == "ideal":
            return quantize_ideal(volts, self.vref, self.bits)
        if self.backend == "tlc2543":
            from ..tlc2543 import convert

            if self.bits != 12:
                raise InvalidArgument(f"the tlc2543 backend converts 12-bit codes, got bits={self.bits}: "
                                      "use the ideal ADC for other resolutions")
            return np.asarray(convert(volts, vref_plus=self.vref, length=12, progress=progress), dtype=np.int64)
        raise InvalidArgument(f"adc backend must be 'tlc2543' or 'ideal', got {self.backend!r}")
