"""GNSS fixes (:data:`.gnss_model.FIX_DTYPE`) as a receiver's byte stream.

* NMEA 0183 (talker ``GN``, as a multi-constellation receiver): per epoch
  ``RMC``, ``VTG``, ``GGA``, ``GSA`` (the order of a u-blox M8), each
  ``$…*hh<CR><LF>`` with the XOR checksum of the characters between ``$`` and
  ``*`` and at most 82 characters (the standard's limit, checked). Resolution
  as a u-blox M8 writes it: time ``hhmmss.ss``, latitude ``ddmm.mmmmm``,
  longitude ``dddmm.mmmmm``, speed ``0.001`` kn / km/h, course ``0.01°``,
  DOP ``0.01``, altitude ``0.1 m``. No fix: status ``V``, mode ``N``,
  empty fields. The altitude above mean sea level equals the ellipsoidal
  height (geoid separation written as 0.0: an assumption of the model).
* UBX ``NAV-PVT`` (class 0x01, id 0x07, 92-byte payload, u-blox 8 protocol
  18+): ``B5 62``, class, id, length (U2 LE), payload, Fletcher-8 checksum
  over class … payload. Integer units: position 1e-7°, height and
  accuracies mm, velocities mm/s, heading 1e-5°, pDOP 0.01, ``iTOW`` ms
  of GPS time (UTC + 18 s, the leap seconds since 2017).

Both are time-ordered by ``t_delivered``; :func:`write_gnss_log` writes
a file complete or not at all (format from the suffix: ``.nmea``/``.ubx``).
"""

from __future__ import annotations

import datetime
import math
import os
import struct
from pathlib import Path
from typing import Any, Literal

import numpy as np

from .._io import atomic_open
from ..errors import InvalidArgument
from .gnss_model import DEFAULT_UTC_START

__all__ = ["GNSS_LOG_FORMATS", "KNOT_M_S", "NMEA_MAX_LEN", "fletcher8", "nmea_checksum", "nmea_epoch",
           "nmea_stream", "ubx_nav_pvt", "ubx_stream", "write_gnss_log"]

GnssLogFormat = Literal["nmea", "ubx"]
GNSS_LOG_FORMATS: tuple[GnssLogFormat, ...] = ("nmea", "ubx")
#: 1 knot in m/s (1852 m per hour, exact).
KNOT_M_S = 1852.0 / 3600.0
#: The longest NMEA 0183 sentence, "$" to <LF> included.
NMEA_MAX_LEN = 82
#: GPS − UTC (s) since 2017-01-01.
GPS_UTC_LEAP_S = 18
_GPS_EPOCH = datetime.datetime(1980, 1, 6, tzinfo=datetime.timezone.utc)
_WEEK_MS = 604_800_000


def nmea_checksum(body: str) -> int:
    """XOR of the characters between ``$`` and ``*``."""
    c = 0
    for ch in body.encode("ascii"):
        c ^= ch
    return c


def _sentence(body: str) -> str:
    s = f"${body}*{nmea_checksum(body):02X}\r\n"
    if len(s) > NMEA_MAX_LEN:  # pragma: no cover - the fields below cannot reach it
        raise InvalidArgument(f"NMEA sentence longer than {NMEA_MAX_LEN} characters: {s!r}")
    return s


def _utc(t: float, utc_start: datetime.datetime, unit_s: float) -> datetime.datetime:
    """The UTC time of t (s after utc_start), rounded to ``unit_s``."""
    return utc_start + datetime.timedelta(seconds=round(t / unit_s) * unit_s)


def _angle(value: float, deg_digits: int, hemis: str) -> str:
    """``ddmm.mmmmm,H`` (or ``dddmm.mmmmm``) rounded to 1e-5 minute."""
    units = round(abs(value) * 60 * 100_000)
    deg, rem = divmod(units, 60 * 100_000)
    return f"{deg:0{deg_digits}d}{rem // 100_000:02d}.{rem % 100_000:05d},{hemis[0] if value >= 0 else hemis[1]}"


def nmea_epoch(fix: Any, utc_start: datetime.datetime = DEFAULT_UTC_START) -> list[str]:
    """One epoch (a row of the fixes) as RMC, VTG, GGA and GSA sentences."""
    when = _utc(float(fix["t_measured"]), utc_start, 0.01)
    hms = when.strftime("%H%M%S") + f".{when.microsecond // 10_000:02d}"
    ok = int(fix["fix_type"]) >= 2
    pos = f"{_angle(float(fix['lat']), 2, 'NS')},{_angle(float(fix['lon']), 3, 'EW')}" if ok else ",,,"
    speed = float(fix["speed"])
    kn, kmh = (f"{speed / KNOT_M_S:.3f}", f"{speed * 3.6:.3f}") if ok else ("", "")
    cog, mode_ind = (f"{float(fix['track']):.2f}", "A") if ok else ("", "N")
    rmc = f"GNRMC,{hms},{'A' if ok else 'V'},{pos},{kn},{cog},{when:%d%m%y},,,{mode_ind}"
    vtg = f"GNVTG,{cog},T,,M,{kn},N,{kmh},K,{mode_ind}"
    alt = f"{float(fix['h']):.1f},M,0.0,M" if ok else ",,,"
    gga = f"GNGGA,{hms},{pos},{1 if ok else 0},{int(fix['nsat']):02d},{float(fix['hdop']):.2f},{alt},,"
    pdop, hdop = float(fix["pdop"]), float(fix["hdop"])
    vdop = math.sqrt(max(pdop * pdop - hdop * hdop, 0.0))
    sats = [f"{k:02d}" if ok and k <= int(fix["nsat"]) else "" for k in range(1, 13)]
    mode = {0: 1, 2: 2, 3: 3}.get(int(fix["fix_type"]), 1)
    gsa = f"GNGSA,A,{mode},{','.join(sats)},{pdop:.2f},{hdop:.2f},{vdop:.2f}"
    return [_sentence(b) for b in (rmc, vtg, gga, gsa)]


