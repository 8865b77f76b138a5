"""WGS-84 geodetic coordinates and a local tangent plane (ENU), in closed form.

* :func:`geodetic_to_ecef`: ``X = (N + h) cos φ cos λ``, ``Y = (N + h) cos φ sin λ``,
  ``Z = (N (1 − e²) + h) sin φ`` with ``N = a / √(1 − e² sin² φ)``;
* :func:`ecef_to_geodetic`: Heikkinen's closed form (M. Heikkinen, "Geschlossene
  Formeln zur Berechnung räumlicher geodätischer Koordinaten aus rechtwinkligen
  Koordinaten", Z. Vermess. 107, 1982; as given by J. Zhu, "Conversion of
  Earth-centered Earth-fixed coordinates to geodetic coordinates", IEEE Trans.
  AES 30(3), 1994): no iteration, sub-millimetre from the Earth's centre region
  outwards;
* :func:`enu_to_geodetic` / :func:`geodetic_to_enu`: the tangent plane at an
  origin ``(φ₀, λ₀, h₀)``: ``x_ecef = x₀ + R(φ₀, λ₀) [e, n, u]`` with the columns of
  ``R`` east, north and up at the origin.

Angles in degrees (as receivers write them), heights in metres above the
ellipsoid, ENU in metres. Constants: WGS-84 (NIMA TR8350.2): a = 6378137 m,
f = 1/298.257223563.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["WGS84_A", "WGS84_F", "ecef_to_geodetic", "enu_to_geodetic", "geodetic_to_ecef", "geodetic_to_enu"]

WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563
_E2 = WGS84_F * (2.0 - WGS84_F)
_B = WGS84_A * (1.0 - WGS84_F)
_EP2 = _E2 / (1.0 - _E2)


def geodetic_to_ecef(lat: Any, lon: Any, h: Any) -> np.ndarray:
    """(…, 3) ECEF (m) of latitude, longitude (deg) and height (m)."""
    phi, lam = np.radians(lat), np.radians(lon)
    h = np.asarray(h, dtype=float)
    n = WGS84_A / np.sqrt(1.0 - _E2 * np.sin(phi) ** 2)
    return np.stack([(n + h) * np.cos(phi) * np.cos(lam), (n + h) * np.cos(phi) * np.sin(lam),
                     (n * (1.0 - _E2) + h) * np.sin(phi)], axis=-1)


def ecef_to_geodetic(xyz: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Latitude, longitude (deg) and height (m) of ECEF points (…, 3) (Heikkinen)."""
    xyz = np.asarray(xyz, dtype=float)
    x, y, z = xyz[..., 0], xyz[..., 1], xyz[..., 2]
    r = np.hypot(x, y)
    f = 54.0 * _B * _B * z * z
    g = r * r + (1.0 - _E2) * z * z - _E2 * (WGS84_A ** 2 - _B ** 2)
    c = _E2 * _E2 * f * r * r / g ** 3
    s = np.cbrt(1.0 + c + np.sqrt(c * c + 2.0 * c))
    p = f / (3.0 * (s + 1.0 / s + 1.0) ** 2 * g * g)
    q = np.sqrt(1.0 + 2.0 * _E2 * _E2 * p)
    r0 = -p * _E2 * r / (1.0 + q) + np.sqrt(np.maximum(
        0.5 * WGS84_A ** 2 * (1.0 + 1.0 / q) - p * (1.0 - _E2) * z * z / (q * (1.0 + q)) - 0.5 * p * r * r, 0.0))
    u = np.hypot(r - _E2 * r0, z)
    v = np.sqrt((r - _E2 * r0) ** 2 + (1.0 - _E2) * z * z)
    z0 = _B * _B * z / (WGS84_A * v)
    h = u * (1.0 - _B * _B / (WGS84_A * v))
    lat = np.degrees(np.arctan2(z + _EP2 * z0, r))
    return lat, np.degrees(np.arctan2(y, x)), h


def _enu_axes(lat0: float, lon0: float) -> np.ndarray:
    """(3, 3): columns east, north, up at (lat0, lon0), in ECEF."""
    p, lam = np.radians(lat0), np.radians(lon0)
    sp, cp, sl, cl = np.sin(p), np.cos(p), np.sin(lam), np.cos(lam)
    return np.array([[-sl, -sp * cl, cp * cl], [cl, -sp * sl, cp * sl], [0.0, cp, sp]])


def enu_to_geodetic(enu: Any, lat0: float, lon0: float, h0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Latitude, longitude (deg), height (m) of ENU points (…, 3) (m) about an origin."""
    x = geodetic_to_ecef(lat0, lon0, h0) + np.asarray(enu, dtype=float) @ _enu_axes(lat0, lon0).T
    return ecef_to_geodetic(x)


def geodetic_to_enu(lat: Any, lon: Any, h: Any, lat0: float, lon0: float, h0: float) -> np.ndarray:
    """ENU (…, 3) (m) of geodetic points about an origin (the inverse of :func:`enu_to_geodetic`)."""
    d = geodetic_to_ecef(lat, lon, h) - geodetic_to_ecef(lat0, lon0, h0)
    return d @ _enu_axes(lat0, lon0)
