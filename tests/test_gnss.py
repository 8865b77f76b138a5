"""attitude_c.gnss: the library's own NMEA 0183 / UBX NAV-PVT parser against the
maintained packages (pynmea2, pyubx2: attitude_c.reference.gnss) and closed forms.

Streams are written here with the packages' own builders (pynmea2's sentence
classes, pyubx2's UBXMessage) and the NMEA standard's example sentences; every
field of every fix is compared. The "never stuck" property: after any garbage
and at most the documented resync distance, a valid sentence is parsed."""

from __future__ import annotations

import math

import numpy as np
import pynmea2
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pyubx2 import GET, UBXMessage

from attitude_c import gnss, names
from attitude_c.errors import InvalidType
from attitude_c.reference import gnss as gnss_reference

# The standard's example epoch (NMEA 0183, the well-known 12:35:19 sentences).
EXAMPLE = (b"$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A\r\n"
           b"$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*48\r\n"
           b"$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n"
           b"$GPGSA,A,3,04,05,,09,12,,,24,,,,,2.5,1.3,2.1*39\r\n")
REALS = ("tod", "tow", "lat", "lon", "height", "height_msl", "vel_n", "vel_e", "vel_d", "speed", "track",
         "hdop", "pdop", "vdop", "h_acc", "v_acc", "s_acc")
# f64: both sides read the same decimal digits; the C scales an integer mantissa, the
# packages a float: a few ulp of values up to 604800 s (tow) -> 1e-9 relative is ample.
# f32: att_real has a 24-bit mantissa (rel. 6e-8 per rounding, a handful of roundings).
TOL = {"f64": (1e-12, 1e-9), "f32": (1e-6, 1e-5)}  # (rel, abs)


def assert_same(c: list[gnss.GnssFix], ref: list[gnss.GnssFix], precision: str = "f64") -> None:
    assert len(c) == len(ref)
    for a, b in zip(c, ref):
        for k in REALS:
            x, y = getattr(a, k), getattr(b, k)
            assert (x is None) == (y is None), (k, a, b)
            if k == "track" and x is not None:  # a course: 0 and 2 pi are one (f32 rounds up to 2 pi)
                x = y + math.remainder(x - y, 2.0 * math.pi)
            if x is not None:
                assert x == pytest.approx(y, rel=TOL[precision][0], abs=TOL[precision][1]), (k, x, y)
        for k in ("date", "fix_type", "valid", "sats", "sources"):
            assert getattr(a, k) == getattr(b, k), (k, a, b)


def test_standard_example_epoch_closed_form() -> None:
    (f,) = gnss.parse(EXAMPLE)
    assert_same([f], gnss_reference.parse(EXAMPLE))
    knot = 1852.0 / 3600.0
    assert f.lat == pytest.approx(math.radians(48 + 7.038 / 60), abs=1e-15)  # a few ulp of 0.84 rad
    assert f.lon == pytest.approx(math.radians(11 + 31.0 / 60), abs=1e-15)
    assert f.speed == pytest.approx(5.5 * knot, rel=1e-15)  # VTG, later than RMC, wins
    assert f.vel_n == pytest.approx(5.5 * knot * math.cos(math.radians(54.7)), rel=1e-14)
    assert f.height == pytest.approx(545.4 + 46.9, rel=1e-15)
    assert (f.date, f.fix_type, f.valid, f.sats, f.hdop) == ((1994, 3, 23), "3d", True, 8, 1.3)


# ---- generated streams ----

def _dm(deg: float, width: int) -> str:
    """|deg| as (d)ddmm.mmmmm."""
    d = int(abs(deg))
    m = (abs(deg) - d) * 60.0
    return f"{d:0{width}d}{m:08.5f}"


def _nmea(kind: str, fields: tuple[str, ...], talker: str) -> bytes:
    cls = getattr(pynmea2, kind)
    return (str(cls(talker, kind, fields)) + "\r\n").encode()


@st.composite
def nmea_epoch(draw: st.DrawFn, csec: int) -> bytes:
    """One epoch's sentences (random subset and order after the first, random values)."""
    talker = draw(st.sampled_from(["GP", "GN", "GL", "GA"]))
    hms = f"{csec // 360000:02d}{csec // 6000 % 60:02d}{csec // 100 % 60:02d}.{csec % 100:02d}"
    lat, lon = draw(st.floats(-89.9, 89.9)), draw(st.floats(-179.9, 179.9))
    ll = (_dm(lat, 2), "N" if lat >= 0 else "S", _dm(lon, 3), "E" if lon >= 0 else "W")
    sog, cog = draw(st.sampled_from(["", "0.0", "12.34", "0.512"])), draw(st.sampled_from(["", "0.0", "359.9", "84.4"]))
    date = draw(st.sampled_from(["", "230394", "281126", "010100"]))
    status, mode = draw(st.sampled_from("AV")), draw(st.sampled_from("ADEN"))
    alt, sep = draw(st.sampled_from(["", "545.4", "-12.0"])), draw(st.sampled_from(["", "46.9", "-30.25"]))
    q, sats = draw(st.sampled_from("012456")), draw(st.sampled_from(["", "08", "12"]))
    sentences = {
        "RMC": ("RMC", (hms, status, *ll, sog, cog, date, "", "", mode)),
        "GGA": ("GGA", (hms, *ll, q, sats, draw(st.sampled_from(["", "0.9"])), alt, "M", sep, "M", "", "")),
        "VTG": ("VTG", (cog, "T", "", "M", sog, "N", draw(st.sampled_from(["", "22.0"])), "K", mode)),
        "GSA": ("GSA", ("A", draw(st.sampled_from("123")), "04", "05", "", "", "", "", "", "", "", "", "", "",
                        "2.5", draw(st.sampled_from(["", "1.3"])), "2.1")),
    }
    first = draw(st.sampled_from(["RMC", "GGA"]))
    rest = draw(st.lists(st.sampled_from(["RMC", "GGA", "VTG", "GSA"]), max_size=4))
    return b"".join(_nmea(*sentences[k], talker) for k in [first, *rest])


