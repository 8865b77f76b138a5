"""IMU recordings from CSV files, in the library's units and body frame.

:func:`read_csv` reads a CSV file with a header naming its columns (any
case; delimiter ``,`` ``;`` tab or spaces, detected from the header):
``gx gy gz`` (gyro), ``ax ay az`` (specific force: +g upward at rest),
optionally ``mx my mz`` (field), ``t`` (s) and a reference attitude
``qw qx qy qz`` (the IMU's axes → ENU). ``columns`` maps these names to the
file's own (``{"gx": "GyroX", ...}``), ``units`` gives each sensor's unit
(:data:`UNITS`), ``axes`` the IMU's mounting (:func:`attitude_c.frames.axes_matrix`):
the returned :class:`Recording` is in rad/s, m/s², µT and the library's
body frame (x right, y forward, z up), the reference rotated to match.

:func:`gyro_scale` measures the gyro's scale against the magnetometer: a
gyro in °/s read as rad/s is 57.3× too fast. Unless ``units`` gives the
gyro's unit, :func:`read_csv` refuses a gyro whose scale is below
:data:`DEG_PER_S_SCALE` or, without a magnetometer, one above
:data:`MAX_RAD_S` (docs/ahrs.md, "Command"); without the accelerometer's
unit, one whose median norm is near 1 (g, not m/s²).
"""

from __future__ import annotations

import csv
import math
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from . import _text
from .core import dcm_to_quat
from .errors import InvalidArgument
from .frames import axes_matrix

__all__ = ["COLUMNS", "DEG_PER_S_SCALE", "MAX_RAD_S", "MIN_CORRELATION", "UNITS", "Recording", "gyro_scale", "read_csv"]

FloatArray = NDArray[np.float64]

#: The column names :func:`read_csv` knows, by sensor (``t`` the time, ``ref`` the reference).
COLUMNS = {"t": ("t",), "gyr": ("gx", "gy", "gz"), "acc": ("ax", "ay", "az"), "mag": ("mx", "my", "mz"),
           "ref": ("qw", "qx", "qy", "qz")}

#: Units per sensor and their factor to the library's (rad/s, m/s², µT); 1 g = 9.80665 m/s²
#: (standard gravity), 1 gauss = 100 µT.
UNITS = {"gyr": {"rad/s": 1.0, "deg/s": math.pi / 180.0},
         "acc": {"m/s2": 1.0, "g": 9.80665},
         "mag": {"uT": 1.0, "gauss": 100.0, "nT": 1e-3}}

#: Below this :func:`gyro_scale` says °/s: the geometric mean of 1 (rad/s) and
#: π/180 (°/s read as rad/s), a factor 7.6 from either. On the 15 BROAD trials
#: (../shared/data/broad) the scale of the rad/s gyro lies in 0.91..1.09.
DEG_PER_S_SCALE = math.sqrt(math.pi / 180.0)

#: :func:`gyro_scale` judges only a recording whose field turns with the gyro: the correlation
#: of ``du/dt`` and ``u × ω`` (scale-free) is 0.40..0.99 over the 15 BROAD trials, at most 0.15
#: over their rest phases before the first movement (noise alone: near 0).
MIN_CORRELATION = 0.3

#: A gyro column above this (rad/s) is °/s: 2000 °/s, the largest full scale of common MEMS
#: gyros (MPU-6050/9250, ICM-20948, BMI160, LSM6DS3: ±2000 °/s). The test without a field.
MAX_RAD_S = math.radians(2000.0)


@dataclass(frozen=True)
class Recording:
    """An IMU recording in rad/s, m/s², µT, the library's body frame; N samples."""

    t: FloatArray                  #: (N,) s
    rate: float                    #: Hz (from ``t``'s median step, or given)
    gyr: FloatArray                #: (N, 3) rad/s
    acc: FloatArray                #: (N, 3) m/s², specific force
    mag: FloatArray | None         #: (N, 3) µT, or None
    ref: FloatArray | None         #: (N, 4) reference attitude (body → ENU), or None
    gyr_scale: float | None = None  #: :func:`gyro_scale` of the file's gyro column (None without a field)


