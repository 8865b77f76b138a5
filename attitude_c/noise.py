"""Allan deviation of a rest recording and the noise terms it shows (docs/noise.md).

:func:`allan` takes a rest recording of rates (a gyro, rad/s) or specific
forces (an accelerometer, m/s²), one column per axis, and returns the
overlapping Allan deviation per axis at octave-spaced cluster times
τ = m/rate (m = 1, 2, 4, ...), computed with ``allantools`` (``oadev``), with
its confidence interval (chi-square with Greenhall's equivalent degrees of
freedom for the noise type that dominates at that τ), and the three terms of
IEEE Std 952's model fitted to it together,

    σ²(τ) = N²/τ + (2 ln 2/π)·B² + K²·τ/3,

each with its 1σ uncertainty: N the white noise (angle or velocity random
walk, the slope −½ line read at τ = 1 s), B the bias instability (the flat
floor is 0.664·B), K the random walk of the bias (the slope +½ line read at
τ = 3 s). The fit is weighted least squares in σ² (linear in N², B², K², each
≥ 0), each τ weighted by its own confidence: var(σ̂²) = 2σ⁴/edf.

:func:`filter_settings` maps the terms to the attitude filter's settings
(:data:`MAPPING` says which term sets which setting, and why); docs/noise.md
has the method, the mapping and the validation on the simulator's sensors.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidArgument, InvalidType

__all__ = ["MAPPING", "MAPPING_CALIBRATED", "PLATEAU", "AllanResult", "Terms", "allan", "config_text", "filter_settings", "horizontal_field", "plot"]

FloatArray = NDArray[np.float64]
Kind = Literal["gyro", "accel"]

#: The Allan deviation of flicker noise of bias instability B is PLATEAU·B (√(2 ln 2/π) = 0.664).
PLATEAU = math.sqrt(2 * math.log(2) / math.pi)
#: The confidence of the reported intervals: 1σ (erf(1/√2)).
ONE_SIGMA = math.erf(1 / math.sqrt(2))
#: The fit starts at this many samples per cluster: a part's own low-pass correlates neighbouring
#: samples, which lowers the first points below N/√τ by about 2a/((1 − a²)·m) (a the correlation of
#: neighbours; 0.08 for a 40 Hz part sampled at 100 Hz: 2 % at m = 8).
FIT_M_MIN = 16
#: At least this many samples: enough octaves (m = 8 .. n/4) for three terms.
MIN_SAMPLES = 256
#: Noise types (allantools' α of the frequency noise) of the three terms: white, flicker, random walk FM.
_ALPHA = (0, -1, -2)


@dataclass(frozen=True)
class Terms:
    """The fitted noise terms of one axis, in the input's units (u: rad/s for a
    gyro, m/s² for an accelerometer), each with its 1σ uncertainty. A term the
    fit did not find is 0, its uncertainty the size it would need to be seen."""

    n: float        #: white noise N, u·√s (angle/velocity random walk): σ(1 s) of its line
    n_sigma: float
    b: float        #: bias instability B, u (the floor of σ is 0.664·B)
    b_sigma: float
    k: float        #: bias random walk K, u/√s (rate/acceleration random walk): σ(3 s) of its line
    k_sigma: float
    tau_min: float  #: s, τ of the smallest Allan deviation (the floor's place)
    adev_min: float  #: u, that smallest deviation

    def adev(self, tau: ArrayLike) -> FloatArray:
        """The fitted model's Allan deviation at ``tau`` (s)."""
        t = np.asarray(tau, dtype=float)
        return np.sqrt(self.n ** 2 / t + (PLATEAU * self.b) ** 2 + self.k ** 2 * t / 3)

    def as_dict(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in ("n", "n_sigma", "b", "b_sigma", "k", "k_sigma", "tau_min",
                                                      "adev_min")}


@dataclass(frozen=True)
class AllanResult:
    """Overlapping Allan deviation of each axis (columns) at the cluster times ``tau``."""

    rate: float        #: Hz, the input's sampling rate
    samples: int
    tau: FloatArray    #: (m,) s
    adev: FloatArray   #: (m, k) input units
    lo: FloatArray     #: (m, k) the 1σ confidence interval's ends
    hi: FloatArray
    edf: FloatArray    #: (m, k) equivalent degrees of freedom (Greenhall)
    terms: tuple[Terms, ...]  #: per axis

    def as_dict(self) -> dict[str, Any]:
        return {"rate_hz": self.rate, "samples": self.samples, "tau_s": self.tau.tolist(),
                "adev": self.adev.T.tolist(), "lo": self.lo.T.tolist(), "hi": self.hi.T.tolist(),
                "edf": self.edf.T.tolist(), "terms": [t.as_dict() for t in self.terms]}


