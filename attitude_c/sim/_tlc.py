"""Adapter: ADC conversions through the C TLC2543 driver and its device model."""

from __future__ import annotations

from typing import Callable

import numpy as np


def convert_tlc2543(volts: np.ndarray, vref: float, bits: int,
                    progress: Callable[[int], None] | None = None) -> np.ndarray:
    raise ImportError("attitude_c.tlc2543 is not available in this build")


def available() -> bool:
    try:
        convert_tlc2543(__import__("numpy").full((1, 3), 2.5), 5.0, 12)
    except (ImportError, AttributeError):
        return False
    return True
