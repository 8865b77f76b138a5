"""The accelerometer and magnetometer models (attitude_c.sim.accelmag) and their
place in the chain (issue 14): the measurement equation term by term, the
noise statistics of each model, the first-order Markov bias of the thesis's
eq. 3.54, saturation, the disturbance window, the presets.

Statistical tolerances are a number of standard deviations of the estimator
itself (stated at each test), with seeds fixed so the tests are repeatable.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from attitude_c.errors import InvalidArgument
from attitude_c.sim import SimConfig, simulate
from attitude_c.sim.accelmag import (
    ACCEL_PRESETS,
    G0,
    MAG_PRESETS,
    MagDisturbance,
    SensorErrors,
    VectorSensor,
    VectorSensorModel,
    accel_preset,
    mag_preset,
    markov,
    white_noise,
)
from attitude_c.sim.adc import AdcModel
from attitude_c.sim.conditioning import Conditioning
from attitude_c.sim.sensors import gyro_preset
from attitude_c.sim.trajectory import EARTH, PaperTrajectory, StaticTrajectory, TurntableTrajectory


def _quiet(kind: str = "accel", **kw) -> VectorSensorModel:
    base = {"range": 1e3, "noise_density": 0.0, "bandwidth_hz": None, "bias_sigma": 0.0, "scale_sigma": 0.0,
                "misalignment_sigma": 0.0}
    base.update(kw)
    return VectorSensorModel("test", kind, **base)


def test_white_noise_has_the_density_through_the_filter() -> None:
    """σ² = N²·π/2·f_c through a first-order filter (the equivalent noise bandwidth
    of a one-pole low-pass), lag-1 correlation e^{−dt/τ}. 3 × 20 000 samples at
    a = 0.53: the std's estimate has a relative σ ≈ √((1+a²)/(1−a²)/(2n)) = 0.4 %
    → 2 % is 5σ; r₁'s σ ≈ √((1−a²)/n) = 0.0035 → 0.02."""
    rng = np.random.default_rng(11)
    n, dt, nd, fc = 20000, 1e-3, 0.3, 100.0
    x = white_noise(n, dt, nd, fc, rng)
    sigma = nd * math.sqrt(math.pi / 2 * fc)
    assert abs(x.std() / sigma - 1) < 0.02
    a = math.exp(-dt * 2 * math.pi * fc)
    r1 = np.mean([np.corrcoef(x[:-1, j], x[1:, j])[0, 1] for j in range(3)])
    assert abs(r1 - a) < 0.02
    # no filter: the mean of white noise over dt, σ = N/√dt, uncorrelated
    y = white_noise(n, dt, nd, None, rng)
    assert abs(y.std() / (nd / math.sqrt(dt)) - 1) < 0.02  # white: relative σ 0.3 %
    assert abs(np.corrcoef(y[:-1, 0], y[1:, 0])[0, 1]) < 0.03  # σ 1/√n = 0.007


def test_markov_bias_is_the_thesis_first_order_process() -> None:
    """Eq. 3.54, x(k+1) = e^{−βT} x(k) + w(k): regressing x(k+1) on x(k) gives
    e^{−T/τ} (slope σ ≈ √((1−a²)/N) = 2.6e-4 for N = 3 × 100 000, bound 2e-3);
    the innovation w is white with variance σ²(1 − a²) (relative σ of its std
    √(1/(2N)) = 0.13 %, bound 1 %); the stationary σ (N_eff ≈ N(1−a)/(1+a) =
    1500: relative σ 1.8 %, bound 10 %)."""
    rng = np.random.default_rng(5)
    sigma, tau, dt, n = 2e-3, 1.0, 0.01, 100000
    x = markov(n, dt, sigma, tau, rng)
    a = math.exp(-dt / tau)
    slope = np.sum(x[1:] * x[:-1]) / np.sum(x[:-1] ** 2)
    assert abs(slope - a) < 2e-3
    w = x[1:] - a * x[:-1]
    assert abs(w.std() / (sigma * math.sqrt(1 - a * a)) - 1) < 0.01
    assert abs(np.corrcoef(w[:-1, 0], w[1:, 0])[0, 1]) < 0.015  # σ 1/√N = 0.003
    assert abs(x.std() / sigma - 1) < 0.10
    np.testing.assert_array_equal(markov(10, dt, 0.0, tau, rng), np.zeros((10, 3)))


