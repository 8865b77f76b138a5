"""BROAD recordings: loading trials and the benchmark's error metric.

BROAD (Berlin Robust Orientation Estimation Assessment Dataset) holds real IMU
recordings with optical ground truth: D. Laidig, M. Caruso, A. Cereatti,
T. Seel, "BROAD — A Benchmark for Robust Inertial Orientation Estimation",
*Data* 6(7), 2021, doi:10.3390/data6070072 (CC BY 4.0). Cite it wherever
results on it are shown. A subset ships with the project in
``../shared/data/broad/``; the upstream ``data_mat/`` folder works too.

Each trial file (MATLAB v5, read with SciPy: ``pip install 'attitude-c[broad]'``) holds ``imu_gyr`` (rad/s),
``imu_acc`` (m/s², specific force: +9.81 upward at rest), ``imu_mag`` (µT),
``opt_quat`` (w, x, y, z of the IMU relative to ENU; NaN where the cameras
lost the markers), ``opt_pos`` (m), ``movement`` (1 in movement phases) and
``sampling_rate`` (Hz).

The error metric (BROAD paper): with e = q_est ⊗ q_ref⁻¹ over the movement
samples, total error 2·acos(|e_w|), heading error 2·atan(|e_z / e_w|),
inclination error 2·acos(√(e_w² + e_z²)); each as an RMS in degrees per
trial, then averaged over trials. The heading part is the rotation about
the navigation frame's vertical (ENU z) in the heading-inclination
decomposition e = e_heading ⊗ e_inclination.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _text
from .errors import InvalidArgument

__all__ = [
    "CITATION",
    "ErrorFigures",
    "Trial",
    "default_dir",
    "error_angles",
    "errors",
    "find_trials",
    "iter_trials",
    "load_trial",
    "mean_figures",
]

CITATION = ("D. Laidig, M. Caruso, A. Cereatti, T. Seel, \"BROAD — A Benchmark for Robust "
            "Inertial Orientation Estimation\", Data 6(7), 2021, doi:10.3390/data6070072 "
            "(CC BY 4.0)")

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Trial:
    """One BROAD trial. Arrays are float64 (``movement`` bool), N samples."""

    name: str          #: file stem, e.g. ``01_undisturbed_slow_rotation_A``
    rate: float        #: sampling rate, Hz
    gyr: FloatArray    #: (N, 3) angular rate, rad/s, IMU frame
    acc: FloatArray    #: (N, 3) specific force, m/s², IMU frame
    mag: FloatArray    #: (N, 3) magnetic field, µT, IMU frame
    quat: FloatArray   #: (N, 4) reference attitude w,x,y,z (IMU → ENU); NaN where lost
    pos: FloatArray    #: (N, 3) reference position, m
    movement: NDArray[np.bool_]  #: (N,) samples that count in the error metric
    groups: tuple[str, ...] = ()  #: BROAD groups of the trial (``undisturbed``, ``disturbed``, ...)

    @property
    def n(self) -> int:
        return int(self.gyr.shape[0])

    @property
    def dt(self) -> float:
        return 1.0 / self.rate

    @property
    def disturbed(self) -> bool:
        return "disturbed" in self.groups


def default_dir() -> Path | None:
    """The copy shipped beside a source checkout (``../shared/data/broad``), if present."""
    here = Path(__file__).resolve()
    for base in (Path.cwd(), *here.parents):
        cand = base.parent / "shared" / "data" / "broad"
        if cand.is_dir():
            return cand
    return None


def _groups_table(folder: Path) -> dict[str, tuple[str, ...]]:
    for cand in (folder / "trials.json", folder.parent / "trials.json"):
        if cand.is_file():
            data = json.loads(cand.read_text())
            return {k: tuple(v.get("groups", ())) for k, v in data.get("trials", {}).items()}
    return {}


def _groups_from_name(stem: str) -> tuple[str, ...]:
    # upstream trial names carry their top-level group
    if "_disturbed_" in stem:
        return ("all_trials", "disturbed")
    if "_undisturbed_" in stem:
        return ("all_trials", "undisturbed")
    return ("all_trials",)


def load_trial(path: str | Path) -> Trial:
    """Read one BROAD ``.mat`` file (needs SciPy: ``pip install 'attitude-c[broad]'``; without it
    ImportError saying so)."""
    p = Path(path)
    if not p.is_file():
        raise InvalidArgument(f"path: no BROAD trial file at {str(p)!r}")
    try:
        from scipy.io import loadmat
    except ImportError as exc:  # pragma: no cover - depends on install
        raise ImportError(f"{p.name}: reading BROAD .mat files needs SciPy: pip install 'attitude-c[broad]'") from exc
    try:
        d = loadmat(str(p))
    except Exception as exc:
        raise InvalidArgument(f"path: {str(p)!r} is not a readable MATLAB file ({exc})") from exc
    need = ("imu_gyr", "imu_acc", "imu_mag", "opt_quat", "movement", "sampling_rate")
    missing = [k for k in need if k not in d]
    if missing:
        raise InvalidArgument(f"path: {str(p)!r} is not a BROAD trial (missing {', '.join(missing)})")

    where = f"path: {str(p)!r}"

    def arr(key: str, cols: int) -> FloatArray:
        raw = np.asarray(d[key])
        if raw.dtype.kind not in "biuf":  # complex, text, cells: not a BROAD array (never cut to its real part)
            raise InvalidArgument(f"{where}: {key} holds {raw.dtype.name} values, expected real numbers")
        a = np.ascontiguousarray(raw, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != cols or a.shape[0] != n:
            raise InvalidArgument(f"{where}: {key} has shape {a.shape}, expected ({n}, {cols})")
        return a

    n = int(np.shape(d["imu_gyr"])[0]) if np.ndim(d["imu_gyr"]) else 0
    if n == 0:
        raise InvalidArgument(f"{where}: imu_gyr holds no sample")
    gyr = arr("imu_gyr", 3)
    pos = arr("opt_pos", 3) if "opt_pos" in d else np.full((n, 3), np.nan)
    movement = np.asarray(d["movement"]).ravel()
    if movement.size != n:
        raise InvalidArgument(f"{where}: movement has {movement.size} values, expected {n} (one per sample)")
    table = _groups_table(p.parent)
    groups = table.get(p.stem) or _groups_from_name(p.stem)
    return Trial(name=p.stem, rate=_rate(d["sampling_rate"], where), gyr=gyr,
                 acc=arr("imu_acc", 3), mag=arr("imu_mag", 3), quat=arr("opt_quat", 4), pos=pos,
                 movement=movement.astype(bool), groups=tuple(groups))


def _rate(value: object, where: str) -> float:
    """The trial's sampling_rate: one real number, finite and > 0 (Hz)."""
    a = np.asarray(value)
    if a.size != 1 or a.dtype.kind not in "biuf" or not (np.isfinite(a).all() and float(a.ravel()[0]) > 0):
        raise InvalidArgument(f"{where}: sampling_rate must be one finite number > 0 (Hz), got "
                              f"{_text.clip(repr(a.ravel().tolist()))}")
    return float(a.ravel()[0])


