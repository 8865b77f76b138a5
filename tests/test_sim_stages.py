"""Each stage of the simulator on its own (docs/architecture.md): what it takes,
what it gives, and that it does what its docstring says. The whole chain is
tested in test_sim_chain.py / test_sim_link.py; the truth in test_sim_truth.py."""

from __future__ import annotations

import math

import numpy as np
import pytest

from attitude_c import reference as ref
from attitude_c.core import integrate
from attitude_c.errors import InvalidArgument
from attitude_c.link import block
from attitude_c.sensor import Sensor
from attitude_c.sim import (
    AdcModel,
    Board,
    Calibration,
    Conditioning,
    ConstantRateTrajectory,
    Delivered,
    Estimate,
    Gyro,
    HostDecoder,
    Integrate,
    Link,
    PaperTrajectory,
    compare,
    gyro_preset,
    wrap_angle,
)
from attitude_c.sim import attitude_angle as lib_angle

DEG = math.pi / 180


def test_gyro_stage_volts() -> None:
    """Still ideal gyros read their null; a constant rate reads null + scale · rate;
    the range clips; noise has the density the model says (white, no filter: σ = N/√dt)."""
    model = gyro_preset("ideal")
    g = Gyro(model, np.zeros(3))
    tr = ConstantRateTrajectory(rate=[0.5, -1.0, 6.0])  # 6 rad/s = 344 °/s: beyond ±300 °/s
    t = np.linspace(0, 1, 11)
    rng = np.random.default_rng(0)
    np.testing.assert_array_equal(g.volts(tr, t, 0.1, rng, static=True), np.full((11, 3), model.null_v))
    v = g.volts(tr, t, 0.1, rng)
    want = model.null_v + model.scale_v_per_dps * np.array([0.5 / DEG, -1.0 / DEG, model.range_dps])
    np.testing.assert_allclose(v, np.tile(want, (11, 1)), rtol=1e-12)
    noisy = Gyro(model.__class__(**{**model.to_dict(), "noise_density": 0.1}), np.zeros(3))
    dv = noisy.volts(tr, np.arange(20000) * 1e-3, 1e-3, rng, static=True) - model.null_v
    sigma = 0.1 / math.sqrt(1e-3) * model.scale_v_per_dps  # °/s per √Hz over 1 kHz, in volts
    assert abs(dv.std() / sigma - 1) < 0.02  # 60 000 draws: the std's own spread is 0.3 %


def test_conditioning_maps_the_range_to_the_span() -> None:
    c = Conditioning(vref=5.0, span=0.9)
    gyro = gyro_preset("cg-l53")
    top = gyro.null_v + gyro.scale_v_per_dps * gyro.range_dps
    out = c.apply(np.array([[gyro.null_v, top, 2 * gyro.null_v - top]]), gyro)
    np.testing.assert_allclose(out, [[2.5, 2.5 + 0.9 * 2.5, 2.5 - 0.9 * 2.5]], rtol=1e-12)


def test_adc_backends_agree() -> None:
    """The C TLC2543 driver against its device model quantizes as the ideal quantizer."""
    v = np.random.default_rng(3).uniform(0.01, 4.99, size=(200, 3))
    a = AdcModel(backend="tlc2543").convert(v)
    b = AdcModel(backend="ideal").convert(v)
    assert a.dtype == b.dtype == np.int64
    assert np.max(np.abs(a - b)) <= 1  # at a code's edge the model may round the other way
    np.testing.assert_array_equal(AdcModel(backend="ideal").convert(np.array([[-1.0, 2.5, 9.0]])),
                                  [[0, 2048, 4095]])
    with pytest.raises(InvalidArgument, match="12-bit"):
        AdcModel(bits=10).convert(v)


def test_board_instants_sums_and_records() -> None:
    b = Board(oversample=4, delay_comp=True, sample_at="mid")
    np.testing.assert_allclose(b.instants(1.0, 2, 0.08, 0.001), 1.0 + (np.arange(8) + 0.5) * 0.02 + 0.001)
    np.testing.assert_allclose(Board(4, False, "start").instants(0.0, 1, 0.08, 0.5), np.arange(4) * 0.02)
    codes = np.arange(24).reshape(8, 3)
    words = b.sums(codes)
    np.testing.assert_array_equal(words, [codes[:4].sum(0), codes[4:].sum(0)])
    s = b.stream(words, 0.08)
    assert s.header == 2 and list(s.sample) == [-1, -1, 0, 1]
    recs = block.number_stream(s.records)
    assert [r.kind for r, _ in recs] == ["boot", "oversample", "sample", "sample"]
    assert recs[0][0].period_ticks == 288 and recs[1][0].oversample == 4
    assert [r.codes for r, _ in recs[2:]] == [tuple(w) for w in words.tolist()]
    # 16 conversions: a sum above 0xFDFF cannot be carried; an ADC_ERROR takes its place
    s16 = Board(16).stream(np.array([[32768, 32768, 32768], [65023, 65024, 0]]), 0.08)
    recs = block.number_stream(s16.records)
    assert [r.kind for r, _ in recs[2:]] == ["sample", "adc_error"] and recs[3][1].first == 1
    with pytest.raises(InvalidArgument, match="oversample must be 1..16"):
        Board(oversample=17).check(12)
    with pytest.raises(InvalidArgument, match="12-bit"):
        Board().check(14)