def test_measurement_equation_term_by_term() -> None:
    """Noise-free parts: y = K f + b (accelerometer), y = K (S (m + d) + h) + b
    (magnetometer), K = diag(1 + s) M, exactly (to rounding)."""
    tr = StaticTrajectory(euler0=(0.4, -0.3, 0.2))
    t = np.linspace(0, 1, 5)
    m_err = np.array([[1.0, 0.01, -0.02], [0.015, 1.0, 0.005], [-0.01, 0.02, 1.0]])
    err = SensorErrors(np.array([0.1, -0.2, 0.05]), np.array([0.01, -0.02, 0.005]), m_err)
    k = np.diag([1.01, 0.98, 1.005]) @ m_err
    acc = VectorSensor(_quiet("accel"), err)
    y = acc.measure(tr, t, 0.25, np.random.default_rng(0))
    f = tr.specific_force(t)
    np.testing.assert_allclose(y, f @ k.T + err.bias, atol=1e-13)
    soft = np.array([[1.1, 0.05, 0.0], [0.05, 0.9, 0.02], [0.0, 0.02, 1.0]])
    hard = np.array([20.0, -15.0, 5.0])
    mag = VectorSensor(_quiet("mag"), err, EARTH, hard, soft)
    y = mag.measure(tr, t, 0.25, np.random.default_rng(0))
    np.testing.assert_allclose(y, (tr.mag_field(t) @ soft.T + hard) @ k.T + err.bias, atol=1e-12)
    with pytest.raises(InvalidArgument, match="magnetometer"):
        VectorSensor(_quiet("accel"), err, EARTH, hard)


def test_saturation_and_quantization() -> None:
    """A ±2 g part on a 20 m, 0.5 Hz translation (peak 20·π² ≈ 197 m/s²) clips at
    the range and says so; a digital part's readings are whole LSBs."""
    tr = PaperTrajectory(translation=(20.0, 0.0, 0.0), translation_frequency=(0.5, 0.1, 0.1))
    part = accel_preset("adxl202").perfect()
    s = VectorSensor(part)
    t = np.linspace(0, 4, 401)
    y = s.measure(tr, t, 0.01, np.random.default_rng(1))
    assert np.abs(y).max() == pytest.approx(2 * G0, rel=1e-15)
    sat = s.saturated(y)
    want = np.any(np.abs(tr.specific_force(t)) >= 2 * G0, axis=1)
    np.testing.assert_array_equal(sat, want)
    assert 0 < sat.sum() < len(t)
    d = VectorSensor(accel_preset("adis16405"))
    y = d.measure(StaticTrajectory(), np.arange(100) * 0.01, 0.01, np.random.default_rng(2))
    lsb = accel_preset("adis16405").lsb
    np.testing.assert_allclose(y / lsb, np.round(y / lsb), atol=1e-9)


