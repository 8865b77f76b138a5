"""A GNSS receiver model: the fixes a receiver on a simulated vehicle delivers.

:class:`GnssModel` is the part (rate, velocity and position noise, latency,
nominal DOP and satellites; :data:`GNSS_PRESETS`, each figure tagged
datasheet or assumption); :class:`GnssReceiver` places it in a run (the
geodetic origin of the ENU frame, the UTC time of t = 0, outages,
fix-quality changes and bad fixes). :meth:`GnssReceiver.fixes` gives a
structured array (:data:`FIX_DTYPE`), one row per measurement epoch
``t_measured = k / rate``:

* the fix is of the truth at ``t_measured`` (position ``traj.position``,
  velocity ``traj.velocity``) plus the noise, and reaches the user at
  ``t_delivered = t_measured + latency``;
* velocity noise: white, ``vel_sigma`` per horizontal axis and
  ``vel_sigma_up`` vertically, plus an optional first-order Gauss–Markov
  part (``vel_gm_sigma``, ``vel_gm_tau``); position noise: Gauss–Markov
  (``pos_sigma``, ``pos_sigma_up``, ``pos_tau``) -- all scaled by
  ``hdop / model.hdop`` while a :class:`Quality` window degrades the fix;
* an outage (``outages``) keeps the epochs but without a fix
  (``fix_type`` 0, the measured fields NaN -- the receiver keeps talking, as
  real ones do); a 2-D fix (``fix_type`` 2) reports ``vd = 0`` and holds the
  height of the last 3-D fix; a :class:`BadFix` adds a velocity jump the
  receiver does not flag (still a 3-D fix).

Velocities are NED (``vn``, ``ve``, ``vd``), as receivers give them; the ENU
of the simulator is ``[ve, vn, −vd]``. ``speed`` is the ground speed (m/s)
and ``track`` the course over ground (deg from true north, [0, 360)).
"""

from __future__ import annotations

import datetime
import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..errors import InvalidArgument
from .accelmag import markov
from .geodetic import enu_to_geodetic
from .trajectory import Trajectory

__all__ = ["FIX_DTYPE", "GNSS_PRESETS", "BadFix", "GnssModel", "GnssReceiver", "Quality", "gnss_preset"]

#: One row per measurement epoch (units: s, deg, m, m/s; fix_type as UBX NAV-PVT:
#: 0 no fix, 2 2-D, 3 3-D). h_acc, v_acc, s_acc: the receiver's 1-σ estimates
#: (horizontal and vertical position, m; speed, m/s).
FIX_DTYPE = np.dtype([("t_measured", "f8"), ("t_delivered", "f8"), ("fix_type", "u1"), ("lat", "f8"),
                      ("lon", "f8"), ("h", "f8"), ("vn", "f8"), ("ve", "f8"), ("vd", "f8"), ("speed", "f8"),
                      ("track", "f8"), ("hdop", "f8"), ("pdop", "f8"), ("nsat", "u1"), ("h_acc", "f8"),
                      ("v_acc", "f8"), ("s_acc", "f8")])

#: The origin of the ENU frame when none is given: Nanjing (the UAV thesis's site, as
#: the default geomagnetic field), 32.06° N, 118.80° E, 10 m above the ellipsoid: an assumption.
DEFAULT_ORIGIN = (32.06, 118.80, 10.0)
#: The UTC time of t = 0 when none is given (an arbitrary date after the last leap second).
DEFAULT_UTC_START = datetime.datetime(2026, 1, 1, 12, 0, 0, tzinfo=datetime.timezone.utc)

# the UTC time stamp of the fixes is resolved to 1 ms (UBX iTOW)
_MAX_RATE_HZ = 10.0
_MIN_RATE_HZ = 1.0


@dataclass(frozen=True)
class GnssModel:
    """A GNSS receiver part (units in the names; sigmas 1-σ per axis)."""

    name: str
    rate_hz: float
    vel_sigma: float
    vel_sigma_up: float
    pos_sigma: float
    pos_sigma_up: float
    latency_s: float
    hdop: float
    pdop: float
    nsat: int
    pos_tau: float = 60.0
    vel_gm_sigma: float = 0.0
    vel_gm_tau: float = 10.0
    sources: dict[str, str] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if not _MIN_RATE_HZ <= self.rate_hz <= _MAX_RATE_HZ:
            raise InvalidArgument(f"gnss rate must be within {_MIN_RATE_HZ:g}..{_MAX_RATE_HZ:g} Hz, "
                                  f"got {self.rate_hz!r}")
        for nm in ("vel_sigma", "vel_sigma_up", "pos_sigma", "pos_sigma_up", "latency_s", "vel_gm_sigma"):
            v = getattr(self, nm)
            if not (math.isfinite(v) and v >= 0):
                raise InvalidArgument(f"gnss {nm} must be a finite number >= 0, got {v!r}")
        if not (self.pos_tau > 0 and self.vel_gm_tau > 0 and self.hdop > 0 and self.pdop >= self.hdop):
            raise InvalidArgument("gnss pos_tau, vel_gm_tau, hdop must be > 0 and pdop >= hdop")
        if not 4 <= self.nsat <= 99:
            raise InvalidArgument(f"gnss nsat must be within 4..99 for a 3-D fix, got {self.nsat!r}")


