"""GNSS logs read with the maintained packages: pynmea2 (NMEA 0183) and pyubx2 (UBX).

The independent reference of the library's own parser (:mod:`attitude_c.gnss`,
docs/gnss.md "Parser"): pyubx2's reader frames the mixed NMEA / UBX stream and
decodes NAV-PVT, pynmea2 decodes the sentences (and checks their checksums);
the epoch rule and the units are applied here from the documentation, not from
the C. Also a reader of real receiver logs where the packages' tolerance is
wanted (``pip install attitude-c[gnss]``).
"""

from __future__ import annotations

import io
import math
import os
from datetime import time
from typing import Any

from ..errors import InvalidType
from ..gnss import FIX_TYPES, GnssFix

__all__ = ["parse", "read"]

KNOT = 1852.0 / 3600.0  # m/s per knot (the international nautical mile)
KMH = 1.0 / 3.6  # m/s per km/h
_NMEA = ("RMC", "VTG", "GGA", "GSA")


def _packages() -> tuple[Any, Any]:
    try:
        import pynmea2
        import pyubx2
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise ImportError("attitude_c.reference.gnss needs pynmea2 and pyubx2: "
                          "pip install 'attitude-c[gnss]'") from exc
    return pynmea2, pyubx2


def _num(v: Any) -> float | None:
    return None if v in (None, "") else float(v)


def _tod(t: time) -> float:
    return t.hour * 3600.0 + t.minute * 60.0 + t.second + t.microsecond * 1e-6


def _course(deg: float | None) -> float | None:
    return None if deg is None else math.radians(deg) % (2.0 * math.pi)


def _rmc(m: Any) -> dict[str, Any]:
    d: dict[str, Any] = {"valid": m.status == "A" and getattr(m, "mode_indicator", "") != "N"}
    if m.lat:
        d.update(lat=math.radians(m.latitude), lon=math.radians(m.longitude))
    if m.spd_over_grnd is not None:
        d["speed"] = m.spd_over_grnd * KNOT
    if m.true_course is not None:
        d["track"] = _course(m.true_course)
    if m.datestamp:
        yy = m.datestamp.year % 100  # docs/gnss.md: yy 80..99 -> 19yy, else 20yy
        d["date"] = (yy + (1900 if yy >= 80 else 2000), m.datestamp.month, m.datestamp.day)
    if getattr(m, "mode_indicator", "") == "E":
        d["fix_type"] = "dr"
    return d


def _vtg(m: Any) -> dict[str, Any]:
    d: dict[str, Any] = {}
    if m.true_track is not None:
        d["track"] = _course(m.true_track)
    if m.spd_over_grnd_kts is not None:
        d["speed"] = float(m.spd_over_grnd_kts) * KNOT
    elif m.spd_over_grnd_kmph is not None:
        d["speed"] = m.spd_over_grnd_kmph * KMH
    if getattr(m, "faa_mode", "") == "N":
        d["valid"] = False
    return d


def _gga(m: Any) -> dict[str, Any]:
    d: dict[str, Any] = {}
    if m.lat:
        d.update(lat=math.radians(m.latitude), lon=math.radians(m.longitude))
    if m.num_sats:
        d["sats"] = int(float(m.num_sats))
    if m.horizontal_dil:
        d["hdop"] = float(m.horizontal_dil)
    if m.altitude is not None:
        d["height_msl"] = m.altitude
        if m.geo_sep:
            d["height"] = m.altitude + float(m.geo_sep)
    if m.gps_qual is not None:
        q = int(m.gps_qual)
        d["valid"] = q > 0
        if q in (0, 6):
            d["fix_type"] = "none" if q == 0 else "dr"
    return d


def _gsa(m: Any) -> dict[str, Any]:
    d: dict[str, Any] = {k: _num(getattr(m, k)) for k in ("pdop", "hdop", "vdop") if _num(getattr(m, k)) is not None}
    if m.mode_fix_type:
        d["fix_type"] = {"1": "none", "2": "2d", "3": "3d"}[m.mode_fix_type]
    return d


