"""Wavelet threshold denoising of gyro data (the FPGA+DSP paper, sec. 3.4).

The C denoiser of ``csrc/include/attitude/denoise.h`` over NumPy arrays, in
the double (``precision="f64"``) and float (``"f32"``) builds:

* :class:`DenoiseConfig` — wavelet, levels, block N, the samples dropped
  at each window's start and end, thresholding rule, detrending (defaults
  from the C library);
* :func:`denoise` — a whole record, (N,) or (N, C), as a pure function;
* :class:`Denoiser` — the same as a stream: :meth:`Denoiser.update` takes
  (M, C) samples and returns the (K, C) denoised samples completed so far,
  :meth:`Denoiser.flush` the rest at the end;
* the block pieces (:func:`wavedec`, :func:`waverec`, :func:`threshold`,
  :func:`noise_sigma`, :func:`universal_threshold`, :func:`denoise_block`),
  which agree with PyWavelets' ``periodization`` mode on the same block.

:mod:`attitude_c.denoise.reference` is the independent NumPy reference.
Every function returns float64 arrays. Method, latency and limits:
docs/denoise.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._lib import ffi_lib
from .._validate import C_INT_RANGES, integer, real
from ..core import _as_real, _check_precision, _ptr, _records, _to_c
from ..errors import InvalidArgument, InvalidType, RangeError
from ..names import raise_for_status

__all__ = [
    "THRESHOLDS",
    "WAVELETS",
    "DenoiseConfig",
    "Denoiser",
    "Threshold",
    "Wavelet",
    "denoise",
    "denoise_block",
    "filters",
    "noise_sigma",
    "threshold",
    "universal_threshold",
    "wavedec",
    "waverec",
]

Wavelet = Literal["haar", "db2", "db4"]
Threshold = Literal["soft", "hard"]
#: Wavelet names (PyWavelets' names for the same filters).
WAVELETS: tuple[str, ...] = get_args(Wavelet)
#: Thresholding rules.
THRESHOLDS: tuple[str, ...] = get_args(Threshold)

FloatArray = NDArray[np.float64]
_DTYPES = {"f64": np.float64, "f32": np.float32}


def _wavelet_code(lib: Any, name: str) -> int:
    return {"haar": lib.ATT_WDEN_HAAR, "db2": lib.ATT_WDEN_DB2, "db4": lib.ATT_WDEN_DB4}[name]


def _mode_code(lib: Any, name: str) -> int:
    return {"soft": lib.ATT_WDEN_SOFT, "hard": lib.ATT_WDEN_HARD}[name]


def _status_table(lib: Any) -> dict[str, tuple[type[Exception], str]]:
    """The denoiser's status codes (attitude/denoise.h), keyed by C name (attitude_c.names)."""
    return {
        "ATT_E_WDEN_WAVELET": (InvalidArgument, f"wavelet must be one of {WAVELETS}"),
        "ATT_E_WDEN_MODE": (InvalidArgument, f"threshold must be one of {THRESHOLDS}"),
        "ATT_E_WDEN_LEVELS": (InvalidArgument, f"levels must be 1..{lib.ATT_WDEN_MAX_LEVELS}"),
        "ATT_E_WDEN_BLOCK": (InvalidArgument, (f"the block length must be 2..{lib.ATT_WDEN_MAX_BLOCK} "
                                               "and a multiple of 2**levels")),
        "ATT_E_WDEN_EDGE": (InvalidArgument, "edge_start + edge_end must be smaller than the block"),
        "ATT_E_WDEN_SHORT": (InvalidArgument, "fewer samples than one block were received"),
        "ATT_E_WDEN_OVERFLOW": (RangeError, "finite input, but the result overflows"),
    }


def _check(status: int, what: str, lib: Any) -> None:
    raise_for_status(status, what, _status_table(lib))


def _choice(value: Any, name: str, allowed: tuple[str, ...]) -> str:
    if not isinstance(value, str):
        raise InvalidType(f"{name} must be a str, got {type(value).__name__}")
    if value not in allowed:
        raise InvalidArgument(f"{name} must be one of {allowed!r}, got {value!r}")
    return value


def _count(value: Any, name: str, minimum: int, ctype: str = "unsigned long") -> int:
    """An integer ≥ minimum that fits the C field or argument it goes to (size_t by default)."""
    return integer(value, name, minimum, C_INT_RANGES[ctype][1], f"C {ctype}")


