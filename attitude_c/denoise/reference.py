"""Independent NumPy (float64) reference of the wavelet threshold denoiser.

Written from the mathematics (docs/denoise.md), not from the C source, and
by different routes where one exists:

* the Daubechies scaling filters are *derived* here by spectral
  factorization of Daubechies' polynomial P(y) = Σ_{k<p} C(p−1+k, k) y^k
  (Daubechies 1992, sec. 6.1), keeping the zeros inside the unit circle
  (the extremal-phase choice); the C library holds them as literals;
* one level of the periodized transform is an explicit n × n orthogonal
  matrix (rows: the shifted, periodized scaling and wavelet functions), so
  reconstruction is its transpose; the C library filters and decimates in
  loops and reconstructs by scatter-adding;
* the median is ``numpy.median`` (a sort); the C library selects in place;
* the noise constant Φ⁻¹(3/4) comes from ``statistics.NormalDist``;
* the least-squares line comes from ``numpy.linalg.lstsq``;
* the stream is cut into windows from the index formulas of
  docs/denoise.md in one pass over the whole record; the C library is a
  ring-buffer state machine fed one sample at a time.

The phase of the periodized filtering is the one PyWavelets uses in its
``periodization`` mode, so that the coefficients can be compared with
``pywt.wavedec(x, wavelet, mode="periodization", level=L)`` one by one.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from statistics import NormalDist

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "MAD_NORMAL",
    "VANISHING_MOMENTS",
    "Windowing",
    "analysis_matrix",
    "daubechies",
    "denoise",
    "denoise_block",
    "filter_bank",
    "mad_sigma",
    "threshold",
    "universal_threshold",
    "wavedec",
    "waverec",
    "windows",
]

F = NDArray[np.float64]

#: Vanishing moments p of each wavelet (Haar = Daubechies with p = 1;
#: db2 is the 4-tap "D4", db4 the 8-tap filter).
VANISHING_MOMENTS = {"haar": 1, "db2": 2, "db4": 4}

#: Φ⁻¹(3/4): the median of |N(0, σ²)| is σ Φ⁻¹(3/4), so σ = median|d| / this.
MAD_NORMAL = NormalDist().inv_cdf(0.75)


def daubechies(p: int) -> F:
    """Extremal-phase Daubechies scaling filter h (2p taps, Σh = √2).

    |H(ω)|² = 2 cos^{2p}(ω/2) P(sin²(ω/2)) with P as above. With
    y = (2 − z − 1/z)/4 each root y_i of P gives the pair z, 1/z of
    z² − (2 − 4 y_i) z + 1 = 0; keeping the root with |z| < 1 gives
    H(z) ∝ (1 + z⁻¹)^p Π (1 − z_i z⁻¹), h[k] its coefficient of z⁻ᵏ."""
    if p == 1:
        return np.array([1.0, 1.0]) / math.sqrt(2.0)
    # np.roots wants the highest power first
    coeffs = [math.comb(p - 1 + k, k) for k in range(p)][::-1]
    zeros = []
    for y in np.roots(coeffs):
        b = 2.0 - 4.0 * y
        z1 = (b + np.sqrt(b * b - 4.0 + 0j)) / 2.0
        zeros.append(z1 if abs(z1) < 1 else 1.0 / z1)
    poly = np.array([1.0 + 0j])
    for z in zeros:
        poly = np.convolve(poly, [1.0, -z])
    for _ in range(p):
        poly = np.convolve(poly, [1.0, 1.0])
    h = np.real(poly)
    return h * (math.sqrt(2.0) / h.sum())


def filter_bank(wavelet: str) -> tuple[F, F]:
    """(h, g): scaling filter and wavelet filter g[k] = (−1)^k h[F−1−k]."""
    h = daubechies(VANISHING_MOMENTS[wavelet])
    k = np.arange(len(h))
    g = (-1.0) ** k * h[::-1]
    return h, g


def analysis_matrix(n: int, wavelet: str) -> F:
    """One level of the periodized DWT as an n × n matrix (n even).

    Row i < n/2 is the scaling function φ_i[t] = Σ_m h[m] δ[t − (2i + m + 1 − F/2) mod n],
    row n/2 + i the wavelet function ψ_i (g in place of h). The shift
    1 − F/2 is PyWavelets' periodization phase. The rows are orthonormal
    (the filters' double-shift orthogonality), so the inverse is the
    transpose."""
    return _analysis_matrix(n, wavelet).copy()


@functools.lru_cache(maxsize=64)
def _analysis_matrix(n: int, wavelet: str) -> F:
    h, g = filter_bank(wavelet)
    f = len(h)
    W = np.zeros((n, n))
    for i in range(n // 2):
        for m in range(f):
            t = (2 * i + m + 1 - f // 2) % n
            W[i, t] += h[m]
            W[n // 2 + i, t] += g[m]
    return W


def wavedec(x: ArrayLike, wavelet: str, levels: int) -> list[F]:
    """[cA_L, cD_L, …, cD_1] of a block (length divisible by 2^levels)."""
    a = np.asarray(x, dtype=np.float64)
    n = len(a)
    if levels < 1 or n % (1 << levels):
        raise ValueError(f"block length {n} is not a multiple of 2^{levels}")
    details: list[F] = []
    for _ in range(levels):
        c = _analysis_matrix(len(a), wavelet) @ a
        a, d = c[: len(c) // 2], c[len(c) // 2:]
        details.append(d)
    return [a, *details[::-1]]


def waverec(coeffs: list[F], wavelet: str) -> F:
    """Inverse of :func:`wavedec` (transposes of the analysis matrices)."""
    a = np.asarray(coeffs[0], dtype=np.float64)
    for d in coeffs[1:]:
        c = np.concatenate([a, np.asarray(d, dtype=np.float64)])
        a = _analysis_matrix(len(c), wavelet).T @ c
    return a


def mad_sigma(d: ArrayLike) -> float:
    """Noise level from the finest details: median(|d|) / Φ⁻¹(3/4)
    (Donoho & Johnstone 1994; the details of white noise are N(0, σ²))."""
    return float(np.median(np.abs(np.asarray(d, dtype=np.float64)))) / MAD_NORMAL


def universal_threshold(sigma: float, n: int) -> float:
    """λ = σ √(2 ln n) for a block of n samples."""
    return sigma * math.sqrt(2.0 * math.log(n))


def threshold(c: ArrayLike, lam: float, mode: str) -> F:
    """soft: sign(c)·max(|c| − λ, 0); hard: c where |c| ≥ λ, else 0."""
    a = np.asarray(c, dtype=np.float64)
    if mode == "soft":
        return np.sign(a) * np.maximum(np.abs(a) - lam, 0.0)
    if mode == "hard":
        return np.where(np.abs(a) >= lam, a, 0.0)
    raise ValueError(f"mode must be 'soft' or 'hard', got {mode!r}")


def _line(n: int, x: F) -> F:
    """Least-squares line a + b t through the block (t = 0..n−1)."""
    t = np.arange(n, dtype=np.float64)
    A = np.column_stack([np.ones(n), t])
    coef, *_ = np.linalg.lstsq(A, x, rcond=None)
    return A @ coef


def denoise_block(x: ArrayLike, wavelet: str, levels: int, mode: str,
                  detrend: bool) -> tuple[F, float]:
    """One block: (optionally) remove the least-squares line, decompose,
    σ from the finest details, threshold every detail level with the
    universal threshold, reconstruct, add the line back. Returns (y, σ)."""
    u = np.asarray(x, dtype=np.float64)
    line = _line(len(u), u) if detrend else np.zeros(len(u))
    c = wavedec(u - line, wavelet, levels)
    sigma = mad_sigma(c[-1])
    lam = universal_threshold(sigma, len(u))
    y = waverec([c[0]] + [threshold(d, lam, mode) for d in c[1:]], wavelet)
    return y + line, sigma


@dataclass(frozen=True)
class Windowing:
    """Where each window of a record of ``total`` samples lies: window
    [start, start + block) outputs [out_start, out_stop) of the record."""

    start: int
    out_start: int
    out_stop: int


def windows(total: int, block: int, edge_start: int, edge_end: int) -> list[Windowing]:
    """The windows of docs/denoise.md: hop H = block − edge_start − edge_end;
    window k ≥ 0 covers [kH, kH + block) and outputs
    [kH + edge_start, kH + block − edge_end), except window 0, which outputs
    from 0 (the record's start is a true edge); a final window over the last
    ``block`` samples outputs what is left up to the end."""
    hop = block - edge_start - edge_end
    if total < block:
        raise ValueError(f"a record of {total} samples is shorter than one block ({block})")
    out: list[Windowing] = []
    k = 0
    while k * hop + block <= total:
        s = k * hop
        out.append(Windowing(s, 0 if k == 0 else s + edge_start, s + block - edge_end))
        k += 1
    done = out[-1].out_stop
    if done < total:
        out.append(Windowing(total - block, done, total))
    return out


def denoise(x: ArrayLike, wavelet: str = "db4", levels: int = 3, block: int = 64,
            edge_start: int = 24, edge_end: int = 8, mode: str = "soft", detrend: bool = True) -> F:
    """Denoise a record (N,) or (N, C) column by column, window by window.

    Each output segment is the window's denoised samples plus the constant
    that makes the segment's sum equal the input's over the same samples."""
    a = np.asarray(x, dtype=np.float64)
    cols = a.reshape(len(a), -1)
    y = np.empty_like(cols)
    for w in windows(len(a), block, edge_start, edge_end):
        for j in range(cols.shape[1]):
            u = cols[w.start: w.start + block, j]
            v, _ = denoise_block(u, wavelet, levels, mode, detrend)
            seg = slice(w.out_start - w.start, w.out_stop - w.start)
            corr = (u[seg].sum() - v[seg].sum()) / (w.out_stop - w.out_start)
            y[w.out_start: w.out_stop, j] = v[seg] + corr
    return y.reshape(a.shape)
