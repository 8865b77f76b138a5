"""attitude_c.onav: onavdata's flight and car logs read into the library's frames. The files
are made here in the package's layout (zipped CSV, its column names) from known values: the
axes relabelled by hand (forward-right-down -> right-forward-up; the n380's sensor axes by its
published matrix), the reference's aerospace angles read back with attitude_c.frames (an
independent path: the z-y-x sequence), NED velocities as ENU."""

from __future__ import annotations

import math
import zipfile
from pathlib import Path

import numpy as np
import pytest

from attitude_c import frames, onav
from attitude_c.errors import InvalidArgument

D = math.pi / 180
G = 9.80665


def _zcsv(path: Path, header: list[str], rows: list[list[float | str]]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    text = ",".join(header) + "\n" + "\n".join(",".join(str(x) for x in r) for r in rows) + "\n"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr(path.name[:-len(".zip")], text)


def _umn(root: Path, heading: float, pitch: float, roll: float) -> None:
    d = root / onav.RECORDINGS["umn-thor77"][1]
    t = [k * 0.02 for k in range(6)]
    _zcsv(d / "accel_data.txt.zip", ["time", "accel_x", "accel_y", "accel_z"], [[x, 1.0, 2.0, -G] for x in t])
    _zcsv(d / "gyro_data.txt.zip", ["time", "gyro_x", "gyro_y", "gyro_z"], [[x, 0.1, -0.2, 0.3] for x in t])
    _zcsv(d / "mag_data.txt.zip", ["time", "mag_x", "mag_y", "mag_z"], [[x, 0.2, 0.0, 0.5] for x in t])
    _zcsv(d / "nav_attitude_data.txt.zip", ["time", "nav_yaw", "nav_pitch", "nav_roll"],
          [[x, heading, pitch, roll] for x in t])
    # fixes held at 50 Hz: new at rows 0 and 3; row 5 missing (an empty field)
    vel = [[1.0, 2.0, -0.5]] * 3 + [[3.0, 4.0, 0.25]] * 2
    _zcsv(d / "gps_velocity_data.txt.zip", ["time", "gps_vn", "gps_ve", "gps_vd"],
          [[x, *v] for x, v in zip(t, vel)] + [[t[5], "", "", ""]])


def test_umn_flight_in_the_librarys_frames(tmp_path: Path) -> None:
    _umn(tmp_path, 30 * D, 10 * D, -20 * D)
    r = onav.load("umn-thor77", tmp_path)
    assert r.kind == "umn-uav" and r.rate == pytest.approx(50.0)
    # forward-right-down (x, y, z) -> right-forward-up (y, x, -z): exact relabelling
    np.testing.assert_array_equal(r.acc, np.tile([2.0, 1.0, G], (6, 1)))
    np.testing.assert_array_equal(r.gyr, np.tile([-0.2, 0.1, -0.3], (6, 1)))
    np.testing.assert_array_equal(r.mag, np.tile([0.0, 0.2, -0.5], (6, 1)))
    # the aerospace angles back through frames.euler's z-y-x sequence (a few ulp of rounding)
    np.testing.assert_allclose(frames.euler(r.q_ref, "zyx"), np.tile([30 * D, 10 * D, -20 * D], (6, 1)), atol=1e-12)
    np.testing.assert_array_equal(r.gnss_t, [0.0, 0.06])
    np.testing.assert_array_equal(r.gnss_vel, [[2.0, 1.0, 0.5], [4.0, 3.0, -0.25]])  # NED -> ENU


def _n380(root: Path) -> None:
    d = root / onav.RECORDINGS["n380-hill"][1]
    t = [20.0 + 0.01 * k for k in range(5)]
    # the IMU's sensor axes: s = R^T b for the forward-right-down body vector b = (1, 2, 3) rad/s and
    # (0.5, -0.25, -G) m/s², R = the published sensor -> case matrix [[0,0,-1],[0,1,0],[1,0,0]]
    dth, dv = [0.03, 0.02, -0.01], [-G / 100, -0.0025, -0.005]
    _zcsv(d / "n380-imu-nav.csv.zip", ["SystemTov"] + [f"DeltaTheta[{i}]" for i in range(3)]
          + [f"DeltaVelocity[{i}]" for i in range(3)] + ["InsGnssBIT.InsMode"], [[x, *dth, *dv, 4] for x in t])
    # attitude rows: not aligned yet (-1), navigation mode (4) 1 ms off the IMU's time, one row missing
    att = [[-1.0, 0, 0, 0, 1e5, 1e5, 1e5, 1]] + [[x + 0.001, 5 * D, -3 * D, 200 * D, 0.01, 0.02, 0.03, 4]
                                                 for x in t[1:4]]
    _zcsv(d / "n380-attitude.csv.zip", ["SystemTov"] + [f"EulerAttitude[{i}]" for i in range(3)]
          + [f"EulerAttitudeStdv[{i}]" for i in range(3)] + ["InsGnssBIT.InsMode"], att)
    _zcsv(d / "n380-gnss-pvt.csv.zip", ["SystemTov", "GnssVelocityN", "GnssVelocityE", "GnssVelocityD", "GnssStdvN",
                                        "GnssStdvE", "GnssStdvD"],
          [[20.0, 1.0, 2.0, 3.0, 0.1, 0.2, 0.3], [21.0, "", "", "", "", "", ""]])


def test_n380_drive_in_the_librarys_frames(tmp_path: Path) -> None:
    _n380(tmp_path)
    r = onav.load("n380-hill", tmp_path)
    assert r.kind == "hguide-n380" and r.mag is None and r.rate == pytest.approx(100.0)
    # increments per 1/100 s as rates, the body's forward-right-down (1, 2, 3) as right-forward-up (2, 1, -3)
    np.testing.assert_allclose(r.gyr, np.tile([2.0, 1.0, -3.0], (5, 1)), rtol=1e-12)
    np.testing.assert_allclose(r.acc, np.tile([-0.25, 0.5, G], (5, 1)), rtol=1e-12)
    ok = np.isfinite(r.q_ref).all(axis=1)
    assert ok.tolist() == [False, True, True, True, False]  # first and last IMU epochs: no navigation-mode row
    np.testing.assert_allclose(frames.euler(r.q_ref[ok], "zyx"), np.tile([200 * D - 2 * math.pi, -3 * D, 5 * D],
                                                                          (3, 1)), atol=1e-12)
    np.testing.assert_array_equal(r.ref_sigma[ok], np.tile([0.01, 0.02, 0.03], (3, 1)))
    np.testing.assert_array_equal(r.gnss_t, [20.0])  # the fix without a velocity is dropped
    np.testing.assert_array_equal(r.gnss_vel, [[2.0, 1.0, -3.0]])
    np.testing.assert_array_equal(r.gnss_sigma, [[0.2, 0.1, 0.3]])


def test_summary_tilt_is_the_angle_between_gravity_and_the_references_up(tmp_path: Path) -> None:
    """A still vehicle (speed 0) whose accelerometer reads level: a reference pitched 4° is 4° off."""
    _umn(tmp_path, 0.0, 4 * D, 0.0)
    d = tmp_path / onav.RECORDINGS["umn-thor77"][1]
    t = [k * 0.02 for k in range(6)]
    _zcsv(d / "accel_data.txt.zip", ["time", "accel_x", "accel_y", "accel_z"], [[x, 0.0, 0.0, -G] for x in t])
    _zcsv(d / "gyro_data.txt.zip", ["time", "gyro_x", "gyro_y", "gyro_z"], [[x, 0.0, 0.0, 0.0] for x in t])
    _zcsv(d / "gps_velocity_data.txt.zip", ["time", "gps_vn", "gps_ve", "gps_vd"],
          [[x, 0.0, 0.0, 0.0] for x in t[:3]] + [[x, 0.0, 0.0, 1e-3] for x in t[3:]])
    s = onav.summary(onav.load("umn-thor77", tmp_path))
    assert s["still_s"] == round(6 / 50, 1)  # every sample still: 6 at 50 Hz (summary rounds to 0.1 s)
    assert s["still_tilt_p50_deg"] == pytest.approx(4.0, abs=1e-3)  # summary rounds to 0.001°
    assert s["gnss_n"] == 2 and s["imu_hz"] == 50.0


def test_errors_name_what_is_wrong(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(InvalidArgument, match="recording must be one of umn-thor60"):
        onav.load("kitti", tmp_path)
    with pytest.raises(InvalidArgument, match="no such folder"):
        onav.load("n380-hill", tmp_path)
    monkeypatch.setattr(onav, "default_dir", lambda: None)
    with pytest.raises(InvalidArgument, match="onavdata is not installed"):
        onav.load("n380-hill")
    _umn(tmp_path, 0.0, 0.0, 0.0)
    d = tmp_path / onav.RECORDINGS["umn-thor77"][1]
    _zcsv(d / "gyro_data.txt.zip", ["time", "gyro_x", "gyro_y", "gyro_z"], [[0.5 * k, 0, 0, 0] for k in range(6)])
    with pytest.raises(InvalidArgument, match="gyro_data's times are not the accelerometer's"):
        onav.load("umn-thor77", tmp_path)
    (d / "mag_data.txt.zip").write_bytes(b"not a zip")
    with pytest.raises(InvalidArgument, match="cannot read"):
        onav.load("umn-thor77", tmp_path)


# -- bench/onav.py's pure helpers (no data needed) -----------------------------------------

def test_bench_tilt_errors_ignore_heading_and_wrap() -> None:
    """Roll and pitch errors are the z-x-y Euler differences whatever the two headings (the
    yaw is the first rotation, about the world's up), wrapped to ±π."""
    from attitude_c.core import euler_to_quat
    from bench.onav import tilt_errors

    ref = euler_to_quat(np.radians([[10.0, 2.0, -3.0], [200.0, -1.0, 179.0]]))
    est = euler_to_quat(np.radians([[95.0, 2.5, -2.0], [-30.0, -1.25, -179.0]]))
    # 1e-9 rad: double-precision conversions of angles of order 1 rad
    np.testing.assert_allclose(np.degrees(tilt_errors(est, ref)), [[1.0, 0.5], [2.0, -0.25]], atol=1e-7)


def test_bench_figures_and_missing_data(tmp_path: Path) -> None:
    from bench import onav as b

    f = b.figures(np.radians([[3.0, 0.0], [-4.0, 1.0], [0.0, 0.25]]))
    # closed forms: sqrt((9 + 16) / 3), max |.|; sqrt((1 + 1/16) / 3), 1; 2 of 3 samples beyond
    # 0.5° (1e-12: double rounding)
    assert f == pytest.approx((math.sqrt(25 / 3), 4.0, math.sqrt(17 / 48), 1.0, 2 / 3), abs=1e-12)
    assert b.missing(str(tmp_path)) == b.HOW  # a folder without the n380 drives
    for r in b.RECORDINGS:
        (tmp_path / onav.RECORDINGS[r][1]).mkdir(parents=True)
    assert b.missing(str(tmp_path)) is None
