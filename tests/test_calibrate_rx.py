"""``attitude calibrate``'s config through ``attitude-rx`` (issue 26), end to end: a
simulated aided board (the front ends of attitude_c.sim.frontend with their errors
drawn, hard iron) is calibrated from a recording of codes; then the same board,
tilted at a known attitude, streams over link v2 to the host build of attitude-rx
reading that config, whose converted accelerometer and magnetometer values must be
the true specific force and field in body axes.

The board has no cross-axis error and a diagonal soft iron here, so that the
sensitivity matrices are symmetric and the calibration leaves no rotation (a
rotation is invisible to a norm-based calibration: docs/sensor.md): the truth is
then the body-frame vector itself.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import require_target
from test_attitude_rx_aided import _lines, _run  # tests/ is on the path (pytest's rootdir conftest)

from attitude_c.cli import EXIT_OK, main
from attitude_c.link import block
from attitude_c.sim.accelmag import G0, SensorErrors
from attitude_c.sim.frontend import ACCEL_FRONTENDS, MAG_FRONTENDS, AmrErrors, flip_code, tlc2543_codes

ACC, MAG = ACCEL_FRONTENDS["adxl335"], MAG_FRONTENDS["hmc1043-ad623"]
HARD = np.array([9.0, -12.0, 5.0])  # µT
SOFT = np.diag([1.04, 0.97, 1.01])
FIELD = 50.6  # µT


@pytest.fixture(scope="module")
def rx_host(tmp_path_factory: pytest.TempPathFactory) -> list[str]:
    from toolchain.tasks.cross import cross_build_target

    require_target("host")
    return [str(cross_build_target("host", out=tmp_path_factory.mktemp("rx-cal") / "host")["app"])]


def _board(rng: np.random.Generator) -> tuple[SensorErrors, AmrErrors]:
    a, m = ACC.draw_errors(rng), MAG.draw_errors(rng)
    return (SensorErrors(a.bias, a.scale, np.eye(3)),
            AmrErrors(SensorErrors(m.bridge.bias, m.bridge.scale, np.eye(3)), m.amp_offset_v))


def _codes(f: np.ndarray, m: np.ndarray, errors: tuple[SensorErrors, AmrErrors],
           rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    acc = tlc2543_codes(ACC.volts(f, errors[0], 0.01, rng), ACC.supply_v)
    mag = flip_code(*MAG.set_reset_codes(m @ SOFT.T + HARD, errors[1], 0.01, rng))
    return acc, mag


def _calibrate(tmp_path: Path, errors: tuple[SensorErrors, AmrErrors], rng: np.random.Generator) -> Path:
    d = rng.normal(size=(24, 3))
    d[:6] = np.vstack([np.eye(3), -np.eye(3)])
    f = np.repeat(d / np.linalg.norm(d, axis=1)[:, None] * G0, 200, axis=0)
    u = rng.normal(size=(len(f), 3))
    acc, mag = _codes(f, u / np.linalg.norm(u, axis=1)[:, None] * FIELD, errors, rng)
    rec, conf = tmp_path / "rec.csv", tmp_path / "rx.conf"
    pose = np.repeat(np.arange(24), 200)
    np.savetxt(rec, np.column_stack([pose, acc, mag]), fmt="%d", delimiter=",", comments="",
               header="pose,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z")
    conf.write_text("# the board\nestimator = ahrs\n")
    assert main(["calibrate", "--acc", str(rec), "--mag", str(rec), "--out", str(conf),
                 "--mag-field", str(FIELD)]) == EXIT_OK
    return conf


def test_attitude_rx_converts_with_the_calibration(rx_host: list[str], tmp_path: Path) -> None:
    rng = np.random.default_rng(26)
    errors = _board(rng)
    conf = _calibrate(tmp_path, errors, rng)
    # the board at rest, rolled 20°, pitched −10°, yawed −30° (heading 30°; ENU, docs/conventions.md)
    c_b = _body_from_nav(math.radians(20.0), math.radians(-10.0), math.radians(-30.0))
    f_body = c_b @ [0.0, 0.0, G0]  # the specific force at rest: gravity's reaction, up
    inc = math.radians(60.0)
    m_body = c_b @ (FIELD * np.array([0.0, math.cos(inc), -math.sin(inc)]))  # north and down
    n = 200
    acc, mag = _codes(np.tile(f_body, (n, 1)), np.tile(m_body, (n, 1)), errors, rng)
    recs = [block.encode_boot(36, 9600, link="v2"), block.encode_channels("aided9", ["gyr", "acc", "mag"], 1, 1)]
    for k in range(n):
        recs += [block.encode_sample([2048] * 3), block.encode_sample(acc[k]), block.encode_sample(mag[k])]
    lines = _lines(_run(rx_host, recs, n, "--config", str(conf))[0])
    got_a = np.mean([x["acc_ms2"] for x in lines], axis=0)
    got_m = np.mean([x["mag_ut"] for x in lines], axis=0)
    # accelerometer: 0.57 code (0.014 m/s²) of noise per sample, 0.001 m/s² over 200; the calibration's
    # ~0.001 m/s² (tests/test_sensorcal.py): 0.01 m/s² (1 mg) is 5 of each together
    np.testing.assert_allclose(got_a, f_body, rtol=0, atol=0.01)
    # magnetometer: a still field's flip code is off by −1..+0.5 code (0.12 µT per code), little noise
    # to average it away; the calibration's 0.05 µT: 0.25 µT
    np.testing.assert_allclose(got_m, m_body, rtol=0, atol=0.25)
    # uncalibrated (nominal zero and scale) the same board is off by tens of mg and µT: the test can fail
    nominal_a = (acc.mean(axis=0) - 2048) * ACC.units_per_code
    assert np.abs(nominal_a - f_body).max() > 0.1


def _body_from_nav(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """C(body ← nav) of the z-y-x (yaw, pitch, roll) rotation."""
    cy, sy, cp, sp, cr, sr = (math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch), math.cos(roll),
                              math.sin(roll))
    c_nb = np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])
    return c_nb.T
