"""Public recordings with an IMU, GNSS velocities and a reference attitude (issue 30): the
flight and car logs that the PyPI package ``onavdata`` (Organic Navigation, version 0.2.5)
ships as zipped CSV files, read here straight from its data folder (``onavdata`` itself is
not imported: it needs pandas and idelib), in the library's conventions
(docs/conventions.md): body x right, y forward, z up; ENU; quaternions body -> ENU.

Two kinds (docs/gnss.md, "Public recordings with GNSS"):

* ``umn-uav``: seven University of Minnesota UAV flights (Thor, FASER, GPSFASER; 2011-2012):
  accelerometer, gyro and magnetometer at 50 Hz, GPS velocity (1 Hz fixes held at 50 Hz in
  the files), and the attitude of the aircraft's own GPS/INS navigation filter (same IMU and
  GPS), aerospace yaw-pitch-roll of a forward-right-down body.
* ``hguide-n380``: two car drives with a Honeywell HGuide n380 (2021): angle and velocity
  increments at 100 Hz, GNSS PVT at 1 Hz with the receiver's velocity sigmas, and the
  n380's INS attitude with its own 1-sigma (rows in navigation mode, ``InsMode`` 4; other
  rows have no reference: NaN).

The reference attitudes are the units' own GNSS/INS solutions from the same IMU, not an
independent (optical) truth. The data's licence is not stated by the package.
"""

from __future__ import annotations

import importlib.util
import io
import math
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from .errors import InvalidArgument
from .frames import axes_matrix

__all__ = ["RECORDINGS", "OnavRecording", "default_dir", "load", "summary"]

FloatArray = NDArray[np.float64]
Kind = Literal["umn-uav", "hguide-n380"]

_UMN = "2014-09-09 UofMN Conservancy 7 UAV Flights/Processed and Parsed Data/"
_N380 = "HGuide n380/"
#: The recordings by short name: their kind and folder under onavdata's ``data`` folder.
RECORDINGS: dict[str, tuple[Kind, str]] = {
    **{f"umn-{f.split('-Flight-')[0].lower()}{f.split('-Flight-')[1]}": ("umn-uav", _UMN + f)
       for f in ("THOR-Flight-60", "THOR-Flight-75", "THOR-Flight-77", "THOR-Flight-79", "FASER-Flight-5",
                 "GPSFASER-Flight-1", "GPSFASER-Flight-3")},
    "n380-stoplights": ("hguide-n380", _N380 + "2021-03-29-automotive-stoplight-to-stoplight"),
    "n380-hill": ("hguide-n380", _N380 + "2021-04-27C-car-hill-drive"),
}

#: v_rfu = _FRD v_frd (x forward, y right, z down -> x right, y forward, z up).
_FRD = axes_matrix("frd")
#: The n380's IMU axes to its case's forward-right-down axes (onavdata's n380-meta.toml, Rsensor2body).
_N380_SENSOR_TO_FRD = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
#: The n380's increments are per IMU sample of 1/100 s (n380-meta.toml: "assumes 100 Hz").
_N380_RATE_HZ = 100.0
#: The n380's navigation mode (n380-meta.toml keeps the rows with InsGnssBIT.InsMode = 4).
_N380_NAV_MODE = 4
#: Rows of two n380 files are the same epoch when their SystemTov differ by less than this
#: (s): n380-meta.toml rounds SystemTov to 0.01 s to align them.
_N380_MATCH_S = 0.004


@dataclass(frozen=True)
class OnavRecording:
    """One recording in the library's frames (module doc); ``n`` IMU samples, ``m`` GNSS velocities."""

    name: str
    kind: Kind
    t: FloatArray                 #: (n,) s, the recording's clock
    gyr: FloatArray               #: (n, 3) rad/s, body (x right, y forward, z up)
    acc: FloatArray               #: (n, 3) m/s², specific force, body
    mag: FloatArray | None        #: (n, 3) gauss, body (umn-uav only)
    q_ref: FloatArray             #: (n, 4) reference attitude body -> ENU, scalar first; NaN: none
    ref_sigma: FloatArray | None  #: (n, 3) rad, 1σ of the reference's roll, pitch, heading (hguide-n380)
    gnss_t: FloatArray            #: (m,) s, on the same clock
    gnss_vel: FloatArray          #: (m, 3) m/s, ENU
    gnss_sigma: FloatArray | None  #: (m, 3) m/s, 1σ of each component, ENU (hguide-n380)

    @property
    def rate(self) -> float:
        """The IMU's sampling rate (Hz): the median interval's inverse."""
        return float(1.0 / np.median(np.diff(self.t)))


def default_dir() -> Path | None:
    """The ``data`` folder of an installed ``onavdata`` (found, not imported), or None."""
    spec = importlib.util.find_spec("onavdata")
    if spec is None or spec.origin is None:
        return None
    d = Path(spec.origin).parent / "data"
    return d if d.is_dir() else None