def _c_defaults() -> dict[str, Any]:
    ffi, lib = ffi_lib("f64")
    c = ffi.new("att_wden_config *")
    lib.att_wden_config_default(c)
    return {"wavelet": WAVELETS[[_wavelet_code(lib, w) for w in WAVELETS].index(c.wavelet)],
            "threshold": THRESHOLDS[[_mode_code(lib, m) for m in THRESHOLDS].index(c.mode)],
            "levels": int(c.levels), "block": int(c.block),
            "edge_start": int(c.edge_start), "edge_end": int(c.edge_end),
            "detrend": bool(c.detrend)}


_DEFAULT = _c_defaults()


@dataclass(frozen=True)
class DenoiseConfig:
    """Denoiser settings (docs/denoise.md). Defaults: the C library's.

    ``block`` N samples per window, ``levels`` L (N a multiple of 2^L),
    ``edge_start`` and ``edge_end``: the oldest and the newest samples of a
    window that are not output (windows advance by the hop
    N − edge_start − edge_end; both 0: non-overlapping blocks),
    ``threshold`` soft or hard, ``detrend``: remove and restore the
    least-squares line per block (a ramp then passes unchanged for every
    wavelet)."""

    wavelet: Wavelet = _DEFAULT["wavelet"]
    levels: int = _DEFAULT["levels"]
    block: int = _DEFAULT["block"]
    edge_start: int = _DEFAULT["edge_start"]
    edge_end: int = _DEFAULT["edge_end"]
    threshold: Threshold = _DEFAULT["threshold"]
    detrend: bool = _DEFAULT["detrend"]

    def __post_init__(self) -> None:
        _choice(self.wavelet, "wavelet", WAVELETS)
        _choice(self.threshold, "threshold", THRESHOLDS)
        for name, minimum in (("levels", 1), ("block", 2), ("edge_start", 0), ("edge_end", 0)):
            ctype = "unsigned int" if name == "levels" else "unsigned long"
            object.__setattr__(self, name, _count(getattr(self, name), name, minimum, ctype))
        if not isinstance(self.detrend, (bool, np.bool_)):
            raise InvalidType(f"detrend must be a bool, got {type(self.detrend).__name__}")
        object.__setattr__(self, "detrend", bool(self.detrend))
        ffi, lib = ffi_lib("f64")
        if self.levels > lib.ATT_WDEN_MAX_LEVELS:
            raise InvalidArgument(f"levels must be 1..{lib.ATT_WDEN_MAX_LEVELS}, got {self.levels}")
        if self.block > lib.ATT_WDEN_MAX_BLOCK:
            raise InvalidArgument(f"block must be 2..{lib.ATT_WDEN_MAX_BLOCK}, got {self.block}")
        st = lib.att_wden_config_check(self._struct(ffi, lib))
        if st == lib.ATT_E_WDEN_BLOCK:
            raise InvalidArgument(f"block must be a multiple of 2**levels = {1 << self.levels}, "
                                  f"got block={self.block}")
        if st == lib.ATT_E_WDEN_EDGE:
            raise InvalidArgument(f"edge_start + edge_end must be < block = {self.block}, got "
                                  f"edge_start={self.edge_start}, edge_end={self.edge_end}")
        _check(st, "DenoiseConfig", lib)

    def _struct(self, ffi: Any, lib: Any) -> Any:
        c = ffi.new("att_wden_config *")
        c.wavelet = _wavelet_code(lib, self.wavelet)
        c.mode = _mode_code(lib, self.threshold)
        c.levels = self.levels
        c.block = self.block
        c.edge_start = self.edge_start
        c.edge_end = self.edge_end
        c.detrend = int(self.detrend)
        return c

    @property
    def hop(self) -> int:
        """Samples between two windows (and output burst size), N − Es − Ee."""
        return self.block - self.edge_start - self.edge_end

    @property
    def latency(self) -> int:
        """Largest delay (samples) from a sample's arrival to its output, steady state."""
        ffi, lib = ffi_lib("f64")
        return int(lib.att_wden_latency(self._struct(ffi, lib)))

    def latency_s(self, rate_hz: float) -> float:
        """:attr:`latency` in seconds at a sampling rate of ``rate_hz``."""
        return self.latency / float(rate_hz)


# --------------------------------------------------------------------------
# block pieces
# --------------------------------------------------------------------------

def _vector(x: ArrayLike, name: str) -> NDArray[np.float64]:
    a = _as_real(x, name)
    if a.ndim != 1:
        raise InvalidArgument(f"{name} must be one block of shape (n,), got {a.shape}")
    if a.shape[0] == 0:
        raise InvalidArgument(f"{name} is empty")
    return _records(a.reshape(-1, 1), name, (1,), "sample").reshape(-1)


