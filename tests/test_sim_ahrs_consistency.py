"""Consistency of the attitude filter's reported covariance on the simulated acceptance
motions (issue 32): the NEES of the attitude (true error against the covariance the
filter reports, ``toolchain.ahrs_acceptance.nees_inside``) inside its two-sided 95 %
χ²(3) band for at least 90 % of the samples after the 10 s settling, seeds 0, 1, 2, the
motions at their full lengths (static 30 min, turntable 360 s, disturbance 150 s: about
18 s of simulation per seed).

The settings come from the sensors' own noise, the way a user gets them: ten minutes of the
calibrated system at rest (seed 11, none of the motions'), ``attitude_c.allan`` on the gyro,
accelerometer and magnetometer, ``filter_settings(..., calibrated=True)``
(``toolchain.allan_settings.calibrated_settings``; docs/noise.md). Nothing in that route
looks at a NEES. The bias step is left out: a 0.5°/s step is a fault no random-walk model
holds (docs/ahrs.md)."""

from __future__ import annotations

import pytest

from toolchain.ahrs_acceptance import FULL, NEES_INSIDE_MIN, disturbance, static, turntable
from toolchain.allan_settings import calibrated_settings

pytestmark = pytest.mark.system  # runs the simulator's acceptance scenarios


@pytest.fixture(scope="module")
def settings() -> dict[str, float]:
    return calibrated_settings()[0]  # 10 min at rest, seed 11: 7 s


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_nees_in_band_static(seed: int, settings: dict[str, float]) -> None:
    f = static(**FULL["static"], seed=seed, settings=settings, calibrated=True)
    assert f.info["nees_inside"] >= NEES_INSIDE_MIN, f.info


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_nees_in_band_turntable(seed: int, settings: dict[str, float]) -> None:
    f = turntable(**FULL["turntable"], seed=seed, settings=settings)
    assert f.info["nees_inside"] >= NEES_INSIDE_MIN, f.info


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_nees_in_band_magnetic_disturbance(seed: int, settings: dict[str, float]) -> None:
    f = disturbance(**FULL["disturbance"], seed=seed, settings=settings)
    assert f.info["nees_inside"] >= NEES_INSIDE_MIN, f.info