def _read(path: Path) -> dict[str, FloatArray]:
    """A zipped CSV (one member, a header line) as columns of floats by name (NaN where empty)."""
    try:
        with zipfile.ZipFile(path) as z:
            text = z.read(z.namelist()[0]).decode("utf-8")
    except (OSError, zipfile.BadZipFile, IndexError, UnicodeDecodeError) as exc:
        raise InvalidArgument(f"onav: cannot read {str(path)!r}: {exc}") from None
    head, _, body = text.partition("\n")
    names = [h.strip() for h in head.split(",")]
    try:  # an empty field (a missing value) is NaN
        a = np.atleast_2d(np.genfromtxt(io.StringIO(body), delimiter=",", dtype=np.float64))
    except ValueError as exc:
        raise InvalidArgument(f"onav: {str(path)!r}: {exc}") from None
    if a.shape[1] != len(names):
        raise InvalidArgument(f"onav: {str(path)!r}: {a.shape[1]} columns under a header of {len(names)}")
    return {k: a[:, i] for i, k in enumerate(names)}


def _quat_aerospace(heading: FloatArray, pitch: FloatArray, roll: FloatArray) -> FloatArray:
    """Aerospace z-y-x angles of a forward-right-down body in NED as the library's quaternions:
    its pitch and roll, and yaw = -heading (docs/conventions.md, "Aerospace yaw-pitch-roll")."""
    from .core import euler_to_quat

    e = np.stack([-heading, pitch, roll], axis=1)
    q = np.full((len(e), 4), np.nan)
    ok = np.isfinite(e).all(axis=1)
    if ok.any():
        q[ok] = euler_to_quat(e[ok])
    return q


def _columns(c: dict[str, FloatArray], names: list[str], rot: FloatArray, scale: float = 1.0) -> FloatArray:
    """Three columns as vectors (n, 3), turned by ``rot`` (v_out = rot v) and scaled."""
    return np.stack([c[k] for k in names], axis=1) @ rot.T * scale


def _nearest(ta: FloatArray, t: FloatArray, tol: float) -> tuple[NDArray[np.intp], NDArray[np.bool_]]:
    """For each time of ``t``, the index of the nearest of the sorted times ``ta`` and whether it
    is within ``tol``."""
    if len(ta) == 0:
        return np.zeros(len(t), np.intp), np.zeros(len(t), bool)
    j = np.clip(np.searchsorted(ta, t), 1, len(ta) - 1) if len(ta) > 1 else np.zeros(len(t), np.intp)
    if len(ta) > 1:
        j = np.where(np.abs(ta[j - 1] - t) < np.abs(ta[j] - t), j - 1, j)
    return j, np.abs(ta[j] - t) < tol


def _ned_to_enu(n: FloatArray, e: FloatArray, d: FloatArray) -> FloatArray:
    return np.stack([e, n, -d], axis=1)


def _umn(name: str, folder: Path) -> OnavRecording:
    acc, gyr, mag = (_read(folder / f"{k}_data.txt.zip") for k in ("accel", "gyro", "mag"))
    att, gv = _read(folder / "nav_attitude_data.txt.zip"), _read(folder / "gps_velocity_data.txt.zip")
    t = acc["time"]
    for what, cols in (("gyro", gyr), ("mag", mag), ("nav_attitude", att), ("gps_velocity", gv)):
        if len(cols["time"]) != len(t) or np.abs(cols["time"] - t).max() > 1e-6:
            raise InvalidArgument(f"onav {name}: {what}_data's times are not the accelerometer's")
    vel = _ned_to_enu(gv["gps_vn"], gv["gps_ve"], gv["gps_vd"])
    # the GPS fixes (1 Hz) are held at 50 Hz in the files: a new fix is where the velocity changes
    new = np.concatenate([[True], np.any(np.diff(vel, axis=0) != 0, axis=1)]) & np.isfinite(vel).all(axis=1)
    def body(c: dict[str, FloatArray], k: str) -> FloatArray:
        return _columns(c, [f"{k}_{a}" for a in "xyz"], _FRD)

    return OnavRecording(name, "umn-uav", t, body(gyr, "gyro"), body(acc, "accel"), body(mag, "mag"),
                         _quat_aerospace(att["nav_yaw"], att["nav_pitch"], att["nav_roll"]), None,
                         t[new], vel[new], None)


def _n380(name: str, folder: Path) -> OnavRecording:
    imu, att, pvt = (_read(folder / f"n380-{k}.csv.zip") for k in ("imu-nav", "attitude", "gnss-pvt"))
    t = imu["SystemTov"]
    rot = _FRD @ _N380_SENSOR_TO_FRD

    def inc(k: str) -> FloatArray:
        return _columns(imu, [f"{k}[{i}]" for i in range(3)], rot, _N380_RATE_HZ)

    # the reference: attitude rows in navigation mode, matched to the IMU's epochs by time
    nav = (att["InsGnssBIT.InsMode"] == _N380_NAV_MODE) & (att["SystemTov"] >= 0)
    j, hit = _nearest(att["SystemTov"][nav], t, _N380_MATCH_S)
    ang = np.full((len(t), 6), np.nan)
    cols = [att[f"EulerAttitude[{i}]"][nav] for i in range(3)] + [att[f"EulerAttitudeStdv[{i}]"][nav] for i in range(3)]
    ang[hit] = np.stack(cols, axis=1)[j[hit]]
    good = np.isfinite(pvt["GnssVelocityN"]) & (pvt["SystemTov"] >= 0)
    g = {k: v[good] for k, v in pvt.items()}
    return OnavRecording(name, "hguide-n380", t, inc("DeltaTheta"), inc("DeltaVelocity"), None,
                         _quat_aerospace(ang[:, 2], ang[:, 1], ang[:, 0]), ang[:, [3, 4, 5]],
                         g["SystemTov"], _ned_to_enu(g["GnssVelocityN"], g["GnssVelocityE"], g["GnssVelocityD"]),
                         np.stack([g["GnssStdvE"], g["GnssStdvN"], g["GnssStdvD"]], axis=1))