_CEP = math.sqrt(2 * math.log(2))  # a 2-D circular Gaussian's 50 % radius in units of its per-axis σ (1.1774)

GNSS_PRESETS: dict[str, GnssModel] = {
    # u-blox NEO-M8N (M8 engine). Data-sheet figures: velocity accuracy 0.05 m/s and heading accuracy 0.3°,
    # horizontal position 2.5 m CEP, navigation update rate up to 10 Hz with GPS+GLONASS (seen in a copy of the
    # u-blox M8 module figures, MAX-M8Q spec sheet; the NEO-M8 data sheet UBX-15031086 gives the same family
    # figures -- "50 % at 30 m/s" for the velocity: datasheet†). 50 % figures to 1-σ per axis: / 1.1774.
    "neo-m8n": GnssModel(
        "neo-m8n", rate_hz=5.0, vel_sigma=0.05 / _CEP, vel_sigma_up=1.5 * 0.05 / _CEP, pos_sigma=2.5 / _CEP,
        pos_sigma_up=1.5 * 2.5 / _CEP, latency_s=0.1, hdop=0.9, pdop=1.6, nsat=14,
        sources={"vel_sigma": "datasheet: 0.05 m/s (50 %) / 1.1774", "pos_sigma": "datasheet: 2.5 m CEP / 1.1774",
                 "rate_hz": "assumption: 5 Hz configured (datasheet: 1 Hz default, up to 10 Hz GPS+GLONASS)",
                 "vel_sigma_up": "assumption: 1.5 x horizontal (VDOP > HDOP)",
                 "pos_sigma_up": "assumption: 1.5 x horizontal", "pos_tau": "assumption: 60 s correlation",
                 "latency_s": "assumption: 0.1 s from measurement to the message's last byte",
                 "hdop": "assumption: 0.9, pdop 1.6, 14 satellites (open sky, two constellations)"}),
    # A receiver in poor conditions (trees, buildings): every figure an ASSUMPTION.
    "degraded": GnssModel(
        "degraded", rate_hz=1.0, vel_sigma=0.2, vel_sigma_up=0.3, pos_sigma=5.0, pos_sigma_up=8.0, latency_s=0.25,
        hdop=2.0, pdop=3.5, nsat=7, vel_gm_sigma=0.1, vel_gm_tau=20.0,
        sources={"all": "assumption: a receiver under foliage or in a street canyon"}),
    # A perfect receiver at 10 Hz, no latency: algorithm studies.
    "ideal": GnssModel("ideal", rate_hz=10.0, vel_sigma=0.0, vel_sigma_up=0.0, pos_sigma=0.0, pos_sigma_up=0.0,
                       latency_s=0.0, hdop=0.5, pdop=1.0, nsat=20, sources={"all": "ideal"}),
}


def gnss_preset(name: str) -> GnssModel:
    try:
        return GNSS_PRESETS[name]
    except KeyError:
        raise InvalidArgument(f"gnss must be one of {sorted(GNSS_PRESETS)}, got {name!r}") from None


def _window(start: float, end: float, what: str) -> None:
    if not (math.isfinite(start) and math.isfinite(end) and 0 <= start < end):
        raise InvalidArgument(f"{what} needs 0 <= START < END (s), got {start!r}, {end!r}")


@dataclass(frozen=True)
class Quality:
    """From ``start`` to ``end`` (s) the fix is of ``fix_type`` (2 or 3) with ``nsat``
    satellites and ``hdop``, ``pdop`` (the noise scales with hdop / the model's)."""

    start: float
    end: float
    fix_type: int = 3
    nsat: int = 5
    hdop: float = 3.0
    pdop: float = 5.0

    def __post_init__(self) -> None:
        _window(self.start, self.end, "a fix-quality window")
        if self.fix_type not in (2, 3) or not 3 <= self.nsat <= 99 or not 0 < self.hdop <= self.pdop:
            raise InvalidArgument(f"fix quality: fix_type 2 or 3, nsat 3..99, 0 < hdop <= pdop, got {self!r}")


@dataclass(frozen=True)
class BadFix:
    """From ``start`` to ``end`` (s) the velocity is off by ``dv`` (m/s, ENU), unflagged."""

    start: float
    end: float
    dv: tuple[float, float, float]

    def __post_init__(self) -> None:
        _window(self.start, self.end, "a bad fix")
        if len(self.dv) != 3 or not all(math.isfinite(v) for v in self.dv):
            raise InvalidArgument(f"a bad fix's dv must be 3 finite values (m/s, ENU), got {self.dv!r}")