def filters(wavelet: Wavelet = "db4") -> tuple[FloatArray, FloatArray]:
    """(h, g) of the C library: scaling and wavelet filters (PyWavelets'
    ``rec_lo`` and ``rec_hi``), double precision."""
    _choice(wavelet, "wavelet", WAVELETS)
    ffi, lib = ffi_lib("f64")
    h = ffi.new(f"att_real[{lib.ATT_WDEN_MAX_TAPS}]")
    g = ffi.new(f"att_real[{lib.ATT_WDEN_MAX_TAPS}]")
    taps = ffi.new("size_t *")
    _check(lib.att_wden_filters(_wavelet_code(lib, wavelet), h, g, taps), "filters", lib)
    f = int(taps[0])
    return np.array([h[i] for i in range(f)]), np.array([g[i] for i in range(f)])


def _shape_check(n: int, levels: int, name: str, lib: Any) -> None:
    if not 1 <= levels <= lib.ATT_WDEN_MAX_LEVELS:
        raise InvalidArgument(f"levels must be 1..{lib.ATT_WDEN_MAX_LEVELS}, got {levels}")
    if n < 2 or n > lib.ATT_WDEN_MAX_BLOCK or n % (1 << levels):
        raise InvalidArgument(f"{name} has {n} samples: a block must have 2..{lib.ATT_WDEN_MAX_BLOCK} "
                              f"samples, a multiple of 2**levels = {1 << levels}")


def wavedec(x: ArrayLike, wavelet: Wavelet = "db4", levels: int = 3,
            precision: str = "f64") -> list[FloatArray]:
    """[cA_L, cD_L, …, cD_1] of one block (PyWavelets' ``wavedec`` order and
    ``periodization`` mode); len(x) a multiple of 2**levels."""
    precision = _check_precision(precision)
    _choice(wavelet, "wavelet", WAVELETS)
    levels = _count(levels, "levels", 1)
    out64 = _transform("att_wden_dwt", _vector(x, "x"), wavelet, levels, precision, "x")
    n = out64.shape[0]
    parts, m = [out64[: n >> levels]], n >> levels
    while m < n:
        parts.append(out64[m: 2 * m])
        m *= 2
    return parts


def waverec(coeffs: Sequence[ArrayLike], wavelet: Wavelet = "db4", precision: str = "f64") -> FloatArray:
    """Inverse of :func:`wavedec`: ``coeffs`` = [cA_L, cD_L, …, cD_1]."""
    precision = _check_precision(precision)
    _choice(wavelet, "wavelet", WAVELETS)
    if isinstance(coeffs, np.ndarray) or not isinstance(coeffs, Sequence) or len(coeffs) < 2:
        raise InvalidArgument("coeffs must be a list [cA_L, cD_L, ..., cD_1] of at least 2 arrays")
    parts = [_vector(c, f"coeffs[{i}]") for i, c in enumerate(coeffs)]
    want = len(parts[0])  # cD_L has the length of cA_L, every finer level twice the previous
    for i, p in enumerate(parts[1:], start=1):
        if len(p) != want:
            raise InvalidArgument(f"coeffs[{i}] has {len(p)} values, expected {want} "
                                  "([cA_L, cD_L, ..., cD_1] as wavedec returns them)")
        want = 2 * len(p)
    return _transform("att_wden_idwt", np.concatenate(parts), wavelet, len(parts) - 1, precision, "coeffs")


def _transform(cname: str, a: NDArray[np.float64], wavelet: str, levels: int, precision: str,
               name: str) -> FloatArray:
    """One C transform (att_wden_dwt or att_wden_idwt) of the flat block a."""
    ffi, lib = ffi_lib(precision)
    n = a.shape[0]
    _shape_check(n, levels, name, lib)
    c = _to_c(a, precision, name)
    out = np.empty(n, dtype=_DTYPES[precision])
    tmp = np.empty(n, dtype=_DTYPES[precision])
    _check(getattr(lib, cname)(_wavelet_code(lib, wavelet), levels, _ptr(ffi, c), n, _ptr(ffi, out),
                               _ptr(ffi, tmp)), f"{cname}({name})", lib)
    return out.astype(np.float64)


def threshold(c: ArrayLike, value: float, mode: Threshold = "soft", precision: str = "f64") -> FloatArray:
    """soft: sign(c)·max(|c| − value, 0); hard: c where |c| ≥ value, else 0."""
    precision = _check_precision(precision)
    _choice(mode, "mode", THRESHOLDS)
    a = _vector(c, "c")
    lam = _scalar(value, "value")
    if lam < 0:
        raise InvalidArgument(f"value must be >= 0, got {lam}")
    ffi, lib = ffi_lib(precision)
    buf = _to_c(a, precision, "c").copy()
    _check(lib.att_wden_threshold(_ptr(ffi, buf), buf.shape[0], lam, _mode_code(lib, mode)),
           "threshold(c)", lib)
    return buf.astype(np.float64)


