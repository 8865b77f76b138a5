"""Accelerometer and magnetometer calibration (attitude_c.sensorcal, issue 26) on
codes simulated by the analog front ends (attitude_c.sim.frontend) with known
zero, sensitivity and cross-axis errors, hard and soft iron: the parameters come
back within tolerances derived from the noise, and the written configuration,
converted by the library's C converter (att_sensor with its matrix and bias),
gives the true specific force and field.

Truth is written from the front ends' transfer functions (docs/sensor.md): with the
nominal zero (2048, 2047.5) and scale (1/codes-per-unit) the uncorrected value is
``v = K u + o`` (u the true quantity), so the fit must return b = o and a C with
C K a rotation; the symmetric C is ``(K⁻ᵀ K⁻¹)^½``.
"""

from __future__ import annotations

import numpy as np
import pytest

from attitude_c.errors import InvalidArgument
from attitude_c.sensorcal import SensorConfig, fit_accel, fit_mag, parse_axes, pose_means, still_segments
from attitude_c.sim.accelmag import G0, SensorErrors
from attitude_c.sim.frontend import ACCEL_FRONTENDS, MAG_FRONTENDS, AmrErrors, flip_code, tlc2543_codes

ACC = ACCEL_FRONTENDS["adxl335"]
MAG = MAG_FRONTENDS["hmc1043-ad623"]
ROWS = 200  # samples per position
# One sample's noise in m/s²: the output noise and the quantization (σ² + 1/12 codes²) times the
# nominal scale; a position's mean has σ/√ROWS (samples 10 ms apart, AR(1) coefficient 0.04: independent).
SIGMA_MEAN = np.sqrt(ACC.noise_sigma_codes**2 + 1 / 12) * ACC.units_per_code / np.sqrt(ROWS)


def _directions(rng: np.random.Generator, k: int) -> np.ndarray:
    d = rng.normal(size=(k, 3))
    return d / np.linalg.norm(d, axis=1)[:, None]


def _faces() -> np.ndarray:
    return np.vstack([np.eye(3), -np.eye(3)])