def _allantools() -> Any:
    try:
        import allantools
    except ImportError:
        raise ImportError("the Allan deviation needs allantools: pip install 'attitude-c[noise]'") from None
    return allantools


def _check(x: ArrayLike, rate: float) -> tuple[FloatArray, float]:
    if isinstance(rate, bool) or not isinstance(rate, (int, float, np.integer, np.floating)):
        raise InvalidType(f"rate must be a number (Hz), got {type(rate).__name__}")
    if not (math.isfinite(rate) and rate > 0):
        raise InvalidArgument(f"rate must be a finite number > 0 (Hz), got {rate!r}")
    a = np.asarray(x)
    if a.dtype.kind not in "iuf":
        raise InvalidType(f"x must hold real numbers, got dtype {a.dtype}")
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2 or a.shape[1] < 1:
        raise InvalidArgument(f"x must have shape (N,) or (N, axes), got {np.shape(x)}")
    if a.shape[0] < MIN_SAMPLES:
        raise InvalidArgument(f"x: at least {MIN_SAMPLES} samples are needed, got {a.shape[0]}")
    if not np.all(np.isfinite(a)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(a), axis=1))[0])
        raise InvalidArgument(f"x: sample {bad} is not finite")
    flat = np.flatnonzero(np.ptp(a, axis=0) == 0)
    if flat.size:
        raise InvalidArgument(f"x: column {int(flat[0])} is constant (a stuck or disconnected sensor?)")
    return np.asarray(a, dtype=np.float64), float(rate)


def allan(x: ArrayLike, rate: float) -> AllanResult:
    """Overlapping Allan deviation of each column of ``x`` ((N,) or (N, axes):
    rates or specific forces at a rest, sampled at ``rate`` Hz) at τ = m/rate,
    m = 1, 2, 4, ... up to N/4, with 1σ confidence intervals and the fitted
    :class:`Terms` of each axis. Needs ``allantools`` (``pip install
    'attitude-c[noise]'``)."""
    a, rate = _check(x, rate)
    at = _allantools()
    n = a.shape[0]
    m = 2 ** np.arange(int(math.log2(n / 4)) + 1)
    cols = [at.oadev(a[:, j] - a[:, j].mean(), rate, "freq", m / rate) for j in range(a.shape[1])]
    tau = np.asarray(cols[0][0], dtype=float)
    adev = np.column_stack([np.asarray(c[1], dtype=float) for c in cols])
    ms = np.round(tau * rate).astype(int)
    terms, edfs = [], []
    for j in range(a.shape[1]):
        t, edf = _fit(tau, adev[:, j], ms, n, at)
        terms.append(t)
        edfs.append(edf)
    edf = np.column_stack(edfs)
    lo, hi = np.vectorize(lambda d, e: at.confidence_interval(d, e, ONE_SIGMA))(adev, edf)
    return AllanResult(rate, n, tau, adev, np.asarray(lo, float), np.asarray(hi, float), edf, tuple(terms))


def _edf(alpha: NDArray[np.int64], ms: NDArray[np.int64], n: int, at: Any) -> FloatArray:
    """Greenhall's EDF of the overlapping Allan variance (d = 2) of n frequency
    samples (n + 1 phase points) for each τ's noise type α."""
    return np.array([at.edf_greenhall(int(al), 2, int(mm), n + 1, overlapping=True) for al, mm in zip(alpha, ms)])


def _design(tau: FloatArray) -> FloatArray:
    return np.column_stack([1 / tau, np.full_like(tau, PLATEAU ** 2), tau / 3])


