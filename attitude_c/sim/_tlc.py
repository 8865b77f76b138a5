"""Adapter: ADC conversions through the C TLC2543 driver and its device model.

``attitude_c.tlc2543.convert`` runs the real driver source (the one SDCC
builds for the AT89S51) against the C twin of the device model, which checks
the protocol and quantizes like the chip: one full X, Y, Z scan per row,
power-up self-test first.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..errors import InvalidArgument


def convert_tlc2543(volts: np.ndarray, vref: float, bits: int,
                    progress: Callable[[int], None] | None = None) -> np.ndarray:
    """(n, 3) volts on AIN0..2 → (n, 3) 12-bit codes through the C driver."""
    try:
        from ..tlc2543 import convert
    except ImportError as exc:
        raise ImportError(f"attitude_c.tlc2543 is not available in this build ({exc})") from exc
    if bits != 12:
        raise InvalidArgument(f"the tlc2543 backend converts 12-bit codes, got bits={bits}: "
                              "use the ideal ADC for other resolutions")
    return np.asarray(convert(np.asarray(volts, dtype=float), vref_plus=vref, length=12,
                              progress=progress), dtype=np.int64)


def available() -> bool:
    """Whether the C TLC2543 driver and its model are built into this install."""
    try:
        convert_tlc2543(np.full((1, 3), 2.5), 5.0, 12)
    except (ImportError, AttributeError):
        return False
    return True
