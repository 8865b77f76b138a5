"""The GNSS receiver model (attitude_c/sim/gnss_model.py), WGS-84 <-> ENU
(attitude_c/sim/geodetic.py) and the NMEA / UBX writers (attitude_c/sim/gnss_log.py),
the writers read back with the maintained parsers pynmea2 and pyubx2."""

from __future__ import annotations

import datetime
import io
import json
import math
from dataclasses import replace

import numpy as np
import pynmea2  # the gnss extra, in the test extra
import pytest
import pyubx2

from attitude_c.sim import SimConfig
from attitude_c.sim.catalog import make_trajectory
from attitude_c.sim.geodetic import (
    WGS84_A,
    WGS84_F,
    ecef_to_geodetic,
    enu_to_geodetic,
    geodetic_to_ecef,
    geodetic_to_enu,
)
from attitude_c.sim.gnss_log import (
    KNOT_M_S,
    NMEA_MAX_LEN,
    nmea_epoch,
    nmea_stream,
    ubx_nav_pvt,
    ubx_stream,
    write_gnss_log,
)
from attitude_c.sim.gnss_model import BadFix, GnssReceiver, Quality, gnss_preset

E2 = WGS84_F * (2 - WGS84_F)


# --- geodetic ------------------------------------------------------------------------------
def test_geodetic_known_points() -> None:
    b = WGS84_A * (1 - WGS84_F)
    np.testing.assert_allclose(geodetic_to_ecef(0, 0, 0), [WGS84_A, 0, 0], atol=1e-9)
    np.testing.assert_allclose(geodetic_to_ecef(90, 0, 0), [0, 0, b], atol=1e-9)
    lat, lon, h = ecef_to_geodetic([0.0, WGS84_A + 100.0, 0.0])
    assert (float(lat), float(lon), float(h)) == pytest.approx((0.0, 90.0, 100.0), abs=1e-9)


def test_geodetic_round_trip() -> None:
    rng = np.random.default_rng(1)
    lat, lon = rng.uniform(-89, 89, 500), rng.uniform(-180, 180, 500)
    h = rng.uniform(-500, 20000, 500)
    la, lo, hh = ecef_to_geodetic(geodetic_to_ecef(lat, lon, h))
    # Heikkinen's closed form: sub-mm near the surface (1e-9° ~ 0.1 mm)
    np.testing.assert_allclose(la, lat, atol=1e-9)
    np.testing.assert_allclose(lo, lon, atol=1e-9)
    np.testing.assert_allclose(hh, h, atol=1e-4)


def test_enu_small_steps_follow_the_radii_of_curvature() -> None:
    lat0, lon0, h0 = 32.06, 118.80, 10.0
    s = math.sin(math.radians(lat0))
    m = WGS84_A * (1 - E2) / (1 - E2 * s * s) ** 1.5  # meridian radius of curvature
    n = WGS84_A / math.sqrt(1 - E2 * s * s)  # prime vertical
    lat, lon, h = enu_to_geodetic([[0, 10.0, 0], [10.0, 0, 0], [0, 0, 10.0]], lat0, lon0, h0)
    # a 10 m step: second-order terms ~ (10 m)² / R ~ 2e-5 m, i.e. ~1e-10° in angle
    assert math.radians(lat[0] - lat0) * (m + h0) == pytest.approx(10.0, abs=1e-4)
    assert math.radians(lon[1] - lon0) * (n + h0) * math.cos(math.radians(lat0)) == pytest.approx(10.0, abs=1e-4)
    assert h[2] - h0 == pytest.approx(10.0, abs=1e-6)
    enu = np.array([[1234.5, -678.9, 55.5], [-3e4, 2e4, 1e3]])
    np.testing.assert_allclose(geodetic_to_enu(*enu_to_geodetic(enu, lat0, lon0, h0), lat0, lon0, h0), enu,
                               atol=1e-6)  # closed forms both ways: the inverse to µm


# --- the receiver model ----------------------------------------------------------------------
def _ideal() -> GnssReceiver:
    return GnssReceiver(model=gnss_preset("ideal"))


