"""The sensor correction out = M (value − b) (att_sensor_set_correction,
docs/sensor.md) through attitude_c.sensor, against the NumPy reference
written from the formula (attitude_c.reference.sensor_values), and a
magnetometer calibration (attitude_c.magcal: m_cal = S (m − h)) as the
correction M = S, b = h.

The C closed forms and checks are csrc/tests/test_sensor.c (host under
ASan/UBSan: test_c_programs.py; ARMv4T: test_cross_bare.py)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from attitude_c import magcal
from attitude_c import reference as ref
from attitude_c.errors import InvalidArgument, InvalidType, NonFiniteError, RangeError
from attitude_c.sensor import Sensor

EPS = {"f64": 2.0**-53, "f32": 2.0**-24}


def _tolerance(precision: str, scale: np.ndarray, matrix: np.ndarray, bias: np.ndarray) -> float:
    """Roundings of value (division, subtraction, two products: ≤ 8 units of
    |value| ≤ 4096 codes × |scale|), of value − b, and of the three products and
    two sums of a row of M: ≤ 16 roundings of terms ≤ max row sum of |M| ×
    (|value| + |b|)."""
    big = 4096 * np.abs(scale).max() + np.abs(bias).max()
    return 16 * EPS[precision] * big * np.abs(matrix).sum(axis=1).max()


@settings(max_examples=100, deadline=None)
@given(st.integers(1, 16), st.permutations([0, 1, 2]), st.lists(st.sampled_from([-1, 1]), min_size=3, max_size=3),
       st.integers(0, 2**32 - 1), st.sampled_from(["f64", "f32"]))
def test_c_agrees_with_the_reference(n: int, axes: list[int], signs: list[int], seed: int, precision: str) -> None:
    rng = np.random.default_rng(seed)
    words = rng.integers(0, min(n * 4095, 0xFFFF) + 1, size=(40, 3))
    zero = rng.uniform(0, 4095, size=3)
    scale = rng.uniform(1e-3, 1e-1, size=3) * rng.choice([-1.0, 1.0], size=3)
    matrix = np.eye(3) + rng.uniform(-0.2, 0.2, size=(3, 3))  # misalignment + scale factor: |det| ≈ 1
    bias = rng.uniform(-50, 50, size=3)
    s = Sensor(zero, scale, axes, signs, precision, matrix=matrix, bias=bias)
    want = ref.sensor_values(words, zero, scale, n, axes, signs, matrix, bias)
    tol = _tolerance(precision, scale, matrix, bias)
    np.testing.assert_allclose(s.convert(words, n), want, rtol=0, atol=tol)
    np.testing.assert_allclose(s.increments(words, n, 0.01), want * 0.01, rtol=0, atol=tol * 0.01 * 1.5)


def test_identity_is_the_uncorrected_sensor_bit_for_bit() -> None:
    rng = np.random.default_rng(3)
    words = rng.integers(0, 16 * 4095 + 1, size=(500, 3))
    words[:5] = 16 * 2047  # value exactly 0 (and −0 with a negative scale)
    for precision in ("f64", "f32"):
        plain = Sensor(2047, [7e-4, -7e-4, 8e-4], (2, 0, 1), (1, -1, 1), precision)
        ident = Sensor(2047, [7e-4, -7e-4, 8e-4], (2, 0, 1), (1, -1, 1), precision, matrix=np.eye(3), bias=[0, 0, 0])
        a, b = plain.convert(words, 16), ident.convert(words, 16)
        assert a.tobytes() == b.tobytes()  # bit for bit, signs of zero included
    np.testing.assert_array_equal(plain.matrix, np.eye(3))
    np.testing.assert_array_equal(plain.bias, np.zeros(3))


def _field_words(rng: np.random.Generator, k: int) -> tuple[np.ndarray, Sensor]:
    """Words of a magnetometer with hard and soft iron turned through all directions,
    and the uncorrected sensor (µT per code) they are read with."""
    u = rng.normal(size=(k, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    soft = np.array([[1.15, 0.06, 0.0], [0.06, 0.9, -0.03], [0.0, -0.03, 1.02]])
    field = 48.0 * u @ soft.T + np.array([9.0, -14.0, 5.0])  # µT: |field| ≤ ~75
    plain = Sensor([2048, 2050, 2046], [0.05, 0.05, 0.05])
    words = np.rint(field / 0.05 + plain.zero).astype(np.int64)
    return words, plain


@pytest.mark.parametrize("precision", ["f64", "f32"])
def test_magcal_result_is_the_correction(precision: str) -> None:
    """M = S, b = h: the corrected words are att_magcal_apply of the uncorrected
    values, exactly (the same operations in the same order, docs/sensor.md)."""
    words, plain = _field_words(np.random.default_rng(7), 400)
    plain = Sensor(plain.zero, plain.scale, precision=precision)
    values = plain.convert(words)
    cal = magcal.fit(values, "full")
    corrected = plain.with_magcal(cal)
    np.testing.assert_array_equal(corrected.matrix, cal.S)
    np.testing.assert_array_equal(corrected.bias, cal.h)
    got = corrected.convert(words)
    assert got.tobytes() == magcal.apply(cal, values, precision).astype(got.dtype).tobytes()
    # and what the calibration is for: the corrected field has one norm (to the words' rounding,
    # 0.025 µT of 48 µT, times the soft iron's gain, plus the fit's own error)
    norms = np.linalg.norm(got.astype(np.float64), axis=1)
    assert np.abs(norms / cal.field - 1).max() < 2e-3


def test_errors_name_the_argument() -> None:
    with pytest.raises(InvalidArgument, match=r"matrix must be invertible, \|det\| >= 0.001, got det 0"):
        Sensor(2048, 1e-3, matrix=[[1, 0, 0], [1, 0, 0], [0, 0, 1]])
    with pytest.raises(InvalidArgument, match=r"got det 0.00097656"):
        Sensor(2048, 1e-3, matrix=np.diag([0.125, 0.125, 0.0625]))
    assert Sensor(2048, 1e-3, matrix=np.diag([0.125, 0.125, 0.125])).matrix[2, 2] == 0.125
    with pytest.raises(InvalidArgument, match=r"matrix must have shape \(3, 3\)"):
        Sensor(2048, 1e-3, matrix=np.eye(2))
    with pytest.raises(NonFiniteError, match="matrix holds NaN"):
        Sensor(2048, 1e-3, matrix=np.full((3, 3), np.nan))
    with pytest.raises(NonFiniteError, match="bias holds NaN"):
        Sensor(2048, 1e-3, bias=[0, np.inf, 0])
    with pytest.raises(InvalidArgument, match="bias must be"):
        Sensor(2048, 1e-3, bias=[0, 1])
    with pytest.raises(InvalidType, match="cal must be an attitude_c.magcal.Calibration"):
        Sensor(2048, 1e-3).with_magcal("full")  # type: ignore[arg-type]
    s = Sensor(2048, 1.0, matrix=np.diag([1e306, 1, 1]))
    with pytest.raises(RangeError, match="sample 0"):  # a corrected value beyond the float range
        s.convert([[4095, 2048, 2048]])
    assert Sensor(2048, 1e-3, matrix=np.eye(3).reshape(9)).matrix.shape == (3, 3)  # row-major 9 values
