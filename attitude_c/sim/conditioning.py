"""Stage 3 of the simulator (docs/architecture.md): analog conditioning.

Between a sensor and the ADC (the paper's "signal processing" of Fig. 2, the
thesis's AD623 follower, sec. 4.4): an offset and a gain that map the
sensor's range onto the ADC's input range.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .sensors import GyroModel

__all__ = ["Conditioning"]


@dataclass(frozen=True)
class Conditioning:
    """``v_adc = vref/2 + gain · (v_sensor − null_v)`` with the gain chosen so
    that the sensor's full range uses ``span`` of the ADC half-range (default
    0.9: 10 % headroom before the ADC clips). ``vref`` = the ADC's REF+ (V),
    REF− = 0."""

    vref: float = 5.0
    span: float = 0.9

    def gain(self, gyro: GyroModel) -> float:
        return self.span * (self.vref / 2) / (gyro.range_dps * gyro.scale_v_per_dps)

    def apply(self, volts: np.ndarray, gyro: GyroModel) -> np.ndarray:
        """Sensor output voltages (k, 3) → ADC input voltages (k, 3)."""
        return self.vref / 2 + self.gain(gyro) * (volts - gyro.null_v)