def _pvt(m: Any) -> GnssFix:
    d: dict[str, Any] = {k: None for k in GnssFix.__dataclass_fields__}
    d.update(tow=m.iTOW / 1000.0, fix_type=FIX_TYPES[m.fixType], valid=bool(m.gnssFixOk), sats=m.numSV,
             vel_n=m.velN / 1000.0, vel_e=m.velE / 1000.0, vel_d=m.velD / 1000.0, speed=m.gSpeed / 1000.0,
             track=_course(m.headMot), pdop=m.pDOP, h_acc=m.hAcc / 1000.0, v_acc=m.vAcc / 1000.0,
             s_acc=m.sAcc / 1000.0, sources=("PVT",))
    if m.validDate:
        d["date"] = (m.year, m.month, m.day)
    if m.validTime:
        d["tod"] = (m.hour * 3600.0 + m.min * 60.0 + m.second + m.nano * 1e-9) % 86400.0
    if not m.invalidLlh:
        d.update(lat=math.radians(m.lat), lon=math.radians(m.lon), height=m.height / 1000.0,
                 height_msl=m.hMSL / 1000.0)
    return GnssFix(**d)


class _Epoch:
    """The NMEA epoch being merged (docs/gnss.md: by UTC time, a later sentence wins)."""

    def __init__(self) -> None:
        self.vals: dict[str, Any] = {}
        self.time: time | None = None
        self.sources: list[str] = []

    def add(self, kind: str, d: dict[str, Any]) -> None:
        if "valid" in d and "valid" in self.vals:
            d["valid"] = d["valid"] and self.vals["valid"]
        self.vals.update(d)
        self.sources.append(kind)

    def fix(self) -> GnssFix:
        v = {k: None for k in GnssFix.__dataclass_fields__} | self.vals
        if v["speed"] is not None and (v["track"] is not None or v["speed"] == 0.0):
            track = v["track"] or 0.0
            v.update(vel_n=v["speed"] * math.cos(track), vel_e=v["speed"] * math.sin(track))
        v["sources"] = tuple(s for s in ("RMC", "VTG", "GGA", "GSA") if s in self.sources)
        return GnssFix(**v)


def parse(data: bytes) -> list[GnssFix]:
    """Every fix of a stream, read by pyubx2 + pynmea2 (bad checksums and other
    message types skipped; the last epoch closed at the end)."""
    if not isinstance(data, (bytes, bytearray)):
        raise InvalidType(f"data must be bytes, got {type(data).__name__}")
    pynmea2, pyubx2 = _packages()
    reader = pyubx2.UBXReader(io.BytesIO(bytes(data)), protfilter=pyubx2.NMEA_PROTOCOL | pyubx2.UBX_PROTOCOL,
                              quitonerror=pyubx2.ERR_IGNORE)
    out: list[GnssFix] = []
    ep: _Epoch | None = None
    for raw, msg in reader:
        if raw is None:
            continue
        if raw[:1] != b"$":
            if getattr(msg, "identity", "") == "NAV-PVT":
                out.append(_pvt(msg))
            continue
        try:
            m = pynmea2.parse(raw.decode("ascii").strip(), check=True)
        except (pynmea2.ParseError, UnicodeDecodeError, ValueError):
            continue
        kind = getattr(m, "sentence_type", "")
        if kind not in _NMEA:
            continue
        d = {"RMC": _rmc, "VTG": _vtg, "GGA": _gga, "GSA": _gsa}[kind](m)
        ts = getattr(m, "timestamp", None)
        if ts is not None and ep is not None and ep.time is not None and ts != ep.time:
            out.append(ep.fix())
            ep = None
        ep = ep or _Epoch()
        if ts is not None:
            ep.time = ep.time or ts
            d["tod"] = _tod(ts)
        ep.add(kind, d)
    if ep is not None:
        out.append(ep.fix())
    return out


def read(path: str | os.PathLike[str]) -> list[GnssFix]:
    """Every fix of a receiver log file, read with pyubx2 + pynmea2."""
    with open(path, "rb") as f:
        return parse(f.read())
