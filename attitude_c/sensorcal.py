"""Calibration of the aided board's accelerometer and magnetometer from raw codes
(``attitude calibrate``, docs/sensor.md "Calibration").

Both sensors are converted as ``attitude-rx`` converts them (docs/sensor.md,
AIDED-SPEC section 3): per body axis i reading channel c = ``axes[i]``::

    v_i = sign_i · (word_c / n − zero_c) · scale_c        out = M (v − b)

:class:`SensorConfig` holds one sensor's ``zero``, ``scale``, ``axes``,
``matrix`` M and ``bias`` b, converts codes with that formula
(:meth:`SensorConfig.convert`, NumPy, written from the formula) and writes its
``acc-*`` / ``mag-*`` lines.

* **Accelerometer, static positions** (:func:`fit_accel`): the board held
  still in P positions; the mean codes of each, converted with the nominal
  zero and scale, must have the norm of gravity after the correction. A
  Levenberg–Marquardt least-squares fit of ``|C (v_p − b)| = g`` over the P
  positions: ``diagonal`` C (per-axis scale and offset: 6 unknowns, six
  positions or more) or ``full`` (C symmetric: scale, offset and the
  non-orthogonality of the axes, 9 unknowns, twelve positions or more by
  default). A rotation of C is invisible in norms; the symmetric C is the
  one that rotates nothing (as the magnetometer's soft iron). The result is
  factored into per-channel zero (codes at 0 g) and scale and a unit-diagonal
  matrix M (cross-axis), bias 0.
* **Magnetometer, a rotation** (:func:`fit_mag`): the values of a slow
  rotation through many directions go to the library's ellipsoid fit
  (:func:`attitude_c.magcal.fit`: hard iron h, soft iron S, det S = 1); M =
  S · F/B when the local field strength F is given (the corrected field then
  has that norm), else S (field in the nominal scale); b = h.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import magcal, names
from .core import FloatPrecision
from .errors import InvalidArgument
from .sensor import Sensor

__all__ = [
    "ACCEL_MODELS",
    "AccelFit",
    "AccelModel",
    "MagFit",
    "SensorConfig",
    "fit_accel",
    "fit_mag",
    "format_axes",
    "parse_axes",
    "pose_means",
    "still_segments",
]

Prefix = Literal["acc", "mag"]
AccelModel = Literal["auto", "diagonal", "full"]
ACCEL_MODELS: tuple[str, ...] = get_args(AccelModel)
#: Fewest positions per model (unknowns: 6 and 9; "full" wants 3 spare positions to show a residual).
MIN_POSES = {"diagonal": 6, "full": 12}
_AXIS_NAMES = "xyz"
_MAX_CODE = 4095


def parse_axes(text: str) -> tuple[tuple[int, int, int], tuple[int, int, int]]:
    """``"x,y,z"`` / ``"-y,+x,z"`` (as attitude-rx's ``axes``) → (channels, signs):
    body axis i reads channel ``channels[i]`` with sign ``signs[i]``."""
    parts = [p.strip().lower() for p in str(text).split(",")]
    chans, signs = [], []
    for p in parts:
        sign = -1 if p.startswith("-") else 1
        name = p.lstrip("+-")
        if len(name) != 1 or name not in _AXIS_NAMES + "012":
            raise InvalidArgument(f"axes {text!r}: each of three entries must be x, y or z with an optional sign")
        chans.append(_AXIS_NAMES.index(name) if name in _AXIS_NAMES else int(name))
        signs.append(sign)
    if sorted(chans) != [0, 1, 2]:
        raise InvalidArgument(f"axes {text!r} must name each channel x, y, z once, e.g. x,y,z or -y,+x,z")
    return (chans[0], chans[1], chans[2]), (signs[0], signs[1], signs[2])


def format_axes(chans: tuple[int, int, int], signs: tuple[int, int, int]) -> str:
    return ",".join(("-" if s < 0 else "") + _AXIS_NAMES[c] for c, s in zip(chans, signs))


def _perm(axes: str) -> NDArray[np.float64]:
    """The signed permutation P: v_body = P · (channel values)."""
    chans, signs = parse_axes(axes)
    p = np.zeros((3, 3))
    for i, (c, s) in enumerate(zip(chans, signs)):
        p[i, c] = s
    return p


def _vec(x: ArrayLike, name: str, shape: tuple[int, ...]) -> NDArray[np.float64]:
    a = np.asarray(x, dtype=float)
    if a.shape == () and shape == (3,):
        a = np.full(3, float(a))
    if a.shape != shape or not np.isfinite(a).all():
        raise InvalidArgument(f"{name} must be {'×'.join(map(str, shape))} finite numbers, got {np.asarray(x)!r}")
    return a


def _fmt(values: ArrayLike) -> str:
    return ",".join(f"{float(v):.10g}" for v in np.asarray(values, dtype=float).reshape(-1))


@dataclass(frozen=True)
class SensorConfig:
    """One sensor's conversion as attitude-rx's config keys ``PREFIX-zero``,
    ``-scale`` (units per code: m/s² or µT), ``-axes``, ``-matrix`` (3×3,
    row-major in the file), ``-bias`` (units)."""

    prefix: Prefix
    zero: NDArray[np.float64]
    scale: NDArray[np.float64]
    axes: str = "x,y,z"
    matrix: NDArray[np.float64] = field(default_factory=lambda: np.eye(3))
    bias: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        if self.prefix not in get_args(Prefix):
            raise InvalidArgument(f"prefix must be one of {get_args(Prefix)}, got {self.prefix!r}")
        zero = _vec(self.zero, "zero", (3,))
        scale = _vec(self.scale, "scale", (3,))
        if (zero < 0).any() or (zero > 65535).any() or (scale == 0).any():
            raise InvalidArgument(f"zero must be 0..65535 codes and scale non-zero, got {zero}, {scale}")
        object.__setattr__(self, "axes", format_axes(*parse_axes(self.axes)))  # as attitude-rx spells it
        matrix = _vec(self.matrix, "matrix", (3, 3))
        if not abs(np.linalg.det(matrix)) >= 1.0 / names.C["ATT_SENSOR_DET_RECIP"]:
            raise InvalidArgument(f"matrix must be invertible, |det| >= 1/ATT_SENSOR_DET_RECIP, got det "
                                  f"{np.linalg.det(matrix):g}")
        for name, v in (("zero", zero), ("scale", scale), ("matrix", matrix), ("bias", _vec(self.bias, "bias", (3,)))):
            object.__setattr__(self, name, v)

    @property
    def unit(self) -> str:
        return "m/s^2" if self.prefix == "acc" else "uT"

    def sensor(self, corrected: bool = True, precision: FloatPrecision = "f64") -> Sensor:
        """The library's converter (``att_sensor``) of this configuration, as
        attitude-rx sets it up; ``corrected=False``: without M and b (v)."""
        chans, signs = parse_axes(self.axes)
        if not corrected:
            return Sensor(self.zero, self.scale, chans, signs, precision)
        return Sensor(self.zero, self.scale, chans, signs, precision, matrix=self.matrix, bias=self.bias)

    def convert(self, words: ArrayLike, n: int = 1, corrected: bool = True) -> NDArray[np.float64]:
        """Integer words (N, 3) of n conversions → body values (N, 3), through the C converter."""
        return np.asarray(self.sensor(corrected).convert(words, n), dtype=np.float64)

    def lines(self) -> list[str]:
        """The attitude-rx config lines (``acc-zero = ...``)."""
        p = self.prefix
        return [f"{p}-zero = {_fmt(self.zero)}", f"{p}-scale = {_fmt(self.scale)}", f"{p}-axes = {self.axes}",
                f"{p}-matrix = {_fmt(self.matrix)}", f"{p}-bias = {_fmt(self.bias)}"]

    def keys(self) -> list[str]:
        return [line.split(" = ")[0] for line in self.lines()]


def pose_means(values: ArrayLike, pose: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.int64],
                                                           NDArray[np.float64], NDArray[np.int64]]:
    """The mean of each static position: values (N, 3) (codes or converted), pose
    (N,) integer labels (a label < 0: a row to ignore, e.g. moving between
    positions). Returns (means (P, 3), rows per pose (P,), standard deviation per
    pose (P, 3), the labels (P,))."""
    w = np.asarray(values, dtype=float)
    lab = np.asarray(pose)
    if w.ndim != 2 or w.shape[1] != 3 or lab.shape != (w.shape[0],):
        raise InvalidArgument(f"values must be (N, 3) and pose (N,), got {w.shape} and {lab.shape}")
    labels = np.unique(lab[lab >= 0])
    means = np.array([w[lab == k].mean(axis=0) for k in labels]).reshape(-1, 3)
    counts = np.array([int((lab == k).sum()) for k in labels], dtype=np.int64)
    stds = np.array([w[lab == k].std(axis=0) for k in labels]).reshape(-1, 3)
    return means, counts, stds, labels.astype(np.int64)


def still_segments(codes: ArrayLike, window: int = 20, still: float = 4.0, merge: float = 10.0,
                   min_windows: int = 3) -> NDArray[np.int64]:
    """Position labels (N,) for a recording (N, 3) of codes (one conversion each) in
    which the board was held still in several positions and moved between them:
    windows of ``window`` rows whose every axis has a standard deviation of at most
    ``still`` codes are still; consecutive still windows whose means agree with the
    first one's within ``merge`` codes form a position (a slow turn is no position), less its first and last window (they may hold
    the end of a movement); a run of fewer than ``min_windows`` windows (≥ 3) and
    every moving row get −1."""
    c = np.asarray(codes, dtype=float)
    if c.ndim != 2 or c.shape[1] != 3:
        raise InvalidArgument(f"codes must be (N, 3), got {c.shape}")
    if window < 2 or min_windows < 3 or not (still > 0 and merge > 0):
        raise InvalidArgument(f"need window >= 2, min_windows >= 3, still and merge > 0, got {window}, "
                              f"{min_windows}, {still}, {merge}")
    k = len(c) // window
    blocks = c[:k * window].reshape(k, window, 3)
    quiet = blocks.std(axis=1).max(axis=1) <= still
    means = blocks.mean(axis=1)
    labels = np.full(len(c), -1, dtype=np.int64)
    run: list[int] = []

    def close(label: int) -> int:
        if len(run) >= min_windows:  # its first and last windows may hold the end of a movement: left out
            labels[(run[0] + 1) * window:run[-1] * window] = label
            return label + 1
        return label

    label = 0
    for i in range(k):
        if quiet[i] and run and np.abs(means[i] - means[run[0]]).max() <= merge:  # no slow drift
            run.append(i)
            continue
        label = close(label)
        run = [i] if quiet[i] else []
    close(label)
    return labels


# --------------------------------------------------------------------------- accelerometer


def _unpack(p: NDArray[np.float64], model: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Parameters → (C, b): b = p[:3]; C diagonal p[3:6] or symmetric from its upper triangle p[3:9]."""
    if model == "diagonal":
        return np.diag(p[3:6]), p[:3]
    c = np.zeros((3, 3))
    c[np.triu_indices(3)] = p[3:9]
    return c + np.triu(c, 1).T, p[:3]


