"""attitude_c.sensor (the C converter att_sensor_*, docs/sensor.md) against the
NumPy reference written from the formula (attitude_c.reference.sensor_values).

The C test program csrc/tests/test_sensor.c runs under ASan/UBSan
(test_c_programs.py) and on ARMv4T (test_cross_bare.py); the test vectors
(toolchain/vectors.py) run it on every target."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from attitude_c import reference as ref
from attitude_c.errors import InvalidArgument, InvalidType, NonFiniteError, RangeError
from attitude_c.sensor import Sensor


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 16), st.permutations([0, 1, 2]), st.lists(st.sampled_from([-1, 1]), min_size=3, max_size=3),
       st.integers(0, 2**32 - 1))
def test_c_agrees_with_the_reference(n: int, axes: list[int], signs: list[int], seed: int) -> None:
    rng = np.random.default_rng(seed)
    words = rng.integers(0, min(n * 4095, 0xFFFF) + 1, size=(50, 3))
    zero = rng.uniform(0, 4095, size=3)
    scale = rng.uniform(1e-4, 1e-2, size=3) * rng.choice([-1.0, 1.0], size=3)
    s = Sensor(zero, scale, axes, signs)
    got = s.increments(words, n, 0.08)
    want = ref.sensor_values(words, zero, scale, n, axes, signs) * 0.08
    # a few roundings (division, subtraction, two products) of terms ≤ 4096 codes × |scale| × h
    tol = 8 * 2.0**-53 * 4096 * np.abs(scale).max() * 0.08
    np.testing.assert_allclose(got, want, rtol=0, atol=tol)
    np.testing.assert_allclose(s.convert(words, n), want / 0.08, rtol=0, atol=tol / 0.08)
    # the float build: the same within its roundings
    g32 = Sensor(zero, scale, axes, signs, precision="f32").increments(words, n, 0.08)
    assert g32.dtype == np.float32
    np.testing.assert_allclose(g32, want, rtol=0, atol=8 * 2.0**-24 * 4096 * np.abs(scale).max() * 0.08
                               + 4 * 2.0**-24 * np.abs(want).max())


def test_errors_name_the_argument_and_the_sample() -> None:
    s = Sensor(2048, 1e-3)
    w = np.full((5, 3), 2048)
    w[3, 1] = 4096
    with pytest.raises(RangeError, match=r"sample 3 = \[2048, 4096, 2048\] is above 1 × 4095"):
        s.increments(w)
    assert s.increments(w, n=2).shape == (5, 3)  # a sum of two conversions may be 4096
    with pytest.raises(InvalidArgument, match="n must be 1..16"):
        s.increments(w, n=17)
    with pytest.raises(InvalidArgument, match="period > 0"):
        s.increments(w, n=2, period=0.0)
    with pytest.raises(InvalidType, match="integer ADC words"):
        s.increments(w * 1.0)
    with pytest.raises(InvalidArgument, match="shape"):
        s.increments(w[:, :2])
    with pytest.raises(InvalidArgument, match="axes"):
        Sensor(2048, 1e-3, axes=(0, 0, 1))
    with pytest.raises(InvalidArgument, match="signs"):
        Sensor(2048, 1e-3, signs=(1, 0, 1))
    with pytest.raises(InvalidArgument, match="zero must be 0..65535"):
        Sensor(-1, 1e-3)
    with pytest.raises(InvalidArgument, match="scale non-zero"):
        Sensor(2048, [1e-3, 0, 1e-3])
    with pytest.raises(NonFiniteError, match="scale"):
        Sensor(2048, np.nan)
