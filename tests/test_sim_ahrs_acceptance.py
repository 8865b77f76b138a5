"""The attitude filter's simulated acceptance tests (issue 15), shortened for the
default suite; `invoke sim-acceptance` runs them at full length (30 min static,
360 s turntable). The scenarios, the system and how each figure is measured:
toolchain/ahrs_acceptance.py; the measured figures: docs/simulation.md.

Each run is shorter but the same test: the static and turntable figures are
maxima over the run after 10 s (the static run's covariance is then within
25 % of its steady state: at rest the tilt averages the accelerometer over
acc_noise/gyr_noise_rest = 12.5 s; the turntable's 10 s start-up transient
is inside both lengths); the bias step is judged 10 s after the step as in
the full run, after 30 s of rest instead of 60 (the filter's bias covariance
is steady after ~20 s); the disturbance lasts 30 s as in the full run, judged
until 30 s after it ends instead of 60.

At full length (`invoke sim-acceptance`, seed 0) every target is met:
static 0.045°, turntable tilt 0.097°, heading 0.101° (docs/simulation.md);
the shortened runs guard against regressions at the targets' thresholds."""

from __future__ import annotations

import pytest

from toolchain.ahrs_acceptance import SHORT, TARGETS, bias_step, disturbance, run, static, turntable
from toolchain.allan_settings import derived

pytestmark = pytest.mark.system  # runs the simulator's acceptance scenarios


def test_static_tilt_is_the_accelerometers() -> None:
    """Roll and pitch within 0.05° of the tilt the accelerometer's own errors
    imply (issue 15's target; the MEMS AHRS paper reports 0.4°). The offset
    itself (bias/g: 4.0° pitch, 0.53° roll for this seed's ADIS16405 draw)
    is no filter's to remove: it is reported, not judged."""
    f = static(**SHORT["static"])
    assert f.values["static_tilt_deg"] <= TARGETS["static_tilt_deg"][0], f.info
    # the offset is the part's: the raw error is its size (a filter that ignored the
    # accelerometer would not show it), within the 0.05° above plus misalignment and scale
    assert abs(f.info["implied_pitch_deg"] - f.info["bias_over_g_pitch_deg"]) < 0.5


def test_turntable_5_dps() -> None:
    """z-axis turntable at 5°/s: roll/pitch ≤ 0.1°, heading ≤ 0.5° (issue 15's
    targets; the FPGA+DSP paper: within 0.4–0.5° of heading), calibrated parts."""
    f = turntable(**SHORT["turntable"])
    assert f.values["turntable_heading_deg"] <= TARGETS["turntable_heading_deg"][0], f.info
    assert f.values["turntable_tilt_deg"] <= TARGETS["turntable_tilt_deg"][0], f.info


def test_gyro_bias_step_at_rest() -> None:
    """A 0.5°/s step on each gyro axis at rest is estimated within 0.05°/s in
    10 s (issue 15's target: a tenth of the step)."""
    f = bias_step(**SHORT["bias_step"])
    assert f.values["bias_step_err_dps"] <= TARGETS["bias_step_err_dps"][0], f.info


def test_magnetic_disturbance_is_rejected() -> None:
    """A 30 s field disturbance (norm +30 %, dip +20°) moves roll/pitch ≤ 0.2°
    and heading ≤ 2° (issue 15's targets)."""
    f = disturbance(**SHORT["disturbance"])
    assert f.values["disturbance_tilt_deg"] <= TARGETS["disturbance_tilt_deg"][0], f.info
    assert f.values["disturbance_heading_deg"] <= TARGETS["disturbance_heading_deg"][0], f.info
    assert f.info["mag_rejected_fraction"] > 0.3  # the 30 s were rejected, not absorbed: 30 of 90 s


def test_settings_from_the_allan_deviation_pass() -> None:
    """The filter's noise settings derived from a rest recording of the same system
    (attitude_c.noise.filter_settings; 10 min of another seed here, 2 h in `invoke
    allan-settings`) meet every target the defaults meet (docs/noise.md has the figures
    side by side: the bias step is learnt 13× better; the static tilt is 12 % worse in the
    shortened run, 18 % better at full length)."""
    from attitude_c.ahrs_filter import default_settings

    settings, _, _ = derived(duration=600.0)
    assert settings["gyr_noise_rest"] < default_settings()["gyr_noise_rest"] / 10  # the sensor's, not the default
    for f in run(SHORT, 0, settings).values():
        for k, v in f.values.items():
            assert v <= TARGETS[k][0], (k, v, f.info)