def _residuals(p: NDArray[np.float64], v: NDArray[np.float64], g: float,
               model: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """r_p = |C (v_p − b)| − g and its Jacobian (P, params)."""
    c, b = _unpack(p, model)
    u = v - b
    w = u @ c.T
    norm = np.linalg.norm(w, axis=1)
    wh = w / norm[:, None]
    jb = -wh @ c  # ∂r/∂b
    if model == "diagonal":
        jc = wh * u  # ∂r/∂C_ii = ŵ_i u_i
    else:
        iu, ju = np.triu_indices(3)
        jc = wh[:, iu] * u[:, ju] + np.where(iu != ju, wh[:, ju] * u[:, iu], 0.0)
    return norm - g, np.hstack([jb, jc])


def _levenberg_marquardt(p: NDArray[np.float64], v: NDArray[np.float64], g: float, model: str,
                         iterations: int = 200) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Minimise Σ r_p² from p; returns (p, J at p)."""
    lam = 1e-3
    r, jac = _residuals(p, v, g, model)
    cost = float(r @ r)
    for _ in range(iterations):
        a = jac.T @ jac
        step = np.linalg.solve(a + lam * np.diag(np.diag(a) + 1e-300), -jac.T @ r)
        r2, j2 = _residuals(p + step, v, g, model)
        if float(r2 @ r2) < cost:
            p, r, jac, cost = p + step, r2, j2, float(r2 @ r2)
            lam = max(lam / 10, 1e-12)
            if np.abs(step).max() <= 1e-13 * (1 + np.abs(p).max()):
                break
        else:
            lam *= 10
            if lam > 1e12:
                break
    return p, jac


@dataclass(frozen=True)
class AccelFit:
    """The accelerometer's calibration: ``config`` (what attitude-rx reads),
    ``model`` fitted, ``residuals`` per position (|out| − g, m/s²), ``gravity``,
    ``correction`` C and ``offset`` b in the nominal body frame, ``condition``
    of the fit (√ of the normal matrix's condition number)."""

    config: SensorConfig
    model: str
    residuals: NDArray[np.float64]
    gravity: float
    correction: NDArray[np.float64]
    offset: NDArray[np.float64]
    condition: float

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.residuals**2)))