def _stream(n: int = 30) -> tuple[Board, object, np.ndarray]:
    b = Board(oversample=16)
    words = np.random.default_rng(4).integers(16 * 1800, 16 * 2300, size=(n, 3))
    return b, b.stream(words, 0.08), words


def test_link_stage_delivers_the_records_and_says_where_each_came_from() -> None:
    _, s, _ = _stream()
    d = Link("c").carry(s, np.random.default_rng(1), 0.08)
    assert d.records == s.records and list(d.source) == list(range(len(s.records)))
    assert d.stats["sent"] == d.stats["delivered"] == d.stats["delivered_ok"] == 30
    d0 = Link("none").carry(s, np.random.default_rng(1), 0.08)
    assert d0.records == s.records and d0.stats["link"] == "none"
    # a noisy line: the header still arrives (clean, before the first sample), every sample
    # record delivered comes from the record its source index names (or is a corrupted copy)
    noisy = Link("c", ber=5e-3, attempts=2).carry(s, np.random.default_rng(2), 0.08)
    assert noisy.records[:2] == s.records[:2]
    same = [r == s.records[i] for r, i in zip(noisy.records, noisy.source)]
    assert len(same) - sum(same) == noisy.stats["corrupted_undetected"]


def test_host_decodes_with_the_library_and_holds_reported_losses() -> None:
    _, s, words = _stream()
    cal = Calibration(np.array([2048.0, 2047.5, 2049.25]), 7.5e-4, 16)
    dec = HostDecoder(cal, 0.08).decode(Delivered(s.records, np.arange(len(s.records))), s.sample)
    np.testing.assert_array_equal(dec.sample_index, np.arange(30))
    np.testing.assert_array_equal(dec.words, words)
    np.testing.assert_array_equal(dec.increments, Sensor(cal.zero, 7.5e-4).increments(words, 16, 0.08))
    # the reference, from the formula: (word / 16 − zero) · scale · h
    np.testing.assert_allclose(dec.increments, ref.sensor_values(words, cal.zero, 7.5e-4, 16) * 0.08,
                               rtol=0, atol=1e-15)
    assert dec.reports == ["boot", "oversample"] and dec.held == []
    # a reported loss (samples 5, 6) is held; a duplicate keeps its true number
    recs = list(s.records[:7]) + [block.encode_loss("overrun", 5, 2)] + list(s.records[9:])
    dec = HostDecoder(cal, 0.08).decode(Delivered(recs, None))
    assert dec.held == [5, 6] and list(dec.sample_index) == list(range(30))
    np.testing.assert_array_equal(dec.words[5], dec.words[4])
    src = np.concatenate([np.arange(12), [11], np.arange(12, 32)])
    dup = HostDecoder(cal, 0.08).decode(Delivered([s.records[i] for i in src], src), s.sample)
    assert list(dup.sample_index[9:12]) == [9, 9, 10]


def test_estimator_is_the_librarys_integrator_at_known_times() -> None:
    tr = ConstantRateTrajectory(rate=[0.1, -0.2, 0.3])
    inc = tr.increments(0.0, 0.08, 30)
    idx = np.arange(3, 33)
    from attitude_c.sim import Decoded

    dec = Decoded(inc, idx, np.zeros((30, 3), dtype=np.int64))
    est = Integrate("rv3", "f64").run(dec, tr.quat, 0.0, 0.08)
    np.testing.assert_array_equal(est.q, integrate(inc, "rv3", q0=tr.quat(3 * 0.08)))
    np.testing.assert_allclose(est.t, (np.arange(1, 11) * 3 + 3) * 0.08)
    rk = Integrate("rk4").run(dec, tr.quat, 0.0, 0.08)
    np.testing.assert_allclose(rk.t, (idx[2 * np.arange(1, len(rk.q) + 1)] + 0.5) * 0.08)
    # constant rate: q' = ½ q ⊗ ω is linear, rk4 truncates exp(Ωh/2) after the 4th power, so per
    # step the angle is off by 2 (|ω|h/2)^5/5! (h = 2 × 0.08 s), adding up over the steps
    step = 2 * (np.linalg.norm(tr.rate) * 0.16 / 2) ** 5 / 120
    assert ref.quat_angle(rk.q, tr.quat(rk.t)).max() < 1.05 * step * len(rk.q)


def test_outputs_compare_the_estimate_with_the_truth() -> None:
    tr = PaperTrajectory()
    t = np.linspace(0, 10, 50)
    exact = compare(Estimate(t, tr.quat(t)), tr)
    # the same attitude: the Euler angles of the library and of the reference agree to a few
    # roundings of angles ≤ π (1e-15), the angle through atan2 (no acos) to rounding (1e-15)
    assert np.abs(exact.err).max() < 1e-14 and exact.err_angle.max() < 1e-15
    turned = ref.quat_multiply(tr.quat(t), ref.rotvec_to_quat(np.array([0.0, 0.0, 1e-3])))
    e = compare(Estimate(t, turned), tr)
    np.testing.assert_allclose(e.err_angle, 1e-3, rtol=1e-9)
    np.testing.assert_allclose(lib_angle(tr.quat(t), turned), ref.quat_angle(tr.quat(t), turned), rtol=1e-9)
    s = e.summary()
    assert set(s) == {"heading", "yaw", "pitch", "roll", "attitude_angle"}
    np.testing.assert_array_equal(wrap_angle(np.array([math.pi, -math.pi, 3 * math.pi, 0.5])),
                                  [math.pi, math.pi, math.pi, 0.5])