def test_disturbance_window() -> None:
    """A field added for a window: zero outside, full inside, raised-cosine edges
    (half strength half-way up the ramp); in the nav frame it turns with the body."""
    d = MagDisturbance(2.0, 6.0, (30.0, -10.0, 0.0), "body", ramp=1.0)
    np.testing.assert_allclose(d.weight([0.0, 1.99, 2.5, 3.0, 4.0, 5.5, 6.0, 7.0]),
                               [0, 0, 0.5, 1, 1, 0.5, 0, 0], atol=1e-15)
    tr = StaticTrajectory(euler0=(0.3, 0.1, -0.2))
    mag = VectorSensor(_quiet("mag"), disturbances=(d,))
    t = np.array([1.0, 4.0, 8.0])
    y = mag.measure(tr, t, 0.1, np.random.default_rng(0)) - tr.mag_field(t)
    np.testing.assert_allclose(y, [[0, 0, 0], [30, -10, 0], [0, 0, 0]], atol=1e-12)
    nav = MagDisturbance(0.0, 100.0, (0.0, 40.0, 0.0), "nav")  # a magnet north of a turntable
    tt = TurntableTrajectory()
    m2 = VectorSensor(_quiet("mag"), disturbances=(nav,))
    t = np.array([10.0, 30.0])
    y = m2.measure(tt, t, 0.1, np.random.default_rng(0)) - tt.mag_field(t)
    for k, tk in enumerate(t):
        psi = math.radians(5.0) * tk  # level, yaw ψ: body x = [cos ψ, sin ψ, 0] in ENU
        np.testing.assert_allclose(y[k], [40 * math.sin(psi), 40 * math.cos(psi), 0.0], atol=1e-12)
    for bad in ({"start": 1.0, "end": 1.0, "field": (1.0, 0.0, 0.0)}, {"start": 0.0, "end": 1.0, "field": (1.0, 0.0, 0.0),
                "ramp": 0.6}, {"start": 0.0, "end": 1.0, "field": (1.0, 0.0, 0.0), "frame": "world"}):
        with pytest.raises(InvalidArgument):
            MagDisturbance(**bad)


def test_presets_load_with_a_source_for_every_figure() -> None:
    for presets, kind in ((ACCEL_PRESETS, "accel"), (MAG_PRESETS, "mag")):
        for name, p in presets.items():
            assert p.kind == kind and p.name == name
            json.dumps(p.to_dict())
            assert p.sources, name
            text = " ".join(p.sources.values())
            assert all(any(tag in v for tag in ("datasheet", "thesis", "paper", "assumption", "perfect"))
                       for v in p.sources.values()), name
            if name != "ideal":
                assert "range" in p.sources and "noise_density" in p.sources, name
                assert text
    with pytest.raises(InvalidArgument, match="accel must be one of"):
        accel_preset("mpu6050")
    with pytest.raises(InvalidArgument, match="mag must be one of"):
        mag_preset("hmc5883")
    # the ADXL202's datasheet density through the thesis's 100 Hz filter gives the
    # thesis's Table 4.2 noise (6.1 mg rms at 100 Hz): 0.5 mg·√(π/2·100) = 6.27 mg
    adxl = accel_preset("adxl202")
    assert adxl.noise_sigma_filtered / (G0 * 1e-3) == pytest.approx(6.1, rel=0.05)


def _static_run(**kw) -> dict:
    cfg = SimConfig(trajectory=StaticTrajectory(euler0=(0.5, 0.2, -0.3)), duration=40.0, calibration_s=10.0,
                    link="none", adc=AdcModel(backend="ideal"), **kw)
    return simulate(cfg)


def test_chain_digital_part_errors_are_the_drawn_ones() -> None:
    """Static, ADIS16405 accelerometer and magnetometer: the mean reading error
    over 500 periods is (K − I)·truth + b as drawn for the run, within
    4σ of the rest: Markov σ (accelerometer 0.2 mg), white noise σ/√(N_eff)
    (0.5 mg/√Hz over 40 s: 0.08 mg), half an LSB (1.7 mg, deterministic)."""
    res = _static_run(accel=accel_preset("adis16405"), mag=mag_preset("adis16405"), seed=4)
    for name, part in (("accel", accel_preset("adis16405")), ("mag", mag_preset("adis16405"))):
        s = res.aux[name]
        e = s.summary()["errors"]
        k = (1 + np.array(e["scale"]))[:, None] * np.array(e["misalignment"])
        want = s.truth @ (k - np.eye(3)).T + np.array(e["bias"])
        got = s.values - s.truth
        tol = 4 * (part.markov_sigma + part.noise_density / math.sqrt(40.0)) + part.lsb / 2
        np.testing.assert_allclose(got.mean(axis=0), want.mean(axis=0), atol=tol)
        assert not s.saturated.any()
    assert len(res.aux["accel"].values) == 500
    assert "sensors" in res.summary and res.summary["sensors"]["mag"]["part"] == "adis16405"