def _order(fixes: np.ndarray) -> np.ndarray:
    return fixes[np.argsort(fixes["t_delivered"], kind="stable")]


def nmea_stream(fixes: np.ndarray, utc_start: datetime.datetime = DEFAULT_UTC_START) -> bytes:
    """Every epoch's sentences in delivery order (ASCII bytes)."""
    return "".join(s for f in _order(fixes) for s in nmea_epoch(f, utc_start)).encode("ascii")


def fletcher8(data: bytes) -> bytes:
    """The UBX checksum (8-bit Fletcher: CK_A, CK_B) of class … payload."""
    a = b = 0
    for x in data:
        a = (a + x) & 0xFF
        b = (b + a) & 0xFF
    return bytes((a, b))


_PVT = struct.Struct("<IHBBBBBBIiBBBBiiiiIIiiiiiIIHHIihH")  # 92 bytes: UBX-NAV-PVT
_NO_ACC = 0xFFFF_FFFF


def _mm(x: float) -> int:
    return round(x * 1000.0)


def _pvt_solution(fix: Any) -> tuple[int, ...]:
    """lon, lat, height, hMSL, hAcc, vAcc, velN, velE, velD, gSpeed, headMot, sAcc, headAcc
    in NAV-PVT's integer units (no fix: zeros and the largest accuracies)."""
    if int(fix["fix_type"]) < 2:
        return (0, 0, 0, 0, _NO_ACC, _NO_ACC, 0, 0, 0, 0, 0, _NO_ACC, 180 * 100_000)
    speed = float(fix["speed"])
    head_acc = min(math.degrees(float(fix["s_acc"]) / speed), 180.0) if speed > 0 else 180.0
    h = _mm(float(fix["h"]))
    return (round(float(fix["lon"]) * 1e7), round(float(fix["lat"]) * 1e7), h, h, _mm(float(fix["h_acc"])),
            _mm(float(fix["v_acc"])), _mm(float(fix["vn"])), _mm(float(fix["ve"])), _mm(float(fix["vd"])),
            _mm(speed), round(float(fix["track"]) * 1e5), _mm(float(fix["s_acc"])), round(head_acc * 1e5))


def ubx_nav_pvt(fix: Any, utc_start: datetime.datetime = DEFAULT_UTC_START) -> bytes:
    """One epoch as a UBX-NAV-PVT frame (100 bytes: 6 header, 92 payload, 2 checksum)."""
    when = _utc(float(fix["t_measured"]), utc_start, 0.001)
    gps_ms = round((when - _GPS_EPOCH).total_seconds() * 1000) + GPS_UTC_LEAP_S * 1000
    ok = int(fix["fix_type"]) >= 2
    payload = _PVT.pack(
        gps_ms % _WEEK_MS, when.year, when.month, when.day, when.hour, when.minute, when.second, 0x07, 50,
        when.microsecond * 1000, int(fix["fix_type"]), 0x01 if ok else 0x00, 0, int(fix["nsat"]),
        *_pvt_solution(fix), round(float(fix["pdop"]) * 100), 0 if ok else 1, 0, 0, 0, 0)
    body = bytes((0x01, 0x07)) + struct.pack("<H", len(payload)) + payload
    return b"\xb5\x62" + body + fletcher8(body)


def ubx_stream(fixes: np.ndarray, utc_start: datetime.datetime = DEFAULT_UTC_START) -> bytes:
    """Every epoch's NAV-PVT frame in delivery order."""
    return b"".join(ubx_nav_pvt(f, utc_start) for f in _order(fixes))


def log_format(path: str | os.PathLike[str]) -> GnssLogFormat:
    """The format a log file's suffix names (``.nmea`` or ``.ubx``)."""
    suffix = Path(path).suffix.lower().lstrip(".")
    if suffix not in GNSS_LOG_FORMATS:
        raise InvalidArgument(f"GNSS log {os.fspath(path)!r}: name it *.nmea or *.ubx (the format comes from the "
                              "suffix)")
    return suffix  # type: ignore[return-value]


def write_gnss_log(path: str | os.PathLike[str], fixes: np.ndarray,
                   utc_start: datetime.datetime = DEFAULT_UTC_START) -> Path:
    """Write the fixes as an NMEA (``*.nmea``) or UBX (``*.ubx``) log, complete or not at all."""
    fmt = log_format(path)
    data = nmea_stream(fixes, utc_start) if fmt == "nmea" else ubx_stream(fixes, utc_start)
    with atomic_open(path, "wb") as fh:
        fh.write(data)
    return Path(path)