def find_trials(folder: str | Path | None = None) -> list[Path]:
    """The trial files of a folder (sorted), by default :func:`default_dir`."""
    f = Path(folder) if folder is not None else default_dir()
    if f is None or not f.is_dir():
        raise InvalidArgument(f"folder: no BROAD data folder at {str(f)!r}")
    files = sorted(p for p in f.glob("*.mat"))
    if not files:
        raise InvalidArgument(f"folder: no .mat files in {str(f)!r}")
    return files


def iter_trials(folder: str | Path | None = None) -> Iterator[Trial]:
    for p in find_trials(folder):
        yield load_trial(p)


@dataclass(frozen=True)
class ErrorFigures:
    """RMS errors over the movement phase, degrees."""

    total: float
    heading: float
    inclination: float
    samples: int  #: movement samples with a valid reference

    def as_dict(self) -> dict[str, float | int]:
        return {"total": self.total, "heading": self.heading, "inclination": self.inclination,
                "samples": self.samples}


def _quat_rows(q: ArrayLike, name: str) -> FloatArray:
    a = np.asarray(q, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 4:
        raise InvalidArgument(f"{name} must have shape (N, 4) (w, x, y, z), got {a.shape}")
    return a


def error_angles(q_est: ArrayLike, q_ref: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Per-sample total, heading and inclination error angles (rad) of BROAD's metric.

    Rows where either quaternion is non-finite or zero give NaN.
    """
    a = _quat_rows(q_est, "q_est")
    b = _quat_rows(q_ref, "q_ref")
    if a.shape != b.shape:
        raise InvalidArgument(f"q_est and q_ref must have the same shape, got {a.shape} and {b.shape}")
    with np.errstate(invalid="ignore", divide="ignore"):
        a = a / np.linalg.norm(a, axis=1, keepdims=True)
        b = b / np.linalg.norm(b, axis=1, keepdims=True)
        # e = a ⊗ conj(b)  (Hamilton product, scalar first)
        aw, ax, ay, az = a.T
        bw, bx, by, bz = b.T
        bx, by, bz = -bx, -by, -bz
        ew = aw * bw - ax * bx - ay * by - az * bz
        ez = aw * bz + ax * by - ay * bx + az * bw
        total = 2.0 * np.arccos(np.clip(np.abs(ew), 0.0, 1.0))
        heading = 2.0 * np.arctan(np.abs(ez / ew))
        incl = 2.0 * np.arccos(np.clip(np.sqrt(ew * ew + ez * ez), 0.0, 1.0))
    return total, heading, incl


def errors(q_est: ArrayLike, q_ref: ArrayLike, movement: ArrayLike | None = None) -> ErrorFigures:
    """BROAD's RMS errors (degrees) of ``q_est`` against ``q_ref`` over ``movement``.

    Samples whose reference is missing (NaN) are left out, as in the benchmark.
    """
    total, heading, incl = error_angles(q_est, q_ref)
    m = np.ones(total.shape, bool) if movement is None else np.asarray(movement, bool).ravel()
    if m.shape != total.shape:
        raise InvalidArgument(f"movement must have {len(total)} entries, got {m.size}")
    ok = m & np.isfinite(total) & np.isfinite(heading) & np.isfinite(incl)
    k = int(ok.sum())
    if k == 0:
        raise InvalidArgument("no movement sample has a valid reference: nothing to score")

    def rms(x: FloatArray) -> float:
        return math.degrees(float(np.sqrt(np.mean(x[ok] ** 2))))

    return ErrorFigures(total=rms(total), heading=rms(heading), inclination=rms(incl), samples=k)


def mean_figures(figs: Sequence[ErrorFigures]) -> dict[str, float]:
    """Mean of per-trial RMS figures (the benchmark's averaging over trials)."""
    if not figs:
        raise InvalidArgument("figs: no trials to average")
    return {k: float(np.mean([getattr(f, k) for f in figs])) for k in ("total", "heading", "inclination")}