def load(name: str, root: str | Path | None = None) -> OnavRecording:
    """The recording ``name`` (a key of :data:`RECORDINGS`) from ``root``, onavdata's ``data``
    folder (default: the installed package's, :func:`default_dir`)."""
    if name not in RECORDINGS:
        raise InvalidArgument(f"onav: recording must be one of {', '.join(RECORDINGS)}, got {name!r}")
    base = Path(root) if root is not None else default_dir()
    if base is None:
        raise InvalidArgument("onav: no data folder given and onavdata is not installed "
                              "(pip install --no-deps onavdata==0.2.5 ships the files)")
    kind, sub = RECORDINGS[name]
    folder = base / sub
    if not folder.is_dir():
        raise InvalidArgument(f"onav: {str(folder)!r}: no such folder (root must be onavdata's data folder)")
    return _umn(name, folder) if kind == "umn-uav" else _n380(name, folder)


#: "Still" for :func:`summary`'s level check: GNSS ground speed below this (m/s), ...
STILL_SPEED_M_S = 0.1
#: ... |specific force| within this of standard gravity (m/s²; a running engine's vibration passes) ...
STILL_FORCE_M_S2 = 0.3
#: ... and |angular rate| below this (°/s).
STILL_RATE_DPS = 1.0


def summary(rec: OnavRecording) -> dict[str, float | int | str]:
    """What a recording holds: duration, rates, GNSS, the reference's coverage and stated 1σ,
    and how level the reference says the accelerometer is while the vehicle stands still (the
    angle between the specific force turned by the reference and up, its median and 90th
    percentile over the samples with a GNSS speed under :data:`STILL_SPEED_M_S`, |f| within
    :data:`STILL_FORCE_M_S2` of g and |ω| under :data:`STILL_RATE_DPS`): a check of the frames
    and of the reference, not of a filter."""
    from .core import quat_to_dcm

    ok = np.isfinite(rec.q_ref).all(axis=1)
    speed = np.hypot(rec.gnss_vel[:, 0], rec.gnss_vel[:, 1])
    f_n = np.full_like(rec.acc, np.nan)
    f_n[ok] = np.einsum("kij,kj->ki", quat_to_dcm(rec.q_ref[ok]), rec.acc[ok])
    fn = np.linalg.norm(f_n, axis=1)
    still = ok & (np.interp(rec.t, rec.gnss_t, speed) < STILL_SPEED_M_S) & (np.abs(fn - 9.80665) < STILL_FORCE_M_S2) \
        & (np.linalg.norm(rec.gyr, axis=1) < math.radians(STILL_RATE_DPS))
    tilt = np.degrees(np.arccos(np.clip(f_n[still, 2] / fn[still], -1.0, 1.0)))
    out: dict[str, float | int | str] = {
        "name": rec.name, "kind": rec.kind, "duration_s": round(float(rec.t[-1] - rec.t[0]), 1),
        "imu_hz": round(rec.rate, 2), "imu_gaps": int(np.sum(np.diff(rec.t) > 1.5 / rec.rate)),
        "gnss_n": len(rec.gnss_t), "gnss_interval_s": round(float(np.median(np.diff(rec.gnss_t))), 3),
        "gnss_speed_max_m_s": round(float(speed.max()), 1), "ref_coverage": round(float(ok.mean()), 3),
        "still_s": round(float(still.sum()) / rec.rate, 1),
        "still_tilt_p50_deg": round(float(np.percentile(tilt, 50)), 3) if tilt.size else math.nan,
        "still_tilt_p90_deg": round(float(np.percentile(tilt, 90)), 3) if tilt.size else math.nan,
    }
    if rec.ref_sigma is not None:
        s = np.degrees(np.nanmedian(rec.ref_sigma, axis=0))
        out.update(ref_sigma_roll_deg=round(float(s[0]), 3), ref_sigma_pitch_deg=round(float(s[1]), 3),
                   ref_sigma_heading_deg=round(float(s[2]), 3))
    return out


if __name__ == "__main__":  # python -m attitude_c.onav [DATA_DIR]: the summary of every recording
    import json
    import sys

    root = sys.argv[1] if len(sys.argv) > 1 else None
    try:
        for n in RECORDINGS:
            print(json.dumps(summary(load(n, root))))
    except InvalidArgument as exc:
        print(f"attitude_c.onav: {exc}", file=sys.stderr)
        raise SystemExit(1) from None