@st.composite
def nav_pvt(draw: st.DrawFn) -> bytes:
    i4 = st.integers(-(2**31), 2**31 - 1)
    msg = UBXMessage(
        "NAV", "NAV-PVT", GET, iTOW=draw(st.integers(0, 604799999)), year=2026, month=11, day=28,
        hour=draw(st.integers(0, 23)), min=draw(st.integers(0, 59)), second=draw(st.integers(0, 60)),
        validDate=draw(st.integers(0, 1)), validTime=draw(st.integers(0, 1)),
        nano=draw(st.integers(-999_999_999, 999_999_999)), fixType=draw(st.integers(0, 5)),
        gnssFixOk=draw(st.integers(0, 1)), numSV=draw(st.integers(0, 255)),
        lat=draw(st.integers(-900_000_000, 900_000_000)) * 1e-7, lon=draw(st.integers(-1_800_000_000, 1_800_000_000)) * 1e-7,
        height=draw(i4), hMSL=draw(i4), hAcc=draw(st.integers(0, 2**32 - 1)), vAcc=draw(st.integers(0, 10**6)),
        velN=draw(i4), velE=draw(i4), velD=draw(i4), gSpeed=draw(st.integers(0, 2**31 - 1)),
        headMot=draw(st.integers(-36_000_000, 36_000_000)) * 1e-5, sAcc=draw(st.integers(0, 10**6)),
        pDOP=draw(st.integers(0, 65535)) * 0.01, invalidLlh=draw(st.integers(0, 1)))
    return msg.serialize()


@st.composite
def stream(draw: st.DrawFn) -> bytes:
    """Epochs with increasing times, NAV-PVT frames and other sentences between them."""
    parts: list[bytes] = []
    csec = draw(st.integers(0, 8_000_000))
    for _ in range(draw(st.integers(1, 5))):
        csec += draw(st.integers(1, 100))
        parts.append(draw(nmea_epoch(csec % 8_640_000)))
        parts += draw(st.lists(st.one_of(nav_pvt(), st.just(b"$GPGSV,1,1,01,04,45,123,40*4C\r\n")), max_size=2))
    return b"".join(parts)


@settings(max_examples=150, deadline=None)
@given(stream())
def test_generated_streams_match_the_packages(data: bytes) -> None:
    ref = gnss_reference.parse(data)
    assert_same(gnss.parse(data), ref)
    assert_same(gnss.parse(data, precision="f32"), ref, "f32")


def test_streaming_in_pieces_is_the_whole() -> None:
    second = [pynmea2.parse(ln) for ln in EXAMPLE.decode().split()]
    for m in second:
        if m.sentence_type in ("RMC", "GGA"):
            m.data[0] = "123520"  # the next epoch; str() writes its checksum
    data = EXAMPLE + "".join(f"{m}\r\n" for m in second).encode()
    p = gnss.Parser()
    got = [f for i in range(0, len(data), 7) for f in p.feed(data[i:i + 7])]
    last = p.flush()
    assert last is not None and p.flush() is None
    assert_same([*got, last], gnss.parse(data))
    assert p.stats["nmea_accepted"] == 8 and p.stats["bad_checksum"] == 0


def test_errors_are_counted_never_fixes() -> None:
    bad = EXAMPLE.replace(b"*6A", b"*6B")
    p = gnss.Parser()
    assert p.feed(bad) == [] and p.stats["bad_checksum"] == 1
    assert p.feed(b"$GP" + b"A" * 100 + b"\r\n") == [] and p.stats["overruns"] == 1
    with pytest.raises(InvalidType, match="data"):
        gnss.parse("$GPRMC")  # type: ignore[arg-type]


def test_to_array_marks_absent_fields() -> None:
    arr = gnss.to_array(gnss.parse(EXAMPLE))
    assert arr.shape == (1,) and np.isnan(arr["vel_d"][0]) and np.isnan(arr["tow"][0])
    assert arr["sats"][0] == 8 and arr["year"][0] == 1994
    assert arr["fix_type"][0] == names.C["ATT_GNSS_FIX_3D"]


GOOD = b"$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n"


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=300))
def test_never_stuck_after_garbage(garbage: bytes) -> None:
    """Whatever came before, a valid sentence after the documented resync distance
    (the longest UBX payload skipped + its header and checksum) is parsed."""
    resync = b"\x00" * (names.C["ATT_GNSS_UBX_SKIP_MAX"] + 8)
    p = gnss.Parser()
    p.feed(garbage + resync + GOOD)
    before = p.stats["nmea_accepted"]
    last = p.flush()
    assert last is not None and "GGA" in last.sources and last.sats == 8
    assert before >= 1