def _scalar(value: Any, name: str) -> float:
    return real(value, name)


def noise_sigma(details: ArrayLike, precision: str = "f64") -> float:
    """σ = median(|d|) / Φ⁻¹(3/4) of detail coefficients (the finest level, cD_1)."""
    precision = _check_precision(precision)
    a = _vector(details, "details")
    ffi, lib = ffi_lib(precision)
    c = _to_c(a, precision, "details")
    work = np.empty_like(c)
    s = ffi.new("att_real *")
    _check(lib.att_wden_mad_sigma(_ptr(ffi, c), c.shape[0], _ptr(ffi, work), s), "noise_sigma(details)",
           lib)
    return float(s[0])


def universal_threshold(sigma: float, n: int, precision: str = "f64") -> float:
    """λ = σ √(2 ln n) for a block of n samples."""
    precision = _check_precision(precision)
    s = _scalar(sigma, "sigma")
    if s < 0:
        raise InvalidArgument(f"sigma must be >= 0, got {s}")
    n = _count(n, "n", 1)
    ffi, lib = ffi_lib(precision)
    out = ffi.new("att_real *")
    _check(lib.att_wden_universal(s, n, out), "universal_threshold", lib)
    return float(out[0])


def denoise_block(x: ArrayLike, config: DenoiseConfig | None = None,
                  precision: str = "f64") -> tuple[FloatArray, float]:
    """Denoise one block x (its length is the block; ``config.block`` and
    the edges are not used). Returns (y, σ)."""
    precision = _check_precision(precision)
    cfg = _config(config)
    a = _vector(x, "x")
    ffi, lib = ffi_lib(precision)
    n = a.shape[0]
    _shape_check(n, cfg.levels, "x", lib)
    c = ffi.new("att_wden_config *")
    c.wavelet, c.mode = _wavelet_code(lib, cfg.wavelet), _mode_code(lib, cfg.threshold)
    c.levels, c.block, c.detrend = cfg.levels, n, int(cfg.detrend)
    c.edge_start = c.edge_end = 0
    buf = _to_c(a, precision, "x")
    out = np.empty_like(buf)
    scratch = np.empty(2 * n, dtype=_DTYPES[precision])
    s = ffi.new("att_real *")
    _check(lib.att_wden_block(c, _ptr(ffi, buf), _ptr(ffi, out), _ptr(ffi, scratch), s),
           "denoise_block(x)", lib)
    return out.astype(np.float64), float(s[0])


def _config(config: DenoiseConfig | None) -> DenoiseConfig:
    if config is None:
        return DenoiseConfig()
    if not isinstance(config, DenoiseConfig):
        raise InvalidType(f"config must be a DenoiseConfig, got {type(config).__name__}")
    return config


# --------------------------------------------------------------------------
# the stream
# --------------------------------------------------------------------------