def test_ideal_fixes_are_the_truth_at_the_measurement_instant() -> None:
    tr = make_trajectory("fixed-wing-turn")
    rx = GnssReceiver(model=replace(gnss_preset("ideal"), latency_s=0.3, rate_hz=4.0))
    f = rx.fixes(tr, 20.0)
    t = f["t_measured"]
    np.testing.assert_allclose(np.diff(t), 0.25, atol=1e-12)
    np.testing.assert_allclose(f["t_delivered"] - t, 0.3, atol=1e-12)
    v = tr.velocity(t)
    np.testing.assert_allclose(np.stack([f["ve"], f["vn"], -f["vd"]], -1), v, atol=1e-12)
    np.testing.assert_allclose(f["speed"], np.hypot(v[:, 0], v[:, 1]), atol=1e-12)
    np.testing.assert_allclose(f["track"], np.mod(np.degrees(np.arctan2(v[:, 0], v[:, 1])), 360), atol=1e-9)
    enu = geodetic_to_enu(f["lat"], f["lon"], f["h"], *rx.origin)
    np.testing.assert_allclose(enu, tr.position(t), atol=1e-6)  # closed forms both ways


def test_velocity_noise_has_the_datasheet_sigma() -> None:
    rx = GnssReceiver(model=replace(gnss_preset("neo-m8n"), rate_hz=10.0))
    tr = make_trajectory("static")
    f = rx.fixes(tr, 1000.0, seed=3)
    n = len(f)
    # σ per horizontal axis = 0.05 m/s (50 %) / 1.1774; the sample σ of n normals has a
    # relative standard error 1/√(2n) = 0.7 % for n = 10001: 5 of them
    for ax in ("vn", "ve"):
        assert np.std(f[ax]) == pytest.approx(0.05 / math.sqrt(2 * math.log(2)), rel=5 / math.sqrt(2 * n))
    # the horizontal error's median radius is the data sheet's 0.05 m/s CEP (same bound, loosely)
    assert np.median(np.hypot(f["vn"], f["ve"])) == pytest.approx(0.05, rel=0.05)


def test_outage_quality_and_bad_fix() -> None:
    tr = make_trajectory("car-roundabout")
    rx = replace(_ideal(), outages=((5.0, 8.0),), quality=(Quality(10.0, 12.0, 2, 4, 4.0, 6.0),),
                 bad_fixes=(BadFix(15.0, 16.0, (2.0, -1.0, 0.5)),))
    f = rx.fixes(tr, 20.0)
    good = _ideal().fixes(tr, 20.0)
    t = f["t_measured"]
    out = (t >= 5) & (t < 8)
    assert np.all(f["fix_type"][out] == 0) and np.all(np.isnan(f["vn"][out])) and np.all(f["nsat"][out] == 0)
    two_d = (t >= 10) & (t < 12)
    assert np.all(f["fix_type"][two_d] == 2) and np.all(f["vd"][two_d] == 0)
    assert np.all(f["hdop"][two_d] == 4.0) and np.all(f["nsat"][two_d] == 4)
    bad = (t >= 15) & (t < 16)
    np.testing.assert_allclose(f["ve"][bad] - good["ve"][bad], 2.0, atol=1e-12)
    np.testing.assert_allclose(f["vn"][bad] - good["vn"][bad], -1.0, atol=1e-12)
    np.testing.assert_allclose(f["vd"][bad] - good["vd"][bad], -0.5, atol=1e-12)
    assert np.all(f["fix_type"][bad] == 3)
    rest = ~(out | two_d | bad)
    np.testing.assert_array_equal(f["vn"][rest], good["vn"][rest])


def test_receiver_arguments_are_checked() -> None:
    with pytest.raises(ValueError, match="rate"):
        replace(gnss_preset("neo-m8n"), rate_hz=20.0)
    with pytest.raises(ValueError, match="outage"):
        GnssReceiver(outages=((5.0, 2.0),))
    with pytest.raises(ValueError, match="gnss must be one of"):
        gnss_preset("sirf")


