"""Stage 3 of the simulator (docs/architecture.md): analog conditioning.

Between a sensor and the ADC (the paper's "signal processing" of Fig. 2, the
thesis's AD623 follower, sec. 4.4): an offset and a gain that map the
sensor's range onto the ADC's input range.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

__all__ = ["AnalogSensor", "Conditioning"]


class AnalogSensor(Protocol):
    """What the conditioning needs of a sensor: its zero output and its swing (V)."""

    @property
    def null_v(self) -> float: ...

    @property
    def span_v(self) -> float: ...


@dataclass(frozen=True)
class Conditioning:
    """``v_adc = vref/2 + gain · (v_sensor − null_v)`` with the gain chosen so
    that the sensor's full range (``span_v``: a gyro's, an accelerometer's)
    uses ``span`` of the ADC half-range (default 0.9: 10 % headroom before the
    ADC clips). ``vref`` = the ADC's full-scale input (V), from 0.

    ``follower=True``: a unity-gain follower, ``v_adc = v_sensor`` (the UAV
    thesis's AD623, sec. 4.4: its ADXRS150 and ADXL202 outputs span 0–5 V
    around 2.5 V and go straight into the AD7927's 0–5 V range)."""

    vref: float = 5.0
    span: float = 0.9
    follower: bool = False

    def gain(self, sensor: AnalogSensor) -> float:
        if self.follower:
            return 1.0
        return self.span * (self.vref / 2) / sensor.span_v

    def apply(self, volts: np.ndarray, sensor: AnalogSensor) -> np.ndarray:
        """Sensor output voltages (k, 3) → ADC input voltages (k, 3)."""
        if self.follower:
            return np.asarray(volts, dtype=float)
        return self.vref / 2 + self.gain(sensor) * (volts - sensor.null_v)

    def null_at_adc(self, sensor: AnalogSensor) -> float:
        """The ADC input voltage of the sensor's zero output (V)."""
        return sensor.null_v if self.follower else self.vref / 2
