"""The aided board's analog front ends (attitude_c.sim.frontend, issue 26) against
closed forms: zero input reads mid-code, the sensitivity in codes, codes invariant
to the supply (ratiometric), set/reset cancelling the bridge and amplifier offsets,
the noise in codes. Codes come from the C TLC2543 driver and device model unless
a test says ``ideal``; truth is written from the transfer functions of the module
docstring (code = round(v / REF+ · 4096)), not taken from the module.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from attitude_c.errors import InvalidArgument
from attitude_c.sim.accelmag import G0, SensorErrors
from attitude_c.sim.frontend import (
    ACCEL_FRONTENDS,
    MAG_FRONTENDS,
    AmrErrors,
    flip_code,
    tlc2543_codes,
)

ACC = ACCEL_FRONTENDS["adxl335"]
MAG = MAG_FRONTENDS["hmc1043-ad623"]
NO_MAG_ERRORS = AmrErrors(SensorErrors.none(), np.zeros(3))


def _round(x: np.ndarray) -> np.ndarray:
    return np.floor(np.asarray(x) + 0.5)


def test_zero_input_reads_mid_code() -> None:
    rng = np.random.default_rng(0)
    acc = ACC.without_errors()
    codes = tlc2543_codes(acc.volts(np.zeros((4, 3)), SensorErrors.none(), 0.01, rng), acc.supply_v)
    assert (codes == 2048).all()  # Vs/2 on REF+ = Vs: exactly half of 4096
    mag = MAG.without_errors()
    c_set, c_reset = mag.set_reset_codes(np.zeros((4, 3)), NO_MAG_ERRORS, 0.01, rng)
    assert (c_set == 2048).all() and (c_reset == 2048).all()
    assert (flip_code(c_set, c_reset) == (2048 + 4095 - 2048) // 2).all()


@pytest.mark.parametrize("g", [-3.0, -1.0, 0.25, 1.0, 2.5])
def test_accelerometer_sensitivity(g: float) -> None:
    acc = ACC.without_errors()
    f = np.eye(3) * g * G0
    codes = tlc2543_codes(acc.volts(f, SensorErrors.none(), 0.01, np.random.default_rng(1)), acc.supply_v)
    want = _round(4096 * (0.5 + 0.300 / 3.0 * g))  # the preset's 300 mV/g at Vs = 3 V
    assert codes[np.eye(3, dtype=bool)].tolist() == [want] * 3
    assert (codes[~np.eye(3, dtype=bool)] == 2048).all()


def test_accelerometer_saturates_at_range_and_rails() -> None:
    acc = ACC.without_errors()
    v = acc.volts(np.array([[10 * G0, -10 * G0, 0.0]]), SensorErrors.none(), 0.01, np.random.default_rng(2))
    assert v[0, 0] == pytest.approx(acc.supply_v * (0.5 + 0.1 * 3.6))  # clipped at +3.6 g
    assert v[0, 1] == pytest.approx(acc.supply_v * (0.5 - 0.1 * 3.6))


@pytest.mark.parametrize("field_ut", [-150.0, -50.0, 20.0, 49.0])
def test_magnetometer_sensitivity_set_and_reset(field_ut: float) -> None:
    mag = MAG.without_errors()
    h = np.eye(3) * field_ut
    c_set, c_reset = mag.set_reset_codes(h, NO_MAG_ERRORS, 0.01, np.random.default_rng(3))
    x = 200 * 1.0e-3 * field_ut / 100 * 4096  # G · S · gauss · 4096: the supply cancels
    assert np.diag(c_set).tolist() == [_round(2048 + x)] * 3
    assert np.diag(c_reset).tolist() == [_round(2048 - x)] * 3


def _random_errors(rng: np.random.Generator) -> SensorErrors:
    return SensorErrors(rng.normal(0, 0.01, 3), rng.normal(0, 0.03, 3), np.eye(3) + rng.normal(0, 0.01, (3, 3))
                        * ~np.eye(3, dtype=bool))


@pytest.mark.parametrize("supply", [2.0, 3.0, 3.6])
def test_codes_are_ratiometric(supply: float) -> None:
    """With every error except the absolute ones (noise, amplifier offset), the codes
    do not depend on the rail: v/REF+ is the same number."""
    rng = np.random.default_rng(4)
    f = rng.uniform(-2.5 * G0, 2.5 * G0, (300, 3))
    e = _random_errors(rng)
    acc = ACC.without_errors()
    ref = tlc2543_codes(acc.volts(f, e, 0.01, rng), acc.supply_v)
    got = tlc2543_codes(acc.at_supply(supply).volts(f, e, 0.01, rng), supply)
    assert np.array_equal(got, ref)
    h = rng.uniform(-100, 100, (300, 3))
    me = AmrErrors(SensorErrors(rng.normal(0, 0.5e-3, 3), e.scale, e.misalignment), np.zeros(3))
    mag = MAG.without_errors()
    for flip in (1, -1):
        ref = tlc2543_codes(mag.volts(h, me, flip, 0.01, rng), mag.supply_v)
        got = tlc2543_codes(mag.at_supply(supply).volts(h, me, flip, 0.01, rng), supply)
        assert np.array_equal(got, ref)


def test_set_reset_cancels_bridge_and_amplifier_offsets() -> None:
    rng = np.random.default_rng(5)
    mag = MAG.without_errors()
    h = rng.uniform(-60, 60, (500, 3))
    offsets = AmrErrors(SensorErrors(np.array([1.2e-3, -1.0e-3, 0.6e-3]), np.zeros(3), np.eye(3)),
                        np.array([150e-6, -200e-6, 90e-6]))
    c_set, c_reset = mag.set_reset_codes(h, offsets, 0.01, rng, backend="ideal")
    x = 200 * 1.0e-3 * h / 100 * 4096
    o = 200 * (3.3 * offsets.bridge.bias + offsets.amp_offset_v) / 3.3 * 4096  # the offsets in codes
    assert np.abs(o).min() > 100  # they are large: hundreds of codes ...
    assert np.abs(c_set - (2048 + o + x)).max() <= 0.5  # ... and in each conversion
    # c_set - c_reset = 2x ± 1 (two roundings), the floor of half of it + 4095: [2047.5 + x − 1, 2047.5 + x + 0.5]
    d = flip_code(c_set, c_reset) - (2047.5 + x)
    assert d.min() >= -1.0 and d.max() <= 0.5


def test_noise_in_codes() -> None:
    """The output noise through the RC filter, quantized: σ² = (N·S·√(π/2·f_c)/Vs·4096)² + 1/12
    (Sheppard; the preset's σ ≈ 0.5 LSB dithers the ADC). 20 000 nearly independent samples
    (AR(1) coefficient e^{−2π·50·0.01} = 0.04): the standard deviation is known to
    1/√(2n) = 0.5 %; 4 % covers that 8 times and Sheppard's approximation at σ ≈ 0.5 LSB."""
    rng = np.random.default_rng(6)
    codes = tlc2543_codes(ACC.volts(np.zeros((20000, 3)), SensorErrors.none(), 0.01, rng), ACC.supply_v)
    sigma = 150e-6 * 0.300 * math.sqrt(math.pi / 2 / (2 * math.pi * 32e3 * 0.1e-6)) / 3.3 * 4096
    assert ACC.noise_sigma_codes == pytest.approx(sigma)
    assert codes.std(axis=0) == pytest.approx([math.sqrt(sigma**2 + 1 / 12)] * 3, rel=0.04)


def test_nominal_scales() -> None:
    assert ACC.codes_per_g == pytest.approx(409.6)
    assert ACC.units_per_code == pytest.approx(G0 / 409.6)
    assert ACC.bandwidth_hz == pytest.approx(1 / (2 * math.pi * 32e3 * 0.1e-6))
    assert ACC.tau == pytest.approx(32e3 * 0.1e-6) and MAG.tau == pytest.approx(1 / (2 * math.pi * 50))
    assert MAG.units_per_code == pytest.approx(100 / (200 * 1.0e-3 * 4096))


def test_presets_name_every_source() -> None:
    for part in (*ACCEL_FRONTENDS.values(), *MAG_FRONTENDS.values()):
        tags = {s.split(":")[0] for s in part.sources.values()}
        assert tags <= {"datasheet", "datasheet†", "assumption"}, part.name
    assert "ratiometric" in ACC.sources and "set_reset" in MAG.sources


def test_bad_arguments() -> None:
    with pytest.raises(InvalidArgument, match="supply_v"):
        replace(ACC, supply_v=float("nan"))
    with pytest.raises(InvalidArgument, match="flip"):
        MAG.volts(np.zeros((1, 3)), NO_MAG_ERRORS, 0, 0.01, np.random.default_rng())  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="12-bit"):
        flip_code(np.array([4096]), np.array([0]))