@dataclass(frozen=True)
class GnssReceiver:
    """A :class:`GnssModel` in a run (module doc). ``origin``: latitude, longitude
    (deg) and height (m, ellipsoid) of the ENU frame's origin; ``utc_start``: the
    UTC time of t = 0; ``outages``: (start, end) windows in s with no fix."""

    model: GnssModel = field(default_factory=lambda: gnss_preset("neo-m8n"))
    origin: tuple[float, float, float] = DEFAULT_ORIGIN
    utc_start: datetime.datetime = DEFAULT_UTC_START
    outages: tuple[tuple[float, float], ...] = ()
    quality: tuple[Quality, ...] = ()
    bad_fixes: tuple[BadFix, ...] = ()

    def __post_init__(self) -> None:
        for a, b in self.outages:
            _window(a, b, "an outage")
        lat, lon, h = self.origin
        if not (abs(lat) < 90 and abs(lon) <= 180 and math.isfinite(h)):
            raise InvalidArgument(f"gnss origin: |lat| < 90°, |lon| <= 180°, finite h, got {self.origin!r}")
        if self.utc_start.tzinfo is None:
            raise InvalidArgument("gnss utc_start must carry a time zone (UTC)")

    def with_rate(self, rate_hz: float) -> GnssReceiver:
        return replace(self, model=replace(self.model, rate_hz=rate_hz))

    def fixes(self, traj: Trajectory, duration: float, seed: int = 0) -> np.ndarray:
        """The fixes of a run of ``duration`` s (module doc), noise from ``seed``."""
        m = self.model
        t = np.arange(0.0, duration + 1e-9, 1.0 / m.rate_hz)
        rng = np.random.default_rng(np.random.SeedSequence([seed, 0x474E5353]))  # "GNSS": its own stream
        out = np.zeros(len(t), dtype=FIX_DTYPE)
        out["t_measured"], out["t_delivered"] = t, t + m.latency_s
        fix, nsat, hdop, pdop = self._quality(t)
        scale = hdop / m.hdop
        up = np.array([1.0, 1.0, 0.0])
        v_noise = rng.standard_normal((len(t), 3)) * np.where(up, m.vel_sigma, m.vel_sigma_up)
        v_noise += markov(len(t), 1.0 / m.rate_hz, m.vel_gm_sigma, m.vel_gm_tau, rng)
        p_noise = markov(len(t), 1.0 / m.rate_hz, 1.0, m.pos_tau, rng) * np.where(up, m.pos_sigma, m.pos_sigma_up)
        vel = traj.velocity(t) + v_noise * scale[:, None] + self._jumps(t)
        pos = traj.position(t) + p_noise * scale[:, None]
        self._two_d(fix, vel, pos)
        lat, lon, h = enu_to_geodetic(pos, *self.origin)
        out["lat"], out["lon"], out["h"] = lat, lon, h
        out["vn"], out["ve"], out["vd"] = vel[:, 1], vel[:, 0], -vel[:, 2]
        out["speed"] = np.hypot(vel[:, 0], vel[:, 1])
        out["track"] = np.mod(np.degrees(np.arctan2(vel[:, 0], vel[:, 1])), 360.0)
        out["hdop"], out["pdop"], out["nsat"], out["fix_type"] = hdop, pdop, nsat, fix
        out["h_acc"], out["v_acc"] = m.pos_sigma * scale, m.pos_sigma_up * scale
        out["s_acc"] = m.vel_sigma * scale
        for name in ("lat", "lon", "h", "vn", "ve", "vd", "speed", "track", "h_acc", "v_acc", "s_acc"):
            out[name][fix == 0] = np.nan
        return out

    def _quality(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        m = self.model
        fix, nsat = np.full(len(t), 3, np.uint8), np.full(len(t), m.nsat, np.uint8)
        hdop, pdop = np.full(len(t), m.hdop), np.full(len(t), m.pdop)
        for q in self.quality:
            w = (t >= q.start) & (t < q.end)
            fix[w], nsat[w], hdop[w], pdop[w] = q.fix_type, q.nsat, q.hdop, q.pdop
        for a, b in self.outages:
            w = (t >= a) & (t < b)
            fix[w], nsat[w] = 0, 0
        hdop[fix == 0], pdop[fix == 0] = 99.99, 99.99  # what u-blox receivers report without a fix
        return fix, nsat, hdop, pdop

    def _jumps(self, t: np.ndarray) -> np.ndarray:
        out = np.zeros((len(t), 3))
        for b in self.bad_fixes:
            out[(t >= b.start) & (t < b.end)] += b.dv
        return out

    @staticmethod
    def _two_d(fix: np.ndarray, vel: np.ndarray, pos: np.ndarray) -> None:
        """A 2-D fix: no vertical velocity, the height of the last 3-D fix (the first fix's if none)."""
        held = pos[0, 2]
        for k in range(len(fix)):  # a plain loop: a few 10^4 epochs at most
            if fix[k] == 3:
                held = pos[k, 2]
            elif fix[k] == 2:
                vel[k, 2], pos[k, 2] = 0.0, held

    def to_dict(self) -> dict[str, Any]:
        return {"model": self.model.name, "rate_hz": self.model.rate_hz, "latency_s": self.model.latency_s,
                "origin": list(self.origin), "utc_start": self.utc_start.isoformat(),
                "outages": [list(w) for w in self.outages], "quality": [vars(q) for q in self.quality],
                "bad_fixes": [vars(b) for b in self.bad_fixes]}