@pytest.mark.parametrize("backend", ["tlc2543", "ad7927"])
def test_chain_analog_part_through_the_adc_is_exact_to_half_a_code(backend: str) -> None:
    """sensors="quantized": a perfect ADXL202 through conditioning, the ADC (C driver
    against its device model) and the board's sums of 16 codes: the host's mean
    reading is the period's mean specific force within half a code of the mean
    (round or floor transfer, the nominal zero at the bin centre) plus the
    midpoint rule's error over 16 sub-intervals (< 1e-6 m/s² here)."""
    follower = backend == "ad7927"
    cfg = SimConfig(trajectory=PaperTrajectory(translation=(2.0, 1.0, 0.5)), duration=8.0, calibration_s=2.0,
                    sensors="quantized", link="none", adc=AdcModel(backend=backend),
                    conditioning=Conditioning(follower=follower),
                    gyro=gyro_preset("adxrs150") if follower else gyro_preset("cg-l53"),
                    accel=accel_preset("adxl202"))
    res = simulate(cfg)
    s = res.aux["accel"]
    upc = s.calibration.units_per_code
    assert np.abs(s.values - s.truth).max() <= 0.5 * upc + 1e-6
    assert res.summary["backends"]["adc"] == backend


def test_chain_ideal_sensors_hand_over_the_truth_and_the_default_has_none() -> None:
    soft = np.diag([1.1, 0.9, 1.0])
    res = simulate(SimConfig(duration=4.0, sensors="ideal", accel=accel_preset("adis16488"),
                             mag=mag_preset("hmr3000"), hard_iron=(5.0, 0.0, -3.0), soft_iron=soft))
    a, m = res.aux["accel"], res.aux["mag"]
    np.testing.assert_array_equal(a.values, a.truth)
    np.testing.assert_allclose(m.values, m.truth @ soft.T + [5.0, 0.0, -3.0], atol=1e-12)
    plain = simulate(SimConfig(duration=4.0, sensors="ideal"))
    assert plain.aux == {} and "sensors" not in plain.summary and "accel" not in plain.summary["parameters"]
    with pytest.raises(InvalidArgument, match="need a magnetometer"):
        SimConfig(hard_iron=(1.0, 0.0, 0.0)).validate()
    with pytest.raises(InvalidArgument, match="invertible"):
        SimConfig(mag=mag_preset("ideal"), soft_iron=np.zeros((3, 3))).validate()
    with pytest.raises(InvalidArgument, match="accelerometer model"):
        SimConfig(accel=mag_preset("ideal")).validate()


# each switch of ``without`` and the one field it turns off (None: no filter); the
# field names are the models' documented attributes
_VECTOR_SWITCHES = {"noise": ("noise_density", 0.0), "bias": ("bias_sigma", 0.0),
                    "bandwidth": ("bandwidth_hz", None), "scale": ("scale_sigma", 0.0),
                    "misalignment": ("misalignment_sigma", 0.0), "markov": ("markov_sigma", 0.0)}
_GYRO_SWITCHES = {"noise": ("noise_density", 0.0), "bias": ("bias_dps", 0.0),
                  "bandwidth": ("bandwidth_hz", None), "scale": ("scale_error", 0.0)}