def gyro_scale(gyr: FloatArray, field: FloatArray, rate: float) -> float:
    """The gyro's scale measured against the field: a fixed world vector seen in
    the body turns as ``du/dt = u × ω`` (u its unit vector); the least-squares
    ``k`` of ``du/dt ≈ k (u × ω)`` over the recording (both smoothed over 50 ms).
    1 for a gyro in rad/s, π/180 for one in °/s read as rad/s; NaN when the field's
    turning and the gyro's correlate below :data:`MIN_CORRELATION` (no motion to judge by)."""
    w = max(1, int(round(0.05 * rate)))
    ker = np.ones(w) / w

    def smooth(x: FloatArray) -> FloatArray:
        return np.column_stack([np.convolve(x[:, i], ker, mode="same") for i in range(3)])

    s = smooth(field)
    u = s / np.linalg.norm(s, axis=1, keepdims=True)
    du = (u[2:] - u[:-2]) * (rate / 2.0)
    p = np.cross(u[1:-1], smooth(gyr)[1:-1])
    num, den = float(np.sum(du * p)), float(np.sum(p * p))
    r = num / math.sqrt(den * float(np.sum(du * du))) if den > 0 else 0.0
    return num / den if r >= MIN_CORRELATION else math.nan


def _text_lines(path: Path) -> Iterator[tuple[int, str]]:
    """The file's lines (0-based numbers), bounded (:mod:`attitude_c._text`): a line that is
    not text raises :class:`InvalidArgument` naming the file and line."""
    _text.probe_text(path)
    with open(path, "rb") as fh:
        for lineno, line, problem in _text.lines(fh):
            if problem is not None:
                raise InvalidArgument(f"{path}: line {lineno}: {problem}")
            yield lineno - 1, line


def _header(path: Path) -> tuple[list[str], str | None, int]:
    """The header's names (lower case), the delimiter (None: spaces) and the header's line number
    (0-based: comment lines starting with # may come first). A byte-order mark is dropped."""
    for k, line in _text_lines(path):
        if line.strip() and not line.lstrip().startswith("#"):
            break
    else:
        raise InvalidArgument(f"{path}: no header line")
    try:
        delim: str | None = csv.Sniffer().sniff(line, delimiters=",;\t ").delimiter
    except csv.Error:
        delim = ","
    if delim == " ":
        delim = None  # runs of spaces
    return [c.strip().lower() for c in (line.split(delim) if delim else line.split())], delim, k


def _table(path: Path, delim: str | None, at: int, width: int) -> FloatArray:
    """The numeric rows below the header (line ``at``), read streaming with bounded lines."""
    rows = (line for k, line in _text_lines(path) if k > at)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data": said below, naming the file
            data = np.loadtxt(rows, delimiter=delim, ndmin=2, comments="#")
    except InvalidArgument:  # a line that is not text (it names the file and line)
        raise
    except ValueError as exc:
        raise InvalidArgument(f"{path}: not a numeric table below the header "
                              f"({_text.clip(str(exc).splitlines()[0] if str(exc) else '', 120)})") from None
    if data.shape[0] == 0:
        raise InvalidArgument(f"{path}: no data rows below the header")
    if data.shape[1] != width or data.shape[0] < 2:
        raise InvalidArgument(f"{path}: expected {width} columns (the header's) and at least 2 rows, "
                              f"got {data.shape[1]} columns, {data.shape[0]} rows")
    return np.asarray(data, dtype=np.float64)


def _names(header: list[str]) -> str:
    return _text.clip(", ".join(header), 200)


def _lookup(header: list[str], columns: dict[str, str]) -> dict[str, int]:
    """Column index of every known name present (``columns`` maps a name to the file's header)."""
    known = {n for names in COLUMNS.values() for n in names}
    bad = sorted(set(columns) - known)
    if bad:
        raise InvalidArgument(f"columns: unknown name(s) {', '.join(bad)} (known: {' '.join(sorted(known))})")
    where: dict[str, int] = {}
    for name in known:
        col = columns.get(name, name).strip().lower()
        if col in header:
            where[name] = header.index(col)
        elif name in columns:
            raise InvalidArgument(f"columns: {name}={columns[name]!r}: no such column in the header "
                                  f"({', '.join(header)})")
    need = [n for n in COLUMNS["gyr"] + COLUMNS["acc"] if n not in where]
    if need:
        raise InvalidArgument(f"the header lacks column(s) {', '.join(need)} (header: {_names(header)}; "
                              "name others with --columns, e.g. gx=GyroX)")
    return where


def _factor(units: dict[str, str], sensor: str) -> float:
    u = units.get(sensor)
    if u is None:
        return 1.0
    table = UNITS[sensor]
    if u not in table:
        raise InvalidArgument(f"units: {sensor} unit {u!r}: choose from {', '.join(table)}")
    return table[u]