# --- the writers, read back by pynmea2 / pyubx2 --------------------------------------------------
@pytest.fixture(scope="module")
def fixes() -> np.ndarray:
    tr = make_trajectory("fixed-wing")
    rx = GnssReceiver(outages=((100.0, 101.0),), quality=(Quality(110.0, 111.0, 2, 4, 3.2, 5.5),),
                      origin=(-33.9, -151.2, 40.0))  # southern and western hemispheres
    return rx.fixes(tr, tr.total, seed=5)


def _utc(t: float, unit: float) -> datetime.datetime:
    return GnssReceiver().utc_start + datetime.timedelta(seconds=round(t / unit) * unit)


def test_nmea_sentences_parse_with_pynmea2(fixes: np.ndarray) -> None:
    for f in fixes:
        ok = f["fix_type"] >= 2
        sentences = nmea_epoch(f)
        assert all(len(s) <= NMEA_MAX_LEN and s.endswith("\r\n") for s in sentences)
        rmc, vtg, gga, gsa = (pynmea2.parse(s.strip(), check=True) for s in sentences)  # checksums verified
        when = _utc(float(f["t_measured"]), 0.01)
        assert rmc.datetime.replace(tzinfo=datetime.timezone.utc) == when and gga.timestamp == when.timetz()
        assert rmc.status == ("A" if ok else "V") and int(gga.gps_qual) == (1 if ok else 0)
        assert int(gsa.mode_fix_type) == {0: 1, 2: 2, 3: 3}[int(f["fix_type"])]
        assert int(gga.num_sats) == f["nsat"]
        assert float(gsa.hdop) == pytest.approx(f["hdop"], abs=0.005)  # 2 decimals
        assert float(gsa.pdop) == pytest.approx(f["pdop"], abs=0.005)
        if not ok:
            assert rmc.lat == "" and rmc.spd_over_grnd is None
            continue
        for msg in (rmc, gga):  # ddmm.mmmmm: 1e-5 minute = 1.7e-7°
            assert msg.latitude == pytest.approx(f["lat"], abs=0.5e-5 / 60 + 1e-12)
            assert msg.longitude == pytest.approx(f["lon"], abs=0.5e-5 / 60 + 1e-12)
        assert rmc.spd_over_grnd == pytest.approx(f["speed"] / KNOT_M_S, abs=0.0005)  # 0.001 kn
        assert float(vtg.spd_over_grnd_kmph) == pytest.approx(f["speed"] * 3.6, abs=0.0005)
        assert rmc.true_course == pytest.approx(f["track"], abs=0.005)  # 0.01°
        assert gga.altitude == pytest.approx(f["h"], abs=0.05)  # 0.1 m


def test_ubx_nav_pvt_parses_with_pyubx2(fixes: np.ndarray) -> None:
    for f in fixes:
        frame = ubx_nav_pvt(f)
        assert len(frame) == 100 and frame[4:6] == (92).to_bytes(2, "little")
        m = pyubx2.UBXReader.parse(frame, validate=pyubx2.VALCKSUM)  # Fletcher-8 verified
        assert m.identity == "NAV-PVT"
        when = _utc(float(f["t_measured"]), 0.001)
        assert (m.year, m.month, m.day, m.hour, m.min, m.second, m.nano) == (
            when.year, when.month, when.day, when.hour, when.minute, when.second, when.microsecond * 1000)
        assert m.fixType == f["fix_type"] and m.numSV == f["nsat"]
        assert m.pDOP == pytest.approx(f["pdop"], abs=0.005)  # 0.01
        if f["fix_type"] == 0:
            assert m.gnssFixOk == 0 and m.invalidLlh == 1
            continue
        assert m.gnssFixOk == 1
        assert m.lat == pytest.approx(f["lat"], abs=0.5e-7 + 1e-12)  # 1e-7°
        assert m.lon == pytest.approx(f["lon"], abs=0.5e-7 + 1e-12)
        assert m.height == pytest.approx(f["h"] * 1000, abs=0.5)  # mm
        for name, field in (("velN", "vn"), ("velE", "ve"), ("velD", "vd"), ("gSpeed", "speed")):
            assert getattr(m, name) == pytest.approx(f[field] * 1000, abs=0.5)  # mm/s
        assert m.headMot == pytest.approx(f["track"], abs=0.5e-5 + 1e-9)  # 1e-5°
        assert m.sAcc == pytest.approx(f["s_acc"] * 1000, abs=0.5)