class Denoiser:
    """Streaming denoiser for ``channels`` signals sampled together (one C
    ``att_wden`` state each, sharing one scratch buffer).

    :meth:`update` takes samples (C,) or (M, C) and returns the denoised
    samples completed by them, (K, C) float64 (K is 0 until a window fills,
    then bursts of ``config.hop``); :meth:`flush` ends the stream and returns
    the rest. Output k is input sample k denoised, delayed by at most
    ``config.latency`` samples (``block − 1`` for the first ``edge_start``)."""

    def __init__(self, config: DenoiseConfig | None = None, channels: int = 3,
                 precision: str = "f64") -> None:
        self.config: DenoiseConfig = _config(config)
        self.channels: int = _count(channels, "channels", 1)
        self.precision: str = _check_precision(precision)
        ffi, lib = self._ffi, self._lib = ffi_lib(self.precision)
        self._cfg = self.config._struct(ffi, lib)
        dt = _DTYPES[self.precision]
        n_state = int(lib.att_wden_state_len(self._cfg))
        n_scratch = int(lib.att_wden_scratch_len(self._cfg))
        self._ring = np.zeros((self.channels, n_state), dtype=dt)
        self._scratch = np.zeros(n_scratch, dtype=dt)
        self._states = [ffi.new("att_wden *") for _ in range(self.channels)]
        for j, s in enumerate(self._states):
            _check(lib.att_wden_init(s, self._cfg, _ptr(ffi, self._ring[j]), n_state,
                                     _ptr(ffi, self._scratch), n_scratch), "Denoiser", lib)

    @property
    def latency(self) -> int:
        """Largest delay (samples) from a sample's arrival to its output (steady state)."""
        return self.config.latency

    @property
    def pending(self) -> int:
        """Samples received and not yet output (what :meth:`flush` returns)."""
        return int(self._lib.att_wden_pending(self._states[0]))

    @property
    def windows(self) -> int:
        """Windows processed since construction, reset or flush."""
        return int(self._states[0].windows)

    @property
    def sigma(self) -> FloatArray:
        """Noise level σ of the last window, per channel (0 before the first)."""
        return np.array([float(s.sigma) for s in self._states])

    def outputs(self, n: int) -> int:
        """How many samples ``n`` more input samples would complete."""
        return int(self._lib.att_wden_outputs(self._states[0], _count(n, "n", 0)))

    def reset(self) -> None:
        """Drop everything received; start a new stream."""
        for s in self._states:
            self._lib.att_wden_reset(s)

    def _samples(self, x: ArrayLike) -> NDArray[Any]:
        a = _as_real(x, "x")
        if a.ndim == 1 and a.shape == (self.channels,):
            a = a.reshape(1, -1)
        if a.ndim != 2 or a.shape[1] != self.channels:
            raise InvalidArgument(f"x must have shape (M, {self.channels}) or ({self.channels},) "
                                  f"(one column per channel), got {a.shape}")
        return _to_c(_records(a, "x", (self.channels,), "sample of every channel"), self.precision, "x")

    def update(self, x: ArrayLike) -> FloatArray:
        """Feed samples (C,) or (M, C); return the (K, C) samples they complete."""
        a = self._samples(x)
        ffi, lib = self._ffi, self._lib
        m = a.shape[0]
        k = self.outputs(m)
        out = np.empty((max(k, 1), self.channels), dtype=_DTYPES[self.precision])
        if m:
            col = np.empty(max(k, 1), dtype=out.dtype)
            n_out = ffi.new("size_t *")
            err = ffi.new("size_t *")
            for j, s in enumerate(self._states):
                xj = np.ascontiguousarray(a[:, j])
                st = lib.att_wden_push_n(s, _ptr(ffi, xj), m, _ptr(ffi, col), k, n_out, err)
                if st != 0:
                    self.reset()
                    _check(st, f"Denoiser.update(x): channel {j}, sample {int(err[0])} "
                               "(the stream was reset)", lib)
                out[:k, j] = col[:k]
        return out[:k].astype(np.float64)

    def flush(self) -> FloatArray:
        """End the stream: the (pending, C) samples left; then start afresh."""
        ffi, lib = self._ffi, self._lib
        k = self.pending
        out = np.empty((max(k, 1), self.channels), dtype=_DTYPES[self.precision])
        col = np.empty(max(k, 1), dtype=out.dtype)
        n_out = ffi.new("size_t *")
        for j, s in enumerate(self._states):
            st = lib.att_wden_flush(s, _ptr(ffi, col), k, n_out)
            if st == lib.ATT_E_WDEN_SHORT:
                raise InvalidArgument(f"flush: only {k} samples were received, fewer than one block "
                                      f"({self.config.block}): nothing can be denoised")
            _check(st, f"Denoiser.flush: channel {j}", lib)
            out[:k, j] = col[:k]
        return out[:k].astype(np.float64)

    def __repr__(self) -> str:
        return (f"Denoiser({self.config!r}, channels={self.channels}, precision={self.precision!r}, "
                f"pending={self.pending})")


def denoise(x: ArrayLike, config: DenoiseConfig | None = None, precision: str = "f64") -> FloatArray:
    """Denoise a whole record x, (N,) or (N, C) (one column per channel;
    N ≥ ``config.block``): the stream of :class:`Denoiser` fed with x and
    flushed, so the output is aligned with x (same shape, no delay)."""
    cfg = _config(config)
    a = _as_real(x, "x")
    if a.ndim not in (1, 2):
        raise InvalidArgument(f"x must have shape (N,) or (N, C), got {a.shape}")
    cols = a.reshape(a.shape[0], -1)
    if cols.shape[1] == 0:
        raise InvalidArgument(f"x has no channel: shape {a.shape}")
    if a.shape[0] < cfg.block:
        raise InvalidArgument(f"x has {a.shape[0]} samples, fewer than one block ({cfg.block})")
    d = Denoiser(cfg, cols.shape[1], precision)
    y = np.vstack([d.update(cols), d.flush()])
    return y.reshape(a.shape)