def _pick_model(model: str, poses: int) -> str:
    if model not in ACCEL_MODELS:
        raise InvalidArgument(f"model must be one of {ACCEL_MODELS}, got {model!r}")
    if model == "auto":
        model = "full" if poses >= MIN_POSES["full"] else "diagonal"
    if poses < MIN_POSES[model]:
        raise InvalidArgument(f"the {model} accelerometer model needs {MIN_POSES[model]} static positions or more, "
                              f"got {poses}")
    return model


def _factor(nominal: SensorConfig, c: NDArray[np.float64], b: NDArray[np.float64]) -> SensorConfig:
    """C (v − b) with v = P diag(s0)(code − z0) as M P diag(s)(code − z), M unit-diagonal:
    z = z0 + diag(1/s0) Pᵀ b; A = C P diag(s0); s_{c_i} = sign_i A[i, c_i]; M = A diag(1/s) Pᵀ."""
    p = _perm(nominal.axes)
    zero = nominal.zero + (p.T @ b) / nominal.scale
    a = c @ p @ np.diag(nominal.scale)
    chans, signs = parse_axes(nominal.axes)
    scale = np.empty(3)
    for i in range(3):
        scale[chans[i]] = signs[i] * a[i, chans[i]]
    return SensorConfig(nominal.prefix, zero, scale, nominal.axes, a @ np.diag(1 / scale) @ p.T, np.zeros(3))