def _nnls(a: FloatArray, y: FloatArray, w: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Weighted least squares of y ≈ a·c with c ≥ 0 (the best of the active sets,
    three columns: seven subsets), and the unconstrained covariance of c."""
    aw, yw = a * np.sqrt(w)[:, None], y * np.sqrt(w)
    best, best_c = math.inf, np.zeros(a.shape[1])
    for r in range(1, a.shape[1] + 1):
        for cols in itertools.combinations(range(a.shape[1]), r):
            c_s = np.linalg.lstsq(aw[:, cols], yw, rcond=None)[0]
            if np.any(c_s < 0):
                continue
            c = np.zeros(a.shape[1])
            c[list(cols)] = c_s
            chi2 = float(np.sum((aw @ c - yw) ** 2))
            if chi2 < best:
                best, best_c = chi2, c
    cov = np.asarray(np.linalg.pinv(aw.T @ aw), dtype=np.float64)
    return best_c, cov


def _fit(tau: FloatArray, adev: FloatArray, ms: NDArray[np.int64], n: int, at: Any) -> tuple[Terms, FloatArray]:
    """The three terms of one axis (weighted by each τ's EDF, for the noise type
    the previous pass says dominates there: white first) and each τ's EDF."""
    a, y = _design(tau), adev ** 2
    use = ms >= min(FIT_M_MIN, int(ms[-1]) // 4)
    alpha = np.zeros(len(tau), dtype=np.int64)
    floor = float(y.max()) * 1e-12  # a deviation of 0 at some τ (a periodic input) keeps a finite weight
    model = np.maximum(y, floor)
    for _ in range(3):
        edf = _edf(alpha, ms, n, at)
        w = edf / (2 * model ** 2)
        c, cov = _nnls(a[use], y[use], w[use])
        parts = a * c
        model = np.maximum(parts.sum(axis=1), floor)
        alpha = np.array(_ALPHA)[np.argmax(parts, axis=1)]
    i = int(np.argmin(adev))
    n2, b2, k2 = c
    sd = UNCERTAINTY_SCALE * np.sqrt(np.maximum(np.diag(cov), 0))
    terms = Terms(*_root(n2, sd[0]), *_root(b2, sd[1]), *_root(k2, sd[2]), float(tau[i]), float(adev[i]))
    return terms, _edf(alpha, ms, n, at)


def _root(c: float, sd: float) -> tuple[float, float]:
    """√c and its 1σ from the 1σ of c (first order); a term fitted as 0: 0 and √sd."""
    if c <= 0:
        return 0.0, math.sqrt(sd)
    return math.sqrt(c), sd / (2 * math.sqrt(c))


#: Which term sets which filter setting (``att_ahrs_settings``, ahrs.h), in the setting's
#: unit, and why: (setting, rule, why). "worst axis": one value for the three axes, the largest.
#: A rest recording shows the sensor's own noise only: where a setting also carries what rest
#: cannot show (model error in motion, linear acceleration, temperature), the library's default
#: stays as its floor.
MAPPING: tuple[tuple[str, str, str], ...] = (
    ("gyr_noise_rest", "N of the gyro (rad/√s)",
     "the attitude's process noise at rest is the gyro's own white noise: the angle random walk"),
    ("gyr_noise", "max(N of the gyro, default)",
     ("in motion the process noise also carries model error (scale, misalignment, timing, vibration) "
      "that no rest recording shows; a gyro noisier than the default raises it")),
    ("bias_noise", "max(√(K² + 3·(0.664·B)²/τ_min), default) of the gyro (rad/s/√s)",
     ("the bias is a random walk in the filter: the smallest walk that covers the measured wander "
      "at every τ ≥ τ_min (the floor's place); turn-on transients and temperature, which a "
      "recording at one temperature does not show, keep the default as the floor")),
    ("rest_noise", "N of the gyro (rad/s·√s)",
     "the zero-rate update measures the bias with the gyro's own reading: its white noise"),
    ("acc_noise", "max(N of the accelerometer / gravity, default) (rad·√s)",
     ("the inclination's noise density is the accelerometer's white noise over g, plus linear "
      "acceleration in motion, which rest does not show: the default stays as the floor")),
)
#: The same for parts whose only error in motion is their noise (``calibrated=True``: scale and
#: misalignment calibrated out, no vibration, no linear acceleration: the simulator's calibrated
#: parts, a turntable run): no floors, and what the floors carried is derived from the noise.
MAPPING_CALIBRATED: tuple[tuple[str, str, str], ...] = (
    ("gyr_noise_rest, gyr_noise, rest_noise", "N of the gyro",
     "no model error in motion: the process noise is the gyro's own white noise, at rest and in motion"),
    ("bias_noise", "max(√(K² + 3·(0.664·B)²/τ_min), default) of the gyro",
     ("as in MAPPING: calibration removes scale and misalignment, not the turn-on transients and "
      "temperature changes the default floor stands for")),
    ("acc_noise", "σ_A(τ)·√τ / gravity at τ = acc_noise / gyr_noise (accelerometer's fitted model)",
     ("the white density with the accelerometer's own Allan deviation over the inclination's Kalman "
      "time constant: the bias instability and walk the filter has no state for count as the noise "
      "they are over the time the inclination averages")),
    ("tilt_tau", "0",
     ("the reported inclination is the state's: the covariance is the state's, and the second "
      "low-pass exists for real motion's linear accelerations")),
    ("turn_sigma", "0", "no scale or misalignment error: no fast-turn term"),
    ("mag_noise", "σ_A(τ)·√τ / |m_h| at τ = mag_noise / gyr_noise (magnetometer's fitted model)",
     "the heading's noise is the field's noise across the horizontal field |m_h|, over the heading's time constant"),
)
#: Uncertainties of the terms are the least-squares 1σ times this: neighbouring octaves share
#: their data, so their errors are correlated and the fit's own σ is too small. In the sweeps of
#: docs/noise.md (``invoke allan-sweep``) the spread of the fitted terms was 1.1–1.7× the
#: undoubled σ for N and B, and 1.2–2.5× for K (2.5× where the floor lasts to 30 s).
UNCERTAINTY_SCALE = 2.0


def filter_settings(gyro: Terms | AllanResult, accel: Terms | AllanResult | None = None,
                    gravity: float | None = None, *, calibrated: bool = False,
                    mag: Terms | AllanResult | None = None, mag_h: float | None = None) -> dict[str, float]:
    """The attitude filter's settings from the noise terms of its gyro (rad/s)
    and accelerometer (m/s²): :data:`MAPPING`, for the worst axis of each; with
    ``calibrated`` (parts whose only error in motion is their noise)
    :data:`MAPPING_CALIBRATED`, which needs ``accel``, and with ``mag`` (its terms,
    any unit) and ``mag_h`` (the horizontal field at rest, that unit) also ``mag_noise``."""
    if not isinstance(calibrated, bool):
        raise InvalidType(f"calibrated must be a bool, got {type(calibrated).__name__}")
    if calibrated:
        return _calibrated_settings(gyro, accel, gravity, mag, mag_h)
    from .ahrs_filter import default_settings

    d = default_settings()
    g = _worst(gyro, "gyro")
    k_eff = math.sqrt(g.k ** 2 + 3 * (PLATEAU * g.b) ** 2 / g.tau_min) if g.b > 0 else g.k
    out = {"gyr_noise_rest": g.n, "gyr_noise": max(g.n, d["gyr_noise"]),
           "bias_noise": max(k_eff, d["bias_noise"]), "rest_noise": g.n}
    if accel is not None:
        grav = float(d["gravity"] if gravity is None else gravity)
        if not (math.isfinite(grav) and grav > 0):
            raise InvalidArgument(f"gravity must be a finite number > 0 (m/s²), got {gravity!r}")
        out["acc_noise"] = max(_worst(accel, "accel").n / grav, d["acc_noise"])
    if g.n <= 0:
        raise InvalidArgument("gyro: no white noise found (N = 0): is this a rate recording at rest?")
    return out


def _own_time_density(t: Terms, sg: float, scale: float) -> float:
    """The fixed point a = σ_A(τ)·√τ / scale, τ = a / sg: the white density whose average over the
    Kalman time constant it sets has the part's own Allan deviation there (σ_A²τ grows with τ, so
    the iteration from N rises monotonically to it)."""
    a = t.n / scale
    for _ in range(200):
        tau = a / sg
        nxt = float(t.adev(tau)) * math.sqrt(tau) / scale
        if abs(nxt - a) <= 1e-12 * a:
            break
        a = nxt
    return a


def _calibrated_settings(gyro: Terms | AllanResult, accel: Terms | AllanResult | None, gravity: float | None,
                         mag: Terms | AllanResult | None, mag_h: float | None) -> dict[str, float]:
    from .ahrs_filter import default_settings

    if accel is None:
        raise InvalidArgument("calibrated: the accelerometer's terms are needed (accel)")
    g = _worst(gyro, "gyro")
    if g.n <= 0:
        raise InvalidArgument("gyro: no white noise found (N = 0): is this a rate recording at rest?")
    grav = float(default_settings()["gravity"] if gravity is None else gravity)
    if not (math.isfinite(grav) and grav > 0):
        raise InvalidArgument(f"gravity must be a finite number > 0 (m/s²), got {gravity!r}")
    k_eff = math.sqrt(g.k ** 2 + 3 * (PLATEAU * g.b) ** 2 / g.tau_min) if g.b > 0 else g.k
    acc = _own_time_density(_worst(accel, "accel"), g.n, grav)
    out = {"gyr_noise_rest": g.n, "gyr_noise": g.n, "rest_noise": g.n,
           "bias_noise": max(k_eff, default_settings()["bias_noise"]), "acc_noise": acc, "tilt_tau": 0.0,
           "turn_sigma": 0.0}
    if mag is not None:
        if mag_h is None or not (math.isfinite(mag_h) and mag_h > 0):
            raise InvalidArgument(f"mag_h must be the horizontal field (> 0, the magnetometer's unit), got {mag_h!r}")
        out["mag_noise"] = _own_time_density(_worst(mag, "mag"), g.n, float(mag_h))
    return out


def horizontal_field(acc: ArrayLike, mag: ArrayLike) -> float:
    """|m_h| of a rest recording: the mean field's part across the mean specific force (which
    points up), in the magnetometer's unit: ``mag_h`` of :func:`filter_settings`."""
    a, m = np.asarray(acc, float).reshape(-1, 3).mean(axis=0), np.asarray(mag, float).reshape(-1, 3).mean(axis=0)
    na = float(np.linalg.norm(a))
    if not (math.isfinite(na) and na > 0 and np.all(np.isfinite(m))):
        raise InvalidArgument("horizontal_field: acc and mag must be finite, acc's mean not zero")
    return float(np.linalg.norm(np.cross(m, a / na)))


def _worst(x: Terms | AllanResult, name: str) -> Terms:
    if isinstance(x, Terms):
        return x
    if not isinstance(x, AllanResult):
        raise InvalidType(f"{name} must be Terms or an AllanResult, got {type(x).__name__}")
    ts = x.terms

    def worst(f: str) -> float:
        return float(max(getattr(t, f) for t in ts))

    return Terms(worst("n"), worst("n_sigma"), worst("b"), worst("b_sigma"), worst("k"), worst("k_sigma"),
                 ts[int(np.argmax([t.b for t in ts]))].tau_min, worst("adev_min"))


def config_text(settings: dict[str, float], source: str) -> str:
    """attitude-rx config lines (``name = value``, docs/attitude-rx.md) for the settings."""
    lines = [f"# attitude allan {source}: filter noise settings from the Allan deviation (docs/noise.md)"]
    lines += [f"{k} = {v:.6g}" for k, v in settings.items()]
    return "\n".join(lines) + "\n"


def plot(results: dict[str, tuple[AllanResult, str]], path: str | Path, title: str) -> None:
    """Log-log Allan deviation of each sensor (``{"gyro": (result, unit), ...}``, one panel
    each): the points with their 1σ intervals per axis, the fitted model and its three lines."""
    from ._plot import plt

    pyplot = plt()
    fig, axes = pyplot.subplots(1, len(results), figsize=(5.0 * len(results), 4.2), squeeze=False)
    try:
        for ax, (name, (r, unit)) in zip(axes[0], results.items()):
            _panel(ax, r, name, unit)
        fig.suptitle(title, fontsize=9.5)
        fig.tight_layout()
        fig.savefig(path, dpi=110, format="png")
    finally:
        pyplot.close(fig)


def _panel(ax: Any, r: AllanResult, name: str, unit: str) -> None:
    colors = ("tab:red", "tab:green", "tab:blue")
    t = r.tau
    for j in range(r.adev.shape[1]):
        c = colors[j % 3]
        ax.errorbar(t, r.adev[:, j], yerr=[r.adev[:, j] - r.lo[:, j], r.hi[:, j] - r.adev[:, j]], fmt="o",
                    ms=3, color=c, label=f"axis {'xyz'[j] if j < 3 else j}")
        ax.plot(t, r.terms[j].adev(t), "-", color=c, lw=0.8)
    w = _worst(r, name)
    lines = ((w.n / np.sqrt(t), f"N {w.n:.3g} {unit}·√s (τ=1 s)"), (np.full_like(t, PLATEAU * w.b), f"0.664·B, B {w.b:.3g} {unit}"),
             (w.k * np.sqrt(t / 3), f"K {w.k:.3g} {unit}/√s (τ=3 s)"))
    for y, lab in lines:
        if np.any(y > 0):
            ax.plot(t, y, "--", color="0.4", lw=0.8)
            ax.annotate(lab, (t[0], y[0]) if "N " in lab else (t[-1], y[-1]), fontsize=7,
                        ha="left" if "N " in lab else "right", va="bottom")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("τ / s")
    ax.set_ylabel(f"Allan deviation / {unit}")
    ax.set_title(name, fontsize=9)
    ax.grid(True, which="both", linestyle=":", linewidth=0.6)
    ax.legend(loc="upper center", fontsize=7)