def test_ubx_itow_is_gps_time_of_week() -> None:
    f = _ideal().fixes(make_trajectory("static"), 1.0)[:1]
    # 2026-01-01 12:00:00 UTC is a Thursday: 4 days 12 h into the GPS week, + 18 leap seconds
    raw = int.from_bytes(ubx_nav_pvt(f[0])[6:10], "little")
    assert raw == ((4 * 24 + 12) * 3600 + 18) * 1000


def test_log_files_are_the_streams_in_delivery_order(tmp_path, fixes: np.ndarray) -> None:
    shuffled = fixes[::-1]
    write_gnss_log(tmp_path / "a.nmea", shuffled)
    write_gnss_log(tmp_path / "a.ubx", shuffled)
    assert (tmp_path / "a.nmea").read_bytes() == nmea_stream(fixes)
    data = (tmp_path / "a.ubx").read_bytes()
    assert data == ubx_stream(fixes)
    msgs = list(pyubx2.UBXReader(io.BytesIO(data)))
    assert len(msgs) == len(fixes)
    with pytest.raises(ValueError, match="nmea or"):
        write_gnss_log(tmp_path / "a.txt", fixes)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.nmea", "a.ubx"]  # no temporary left behind


def test_options_configure_the_receiver() -> None:
    cfg = SimConfig.from_dict({"trajectory": "fixed-wing-turn", "gnss_log": "fix.nmea", "gnss_outage": [[40, 70]],
                               "gnss_rate": 10, "gnss_bad_fix": "20,21,0,3,0"})
    assert cfg.gnss is not None and cfg.gnss.model.name == "neo-m8n" and cfg.gnss.model.rate_hz == 10
    assert cfg.gnss.outages == ((40.0, 70.0),) and cfg.gnss.bad_fixes[0].dv == (0.0, 3.0, 0.0)
    assert SimConfig.from_dict({}).gnss is None
    with pytest.raises(ValueError, match="needs a GNSS receiver"):
        SimConfig.from_dict({"gnss": "none", "gnss_outage": "1,2"})
    with pytest.raises(ValueError, match="nmea or"):
        SimConfig.from_dict({"gnss_log": "fix.log"})


def test_simulate_writes_the_gnss_log_beside_the_run(tmp_path, capsys) -> None:
    from attitude_c.cli import main

    out = tmp_path / "run"
    args = ["simulate", "--trajectory", "fixed-wing-turn", "--sensors", "ideal", "--link", "none", "--calibration",
            "0", "--no-plots", "--no-progress", "--out", str(out), "--gnss-outage", "40,70"]
    assert main([*args, "--gnss-log", "fix.ubx"]) == 0
    assert main([*args, "--gnss-log", "fix.nmea", "--gnss", "ideal"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["files"]["gnss_log"] == "fix.nmea" and summary["gnss"]["model"] == "ideal"
    # ideal: 10 Hz over the 83 s turn (0 .. 83 s inclusive), 300 epochs without a fix in 40 .. 70 s
    assert summary["gnss"]["epochs"] == 831 and summary["gnss"]["no_fix"] == 300
    msgs = list(pyubx2.UBXReader(io.BytesIO((out / "fix.ubx").read_bytes())))
    assert len(msgs) == 5 * 83 + 1  # the neo-m8n preset's 5 Hz
    lines = (out / "fix.nmea").read_text().splitlines()
    assert len(lines) == 4 * 831 and all(pynmea2.parse(s, check=True) for s in lines[:8])
    assert sorted(p.name for p in out.iterdir()) == ["fix.nmea", "fix.ubx", "summary.json", "timeseries.csv"]
    capsys.readouterr()
    assert main([*args, "--gnss-log", "fix.txt"]) == 2
    assert "name it *.nmea or *.ubx" in capsys.readouterr().err