def fit_accel(means: ArrayLike, nominal: SensorConfig, gravity: float = 9.80665,
              model: AccelModel = "auto") -> AccelFit:
    """Fit the accelerometer to the means (P, 3) of P static positions of its values
    converted with the ``nominal`` zero, scale and axes and no correction
    (``nominal.convert(words, n, corrected=False)``; its matrix and bias are ignored).

    Raises InvalidArgument when there are too few positions for the model, when
    the positions do not determine it (e.g. an axis never pointed up or down:
    condition above 1e6) or when the fit does not converge."""
    if not (isinstance(gravity, (int, float)) and math.isfinite(gravity) and gravity > 0):
        raise InvalidArgument(f"gravity must be a finite number > 0 (m/s^2), got {gravity!r}")
    base = SensorConfig(nominal.prefix, nominal.zero, nominal.scale, nominal.axes)
    v = _vec(means, "means", (len(np.asarray(means)), 3))
    kind = _pick_model(model, len(v))
    b0 = v.mean(axis=0)  # positions spread over the sphere average to about the offset
    s0 = gravity / np.linalg.norm(v - b0, axis=1).mean()
    p0 = np.concatenate([b0, [s0] * 3 if kind == "diagonal" else [s0, 0, 0, s0, 0, s0]])
    p, jac = _levenberg_marquardt(p0, v, gravity, kind)
    sv = np.linalg.svd(jac, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
    if not cond < 1e6:
        raise InvalidArgument(f"the {len(v)} positions do not determine the {kind} model (condition {cond:.3g}): "
                              "hold each axis pointing up and pointing down, and more tilts between")
    c, b = _unpack(p, kind)
    if not (np.isfinite(p).all() and np.linalg.det(c) > 0):
        raise InvalidArgument("the accelerometer fit did not converge: check that every position was still")
    r, _ = _residuals(p, v, gravity, kind)
    return AccelFit(_factor(base, c, b), kind, r, float(gravity), c, b, cond)


# --------------------------------------------------------------------------- magnetometer


@dataclass(frozen=True)
class MagFit:
    """The magnetometer's calibration: ``config``, the ellipsoid fit ``cal``
    (attitude_c.magcal), ``field`` the norm of the corrected field (µT: the given
    local field, else the fit's B), ``norm_error`` per sample (|out| − field, µT)."""

    config: SensorConfig
    cal: magcal.Calibration
    field: float
    norm_error: NDArray[np.float64]

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.norm_error**2)))


def fit_mag(values: ArrayLike, nominal: SensorConfig, field_ut: float | None = None,
            model: magcal.Model = "full", min_span: float = 0.1) -> MagFit:
    """Fit hard and soft iron to the values (N, 3) of a rotation through many
    directions, converted with the ``nominal`` zero, scale and axes and no
    correction (``nominal.convert(words, n, corrected=False)``). ``field_ut``: the
    local field strength (e.g. from a geomagnetic model), to scale M so that the
    corrected field has that norm. Refusals of the ellipsoid fit (too few
    samples, too little spread: rotate about more axes) raise InvalidArgument."""
    if field_ut is not None and not (isinstance(field_ut, (int, float)) and math.isfinite(field_ut)
                                     and field_ut > 0):
        raise InvalidArgument(f"field_ut must be a finite number > 0 (uT) or None, got {field_ut!r}")
    v = _vec(values, "values", (len(np.asarray(values)), 3))
    cal = magcal.fit(v, model, min_span=min_span)
    k = 1.0 if field_ut is None else field_ut / cal.field
    config = SensorConfig(nominal.prefix, nominal.zero, nominal.scale, nominal.axes, cal.S * k, cal.h)
    strength = cal.field * k
    return MagFit(config, cal, strength, np.linalg.norm((v - cal.h) @ config.matrix.T, axis=1) - strength)
