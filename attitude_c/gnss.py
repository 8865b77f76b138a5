"""GNSS receiver input: the library's own NMEA 0183 / UBX NAV-PVT parser.

Python side of ``csrc/include/attitude/gnss.h`` (docs/gnss.md, "Parser"):
RMC, VTG, GGA and GSA sentences of any talker, merged into one fix per
epoch by their UTC time, and UBX NAV-PVT frames, interleaved on one byte
stream. Units: angles in rad, lengths in m, speeds in m/s, times in s.

* :class:`Parser` — streaming: :meth:`Parser.feed` bytes as they arrive,
  get the fixes they complete; :meth:`Parser.flush` at the end;
* :func:`parse` — a whole stream (``bytes``) → list of :class:`GnssFix`;
* :func:`read` — a log file → list of :class:`GnssFix`;
* :func:`to_array` — fixes → a structured NumPy array (NaN where absent).

A quantity the receiver did not give in an epoch is ``None`` in
:class:`GnssFix` (the C ``present`` bits). ``attitude_c.reference.gnss``
reads the same streams with pynmea2 / pyubx2 (the differential tests).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from . import names
from ._lib import ffi_lib
from .errors import InvalidType
from .names import raise_for_status

__all__ = ["FIX_TYPES", "SOURCES", "FixType", "GnssFix", "Parser", "parse", "read", "to_array"]

FixType = Literal["none", "dr", "2d", "3d", "gnss+dr", "time"]
Precision = Literal["f64", "f32"]

#: fix_type code -> name (codes: attitude/gnss.h's att_gnss_fix_type)
_FIX_NAMES: tuple[tuple[str, FixType], ...] = (
    ("NONE", "none"), ("DR", "dr"), ("2D", "2d"), ("3D", "3d"), ("GNSS_DR", "gnss+dr"), ("TIME", "time"))
FIX_TYPES: dict[int, FixType] = {names.C[f"ATT_GNSS_FIX_{k}"]: v for k, v in _FIX_NAMES}
#: message names, in the order of the ATT_GNSS_SRC_ bits
SOURCES = ("RMC", "VTG", "GGA", "GSA", "PVT")

# presence bit (ATT_GNSS_HAS_<name>) -> the real fields it covers
_REALS = {"TOD": ("tod",), "TOW": ("tow",), "LATLON": ("lat", "lon"), "HEIGHT": ("height",),
          "HEIGHT_MSL": ("height_msl",), "VEL_NE": ("vel_n", "vel_e"), "VEL_D": ("vel_d",),
          "SPEED": ("speed",), "TRACK": ("track",), "HDOP": ("hdop",), "PDOP": ("pdop",), "VDOP": ("vdop",),
          "ACC": ("h_acc", "v_acc", "s_acc")}
_CHUNK = 256  # fixes per att_gnss_feed_buf call


@dataclass(frozen=True)
class GnssFix:
    """One epoch of the receiver (attitude/gnss.h's att_gnss_fix); None: not given."""

    tod: float | None  #: s, UTC time of day
    tow: float | None  #: s, GPS time of week (NAV-PVT)
    lat: float | None  #: rad, geodetic latitude
    lon: float | None  #: rad, longitude
    height: float | None  #: m above the WGS84 ellipsoid
    height_msl: float | None  #: m above mean sea level
    vel_n: float | None  #: m/s north
    vel_e: float | None  #: m/s east
    vel_d: float | None  #: m/s down (NAV-PVT only)
    speed: float | None  #: m/s, ground speed
    track: float | None  #: rad, course over ground from true north, 0..2π
    hdop: float | None
    pdop: float | None
    vdop: float | None
    h_acc: float | None  #: m (NAV-PVT)
    v_acc: float | None  #: m (NAV-PVT)
    s_acc: float | None  #: m/s (NAV-PVT)
    date: tuple[int, int, int] | None  #: UTC (year, month, day)
    fix_type: FixType | None
    valid: bool | None  #: the receiver flags the fix valid
    sats: int | None  #: satellites used
    sources: tuple[str, ...]  #: messages merged into the fix (names of SOURCES)


def _has(present: int, name: str) -> bool:
    return bool(present & names.C[f"ATT_GNSS_HAS_{name}"])


def _fix(c: Any) -> GnssFix:
    p = int(c.present)
    vals: dict[str, Any] = {}
    for bit, keys in _REALS.items():
        for k in keys:
            vals[k] = float(getattr(c, k)) if _has(p, bit) else None
    return GnssFix(**vals,
                   date=(int(c.year), int(c.month), int(c.day)) if _has(p, "DATE") else None,
                   fix_type=FIX_TYPES[int(c.fix_type)] if _has(p, "FIX_TYPE") else None,
                   valid=bool(c.valid) if _has(p, "VALID") else None,
                   sats=int(c.sats) if _has(p, "SATS") else None,
                   sources=tuple(s for i, s in enumerate(SOURCES) if c.sources >> i & 1))


class Parser:
    """A streaming parser (one att_gnss_parser); ``precision`` picks att_real."""

    def __init__(self, precision: Precision = "f64") -> None:
        self._ffi, self._lib = ffi_lib(precision)
        self._p = self._ffi.new("att_gnss_parser *")
        self._out = self._ffi.new("att_gnss_fix[]", _CHUNK)
        raise_for_status(self._lib.att_gnss_init(self._p), "gnss.Parser")

    def feed(self, data: bytes | bytearray | memoryview) -> list[GnssFix]:
        """Take ``data``; the fixes it completes, in stream order."""
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise InvalidType(f"data must be bytes, got {type(data).__name__}")
        buf = bytes(data)
        src = self._ffi.cast("const uint8_t *", self._ffi.from_buffer(buf))  # buf outlives the loop
        used, nfix = self._ffi.new("size_t *"), self._ffi.new("size_t *")
        out: list[GnssFix] = []
        pos = 0
        while pos < len(buf):
            st = self._lib.att_gnss_feed_buf(self._p, src + pos, len(buf) - pos, self._out, _CHUNK, used, nfix)
            raise_for_status(st, "gnss.Parser.feed")
            out.extend(_fix(self._out[i]) for i in range(nfix[0]))
            pos += used[0]
        return out

    def flush(self) -> GnssFix | None:
        """The NMEA epoch being merged, now (None if there is none)."""
        st = self._lib.att_gnss_flush(self._p, self._out)
        raise_for_status(st, "gnss.Parser.flush")
        return _fix(self._out[0]) if st == self._lib.ATT_GNSS_FIX else None

    @property
    def stats(self) -> dict[str, int]:
        """The C counters (att_gnss_stats), by field name."""
        s = self._p.stats
        return {name: int(getattr(s, name)) for name, _ in self._ffi.typeof("att_gnss_stats").fields}


def parse(data: bytes | bytearray | memoryview, *, precision: Precision = "f64") -> list[GnssFix]:
    """Every fix of a whole stream (the last NMEA epoch flushed at its end)."""
    p = Parser(precision)
    out = p.feed(data)
    last = p.flush()
    return out + ([last] if last is not None else [])


def read(path: str | os.PathLike[str], *, precision: Precision = "f64") -> list[GnssFix]:
    """Every fix of a receiver log file (NMEA, UBX or both, as recorded)."""
    with open(path, "rb") as f:
        return parse(f.read(), precision=precision)


_REAL_KEYS = [k for keys in _REALS.values() for k in keys]
#: the structured dtype of :func:`to_array`
DTYPE = np.dtype([*((k, np.float64) for k in _REAL_KEYS), ("year", np.int16), ("month", np.int8),
                  ("day", np.int8), ("fix_type", np.int8), ("valid", np.int8), ("sats", np.int16)])


def to_array(fixes: list[GnssFix]) -> NDArray[Any]:
    """Fixes as a structured array (dtype :data:`DTYPE`): NaN for an absent real,
    -1 for an absent integer (date, fix_type code, valid, sats)."""
    codes = {v: k for k, v in FIX_TYPES.items()}
    arr = np.empty(len(fixes), DTYPE)
    for i, f in enumerate(fixes):
        row: list[Any] = [np.nan if getattr(f, k) is None else getattr(f, k) for k in _REAL_KEYS]
        row += list(f.date) if f.date else [-1, -1, -1]
        row += [codes[f.fix_type] if f.fix_type else -1, -1 if f.valid is None else int(f.valid),
                -1 if f.sats is None else f.sats]
        arr[i] = tuple(row)
    return arr