def read_csv(path: str | Path, columns: dict[str, str] | None = None, units: dict[str, str] | None = None,
             axes: str = "rfu", rate: float | None = None) -> Recording:
    """Read an IMU recording (module doc). ``rate`` (Hz) is needed without a ``t``
    column. Raises :class:`~attitude_c.InvalidArgument` (one line) for a file
    that is not such a recording, and when the gyro looks like °/s while
    ``units`` does not give the gyro's unit."""
    p = Path(path)
    units = dict(units or {})
    bad = sorted(set(units) - set(UNITS))
    if bad:
        raise InvalidArgument(f"units: unknown sensor(s) {', '.join(bad)} (known: {', '.join(UNITS)})")
    R = axes_matrix(axes)
    header, delim, at = _header(p)
    try:
        where = _lookup(header, dict(columns or {}))
    except InvalidArgument as exc:
        raise InvalidArgument(f"{p}: {exc}") from None
    data = _table(p, delim, at, len(header))

    def take(sensor: str) -> FloatArray | None:
        names = COLUMNS[sensor]
        if not all(n in where for n in names):
            return None
        return np.ascontiguousarray(data[:, [where[n] for n in names]], dtype=np.float64)

    t, rate = _time(p, take("t"), rate, len(data))
    gyr, acc, mag = (take(s) for s in ("gyr", "acc", "mag"))
    assert gyr is not None and acc is not None
    gyr, acc = gyr * _factor(units, "gyr") @ R.T, acc * _factor(units, "acc") @ R.T
    mag = None if mag is None else mag * _factor(units, "mag") @ R.T
    ref = take("ref")
    if ref is not None:
        ref = _times(ref, np.asarray(dcm_to_quat(R.T), dtype=np.float64))  # C_rfu^n = C_imu^n R^T (rows lost by the reference stay NaN)
    k = None if mag is None else gyro_scale(gyr, mag, rate)
    try:
        if "gyr" not in units:
            _refuse_deg_per_s(gyr, k)
        if "acc" not in units:
            _refuse_g(acc)
    except InvalidArgument as exc:
        raise InvalidArgument(f"{p}: {exc}") from None
    return Recording(t=t, rate=rate, gyr=gyr, acc=acc, mag=mag, ref=ref, gyr_scale=k)


def _refuse_deg_per_s(gyr: FloatArray, k: float | None) -> None:
    top = float(np.abs(gyr).max())
    if k is not None and k < DEG_PER_S_SCALE:
        why = (f"its rotation is {1 / k:.1f}x the rotation the magnetometer sees (rad/s: 1x, deg/s read as "
               "rad/s: 57.3x)")
    elif top > MAX_RAD_S:
        why = f"it reaches {top:.1f}, beyond a MEMS gyro's largest full scale (2000 deg/s = {MAX_RAD_S:.1f} rad/s)"
    else:
        return
    raise InvalidArgument(f"the gyro looks like deg/s: {why}; give its unit (--gyr-unit deg/s, or rad/s if it "
                          "is; units={'gyr': ...} in Python)")


def _refuse_g(acc: FloatArray) -> None:
    """The specific force's median norm is g (gravity at rest, its average in motion): within
    0.25..4 of 1 it is in g (the filter's alignment bounds, ahrs.h, around 1 instead of 9.81)."""
    med = float(np.median(np.linalg.norm(acc, axis=1)))
    if 0.25 <= med <= 4.0:
        raise InvalidArgument(f"the accelerometer looks like g: its median norm is {med:.3g} (m/s^2: about "
                              "9.81); give its unit (--acc-unit g, or m/s2 if it is; units={'acc': ...} in Python)")


def _times(q: FloatArray, r: FloatArray) -> FloatArray:
    """``q ⊗ r`` for rows q (N, 4) and one quaternion r (Hamilton, scalar first), NaN rows kept."""
    w, x, y, z = r
    right = np.array([[w, -x, -y, -z], [x, w, z, -y], [y, -z, w, x], [z, y, -x, w]])
    return np.asarray(q @ right.T, dtype=np.float64)


def _time(p: Path, t: FloatArray | None, rate: float | None, n: int) -> tuple[FloatArray, float]:
    if t is not None:
        t = t[:, 0]
        if not np.all(np.diff(t) > 0):
            raise InvalidArgument(f"{p}: the t column must increase")
    if rate is None:
        if t is None:
            raise InvalidArgument(f"{p}: no t column: give the rate (--rate)")
        rate = 1.0 / float(np.median(np.diff(t)))
    return (np.arange(n) / rate if t is None else t), float(rate)