def _accel_codes(part, errors: SensorErrors, f: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """ROWS codes of each position f (P, 3) m/s² (channel frame), and their pose labels."""
    rows = np.repeat(f, ROWS, axis=0)
    return tlc2543_codes(part.volts(rows, errors, 0.01, rng), part.supply_v), np.repeat(np.arange(len(f)), ROWS)


def _nominal(prefix: str = "acc", axes: str = "x,y,z") -> SensorConfig:
    if prefix == "acc":
        return SensorConfig("acc", [2048] * 3, [ACC.units_per_code] * 3, axes)
    return SensorConfig("mag", [2047.5] * 3, [MAG.units_per_code] * 3, axes)


def _fit(codes: np.ndarray, pose: np.ndarray, nominal: SensorConfig, model: str = "auto"):
    means = pose_means(nominal.convert(codes, corrected=False), pose)[0]
    return fit_accel(means, nominal, G0, model)  # type: ignore[arg-type]


def _sym_sqrt_inv(k: np.ndarray) -> np.ndarray:
    """(K⁻ᵀ K⁻¹)^½ by eigen-decomposition: the symmetric C with C K orthogonal."""
    ki = np.linalg.inv(k)
    w, q = np.linalg.eigh(ki.T @ ki)
    return (q * np.sqrt(w)) @ q.T


def test_accelerometer_full_model_recovers_offset_scale_and_cross_axis() -> None:
    rng = np.random.default_rng(10)
    errors = ACC.draw_errors(rng)
    f = np.vstack([_faces(), _directions(rng, 24)]) * G0
    codes, pose = _accel_codes(ACC, errors, f, rng)
    fit = _fit(codes, pose, _nominal())
    assert fit.model == "full"
    o = G0 * errors.bias / ACC.ratio_per_g  # the zero-g error in m/s² (nominal scale)
    # 10 σ of a position's mean: each parameter is fixed by a few of the 30 positions (condition ≈ 14)
    assert np.abs(fit.offset - o).max() < 10 * SIGMA_MEAN
    assert np.abs(fit.correction - _sym_sqrt_inv(errors.matrix)).max() < 10 * SIGMA_MEAN / G0
    assert fit.rms < 3 * SIGMA_MEAN  # the residual is the noise of the means, no model error
    # round trip through the C converter with the written matrix: out = R f, R = C K a rotation
    r = fit.correction @ errors.matrix
    assert np.abs(r.T @ r - np.eye(3)).max() < 10 * SIGMA_MEAN / G0
    out = pose_means(fit.config.convert(codes), pose)[0]
    assert np.abs(out - f @ r.T).max() < 10 * SIGMA_MEAN


def test_accelerometer_six_positions_per_axis_zero_and_scale() -> None:
    rng = np.random.default_rng(11)
    part = ACC
    errors = part.draw_errors(rng)
    errors = SensorErrors(errors.bias, errors.scale, np.eye(3))  # no cross-axis: the diagonal model is exact
    codes, pose = _accel_codes(part, errors, _faces() * G0, rng)
    fit = _fit(codes, pose, _nominal())
    assert fit.model == "diagonal"
    assert np.abs(fit.residuals).max() < 1e-9  # six equations, six unknowns: no residual to show
    cfg = fit.config
    zero_codes = 2048 + 4096 * errors.bias  # 0 g code of each channel
    counts_per_g = part.codes_per_g * (1 + errors.scale)
    # a position's mean has σ_c/√ROWS ≈ 0.04 code; zero = mean of +1 g and −1 g: 10 σ is 0.3 code
    assert np.abs(cfg.zero - zero_codes).max() < 0.3
    assert np.abs(cfg.scale * counts_per_g / G0 - 1).max() < 10 * SIGMA_MEAN / G0
    assert np.abs(cfg.matrix - np.eye(3)).max() < 1e-12 and (cfg.bias == 0).all()


def test_accelerometer_axes_mapping() -> None:
    """Mounted with body x = −channel y, body y = channel x: the body values come out."""
    rng = np.random.default_rng(12)
    part = ACC.without_errors()
    chans, signs = parse_axes("-y,x,z")
    p = np.zeros((3, 3))
    p[range(3), chans] = signs
    f_body = np.vstack([_faces(), _directions(rng, 6)]) * G0
    codes, pose = _accel_codes(part.at_supply(3.3), SensorErrors(np.array([0.01, -0.02, 0.005]), np.zeros(3),
                                                                   np.eye(3)), f_body @ p, rng)  # f_ch = Pᵀ f_body
    nominal = _nominal(axes="-y,x,z")
    fit = _fit(codes, pose, nominal, "diagonal")
    out = pose_means(fit.config.convert(codes), pose)[0]
    # no noise: each position's codes are off by ≤ 0.5 code of quantization, which passes into the six
    # fitted parameters: a few half-codes at most; a mapping mistake would be off by ~g (400 codes)
    assert np.abs(out - f_body).max() < 2 * ACC.units_per_code
    assert fit.config.axes == "-y,x,z"


def test_accelerometer_refusals() -> None:
    rng = np.random.default_rng(13)
    with pytest.raises(InvalidArgument, match="needs 6"):
        fit_accel(_faces()[:5] * G0, _nominal())
    with pytest.raises(InvalidArgument, match="needs 12"):
        fit_accel(np.vstack([_faces(), _directions(rng, 2)]) * G0, _nominal(), model="full")
    tilts = _directions(rng, 12)
    tilts[:, 2] = 0.7  # every position the same height of z: its offset and scale are not separable
    tilts[:, :2] *= np.sqrt(1 - 0.49) / np.linalg.norm(tilts[:, :2], axis=1)[:, None]
    with pytest.raises(InvalidArgument, match="do not determine"):
        fit_accel(tilts * G0, _nominal(), model="diagonal")
    with pytest.raises(InvalidArgument, match="gravity"):
        fit_accel(_faces() * G0, _nominal(), gravity=float("nan"))


def _mag_words(errors: AmrErrors, seen_ut: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    c_set, c_reset = MAG.set_reset_codes(seen_ut, errors, 0.01, rng)
    return flip_code(c_set, c_reset)


def test_magnetometer_hard_and_soft_iron_round_trip() -> None:
    rng = np.random.default_rng(14)
    e = MAG.draw_errors(rng)
    errors = AmrErrors(SensorErrors(e.bridge.bias, e.bridge.scale, np.eye(3)), e.amp_offset_v)
    field = 50.6
    m = _directions(rng, 3000) * field
    soft = np.array([[1.06, 0.04, -0.02], [0.04, 0.95, 0.03], [-0.02, 0.03, 1.01]])  # symmetric
    hard = np.array([14.0, -9.0, 6.0])
    words = _mag_words(errors, m @ soft.T + hard, rng)
    fit = fit_mag(_nominal("mag").convert(words, corrected=False), _nominal("mag"), field_ut=field)
    k = (1 + errors.bridge.scale)[:, None] * soft  # v = K m + o
    o = (1 + errors.bridge.scale) * hard - 0.25 * MAG.units_per_code  # the flip code's floor: −0.25 code
    # per sample ≈ 0.4 code (0.05 µT) of quantization with little noise (0.13 code) to dither it: the
    # errors are not independent, so the hard iron is off by 0.017-0.023 µT on seeds 10-17, not the
    # 0.001 µT of 3000 independent samples; 0.05 µT (0.4 code) bounds it
    assert np.abs(fit.config.bias - o).max() < 0.05
    r = fit.config.matrix @ k
    assert np.abs(r.T @ r - np.eye(3)).max() < 0.05 / field  # that 0.05 µT relative to the field (seen: 1e-4)
    assert fit.field == pytest.approx(field) and fit.rms < 0.1  # |out| − F: about the 0.05 µT per sample
    out = fit.config.convert(words)  # the C converter with mag-matrix and mag-bias
    assert np.sqrt(np.mean((out - m @ r.T) ** 2)) < 0.1


def test_magnetometer_set_state_codes_offsets_become_hard_iron() -> None:
    """A board that converts once per sample in the set state (no reset conversion):
    the bridge and amplifier offsets stay in the codes, and the fit takes them as hard
    iron: b = (1 + s)·h + o/codes-per-µT, the field comes out the same."""
    rng = np.random.default_rng(16)
    e = MAG.draw_errors(rng)
    errors = AmrErrors(SensorErrors(e.bridge.bias, e.bridge.scale, np.eye(3)), e.amp_offset_v)
    m = _directions(rng, 3000) * 50.6
    hard = np.array([-6.0, 11.0, 3.0])
    words = tlc2543_codes(MAG.volts(m + hard, errors, 1, 0.01, rng), MAG.supply_v)
    nominal = SensorConfig("mag", [2048] * 3, [MAG.units_per_code] * 3)
    fit = fit_mag(nominal.convert(words, corrected=False), nominal, field_ut=50.6)
    offset_ut = MAG.gain * (MAG.supply_v * errors.bridge.bias + errors.amp_offset_v) / MAG.supply_v * 4096 \
        * MAG.units_per_code  # the offsets in codes, then µT at the nominal scale
    assert np.abs(offset_ut).max() > 20  # tens of µT: as large as the hard iron
    # one rounding per sample (unbiased, unlike the flip code's floor): σ ≈ √(1/12 + 0.13²) code = 0.038 µT,
    # 0.0007 µT over 3000 samples, a few times that per parameter; 0.01 µT bounds it (seen: 0.001-0.002)
    assert np.abs(fit.config.bias - ((1 + errors.bridge.scale) * hard + offset_ut)).max() < 0.01
    assert fit.rms < 0.1


def test_magnetometer_without_field_keeps_det_one_and_refuses_a_level_turn() -> None:
    rng = np.random.default_rng(15)
    m = _directions(rng, 500) * 48.0
    words = _mag_words(AmrErrors(SensorErrors.none(), np.zeros(3)), m, rng)
    fit = fit_mag(_nominal("mag").convert(words, corrected=False), _nominal("mag"))
    assert np.linalg.det(fit.config.matrix) == pytest.approx(1.0, abs=1e-9)
    assert fit.field == pytest.approx(48.0, rel=0.01)  # nominal scale exact for a perfect part: LSB/48 µT
    level = m.copy()
    level[:, 2] = -30.0
    with pytest.raises(InvalidArgument):
        words = _mag_words(AmrErrors(SensorErrors.none(), np.zeros(3)), level, rng)
        fit_mag(_nominal("mag").convert(words, corrected=False), _nominal("mag"))


def test_sensor_config_lines_and_checks() -> None:
    cfg = SensorConfig("mag", [2047.5, 2047, 2048], [0.12] * 3, "-Y, +x,z", np.eye(3) * 1.1, [1, 2, 3])
    assert cfg.lines() == ["mag-zero = 2047.5,2047,2048", "mag-scale = 0.12,0.12,0.12", "mag-axes = -y,x,z",
                           "mag-matrix = 1.1,0,0,0,1.1,0,0,0,1.1", "mag-bias = 1,2,3"]
    with pytest.raises(InvalidArgument, match="invertible"):
        SensorConfig("acc", 2048, 0.02, matrix=np.diag([1, 1, 1e-4]))
    with pytest.raises(InvalidArgument, match="axes"):
        SensorConfig("acc", 2048, 0.02, "x,x,z")
    with pytest.raises(InvalidArgument, match="zero"):
        SensorConfig("acc", 70000, 0.02)


def test_still_segments_finds_the_positions_and_no_movement() -> None:
    """Seven positions of 150-300 samples (σ 0.6 code) joined by 60-sample straight moves:
    seven labels, each on rows of one position only, each holding all of its position but
    less than four windows' worth (the partial windows at both ends, under two windows,
    and the first and last whole ones, which the search leaves out)."""
    rng = np.random.default_rng(17)
    pos = rng.uniform(1600, 2500, (7, 3))
    parts, truth = [], []
    for i, p in enumerate(pos):
        n = int(rng.integers(150, 300))
        parts.append(p + rng.normal(0, 0.6, (n, 3)))
        truth += [i] * n
        if i < 6:
            parts.append(np.linspace(p, pos[i + 1], 60) + rng.normal(0, 0.6, (60, 3)))
            truth += [-1] * 60
    t = np.array(truth)
    labels = still_segments(np.round(np.vstack(parts)), window=20)
    assert sorted(set(labels.tolist())) == [-1, *range(7)]
    for k in range(7):
        assert set(t[labels == k].tolist()) == {k}
        assert (labels == k).sum() >= (t == k).sum() - 4 * 20
    with pytest.raises(InvalidArgument, match="window"):
        still_segments(np.zeros((10, 3)), window=1)