@pytest.mark.parametrize("kind", ["accel", "mag", "gyro"])
def test_without_switches_off_exactly_the_named_sources(kind: str) -> None:
    """``without(x=True)`` turns off the one field of x and leaves every other
    field as it was; ``perfect()`` (vector parts) turns them all off."""
    part, switches = {"accel": (accel_preset("adis16405"), _VECTOR_SWITCHES),
                      "mag": (replace(mag_preset("adis16405"), markov_sigma=0.1), _VECTOR_SWITCHES),
                      "gyro": (replace(gyro_preset("adxrs150"), scale_error=0.01), _GYRO_SWITCHES)}[kind]
    before = vars(part)
    assert all(before[f] not in (0.0, None) for f, _ in switches.values())  # every switch has work to do
    assert part.without() == part
    for flag, (name, off) in switches.items():
        assert vars(part.without(**{flag: True})) == {**before, name: off}, flag
    assert vars(part.without(**dict.fromkeys(switches, True))) == {**before, **dict(switches.values())}
    if kind != "gyro":
        assert part.perfect() == part.without(**dict.fromkeys(switches, True))


@pytest.mark.parametrize("part", [*ACCEL_PRESETS.values(), *MAG_PRESETS.values()],
                         ids=lambda p: f"{p.kind}-{p.name}")
def test_each_preset_noise_has_its_stated_level(part: VectorSensorModel) -> None:
    """At rest, every error but the noise off: the readings' spread is the
    filtered white noise, σ² = N²·π/2·f_c, plus the digital part's quantization
    lsb²/12 (Sheppard; the presets' σ is ≥ 1.8 LSB, where the uniform model
    holds). Sampled every τ (lag-1 correlation e^{−1}), 3 × 20 000 readings:
    the std's relative σ is √((1+a²)/((1−a²)·2n)) ≈ 0.33 % → 3 % bound."""
    quiet = part.without(bias=True, scale=True, misalignment=True, markov=True)
    s = VectorSensor(quiet)
    tr = StaticTrajectory(euler0=(0.3, 0.2, -0.1))
    dt = quiet.tau if quiet.tau > 0 else 1e-3
    t = np.arange(20000) * dt
    y = s.measure(tr, t, dt, np.random.default_rng(9))
    e = y - s.truth(tr, t)
    want = quiet.noise_sigma_filtered ** 2 + (quiet.lsb ** 2 / 12 if quiet.lsb else 0.0)
    if want == 0:
        np.testing.assert_allclose(e, 0.0, atol=1e-12)
        return
    assert abs(e.std() / math.sqrt(want) - 1) < 0.03
    # zero mean: bound 0.06σ, ten times the mean's own σ (σ/√60000 × √((1+a)/(1−a)) ≈ 0.006σ)
    assert abs(e.mean()) < 5 * math.sqrt(want / 20000 * 3)


def test_chain_saturation_through_the_adc() -> None:
    """A perfect ADXL202 (±2 g) on a translation reaching 3.6 g, through the
    conditioning (±2 g ↦ 90 % of the ADC's half range: the part clips before the
    ADC does) and the TLC2543: the host's readings never pass the range by more
    than half a code, the periods flagged saturated include every period whose
    exact mean is beyond the range, and none whose readings all stayed inside
    (the flag is per reading: a period whose mean is inside may hold a clipped reading)."""
    # 90 m at 0.1 Hz: peak 90·(0.2π)² = 35.5 m/s² = 3.6 g, changing by ≤ 1.8 m/s² within a period
    tr = PaperTrajectory(translation=(90.0, 0.0, 0.0), translation_frequency=(0.1, 0.1, 0.1))
    res = simulate(SimConfig(trajectory=tr, duration=6.0, calibration_s=1.0, sensors="quantized", link="none",
                             accel=accel_preset("adxl202")))
    s = res.aux["accel"]
    upc = s.calibration.units_per_code
    assert np.abs(s.values).max() <= 2 * G0 + 0.5 * upc
    beyond = np.any(np.abs(s.truth) > 2 * G0, axis=1)
    assert beyond.any() and np.all(s.saturated[beyond])
    assert not s.saturated[np.all(np.abs(s.truth) < 2 * G0 * 0.9, axis=1)].any()
    assert res.summary["sensors"]["accel"]["saturated_samples"] == int(s.saturated.sum())
