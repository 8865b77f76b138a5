"""The wavelet denoiser (attitude_c.denoise over csrc/src/denoise*.c) against
PyWavelets (the oracle for the block pieces: same block, same wavelet,
``mode="periodization"``) and against the independent NumPy reference
(attitude_c.denoise.reference) for the detrending and the stream, in the
double and the float build.

Tolerances (``_tol``): one level of the transform forms each coefficient
as a sum of F products; in floating point that sum errs by at most
F·u·Σ|h_k||x_k| ≤ F·u·‖h‖₁·max|x| (u the unit roundoff), and the magnitude
bound grows by ‖h‖₁ per level, so L levels err by ≤ L·F·u·‖h‖₁^L·max|x|.
Two implementations (C and PyWavelets or the reference, both in float64
for the f64 build) and filter literals that may differ by an ulp double
that; a factor 2 on top is margin. For the f32 build the oracle works in
float64 on the same float32-rounded input, so the C code's float32
rounding (u = 2^-24) is the whole error.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pywt = pytest.importorskip("pywt", reason="needs PyWavelets: pip install PyWavelets (test extra)")

from attitude_c import InvalidArgument, InvalidType, NonFiniteError, RangeError
from attitude_c import denoise as D
from attitude_c._lib import ffi_lib
from attitude_c.denoise import reference as R

U = {"f64": 2.0 ** -53, "f32": 2.0 ** -24}
PRECISIONS = ("f64", "f32")


def _l1(wavelet: str) -> float:
    return float(np.abs(R.filter_bank(wavelet)[0]).sum())


def _tol(wavelet: str, levels: int, scale: float, precision: str) -> float:
    """Bound of the module docstring: 4·L·F·u·‖h‖₁^L·scale."""
    f = 2 * R.VANISHING_MOMENTS[wavelet]
    return 4.0 * levels * f * U[precision] * _l1(wavelet) ** levels * scale


def _f32(x: np.ndarray) -> np.ndarray:
    return np.asarray(x, dtype=np.float32).astype(np.float64)


SHAPES = [(2, 1), (4, 2), (8, 3), (64, 3), (96, 5), (256, 4), (1024, 6)]


# -- filters -----------------------------------------------------------------

@pytest.mark.parametrize("wavelet", D.WAVELETS)
def test_filters_match_pywt_and_the_derivation(wavelet: str) -> None:
    h, g = D.filters(wavelet)
    w = pywt.Wavelet(wavelet)
    # the literals are correctly rounded 25-digit values; PyWavelets' and the
    # float64 spectral factorization differ from them by a few ulps
    np.testing.assert_allclose(h, w.rec_lo, rtol=0, atol=4 * U["f64"])
    np.testing.assert_allclose(g, w.rec_hi, rtol=0, atol=4 * U["f64"])
    hr, gr = R.filter_bank(wavelet)
    np.testing.assert_allclose(h, hr, rtol=0, atol=8 * U["f64"])
    np.testing.assert_allclose(g, gr, rtol=0, atol=8 * U["f64"])


def test_filter_literals_are_the_high_precision_solution() -> None:
    """csrc/src/denoise.c holds toolchain.wavelet_constants' 50-digit Newton
    solution of the defining equations, rounded to double: exactly."""
    from toolchain.wavelet_constants import TABLES, daubechies_decimal

    for name, p in TABLES.items():
        exact = np.array([float(v) for v in daubechies_decimal(p)])
        assert np.array_equal(D.filters(name)[0], exact), name


# -- the block pieces against PyWavelets ---------------------------------------------

@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("wavelet", D.WAVELETS)
@pytest.mark.parametrize(("n", "levels"), SHAPES)
def test_wavedec_waverec_match_pywt(wavelet: str, n: int, levels: int, precision: str) -> None:
    rng = np.random.default_rng(n * 31 + levels)
    x = _f32(rng.normal(size=n) * 3.0 + 1.0)
    scale = float(np.max(np.abs(x)))
    tol = _tol(wavelet, levels, scale, precision)
    ours = D.wavedec(x, wavelet, levels, precision=precision)
    with pytest.warns(UserWarning) if levels > pywt.dwt_max_level(n, wavelet) else _nowarn():
        theirs = pywt.wavedec(x, wavelet, mode="periodization", level=levels)
    assert [len(a) for a in ours] == [len(b) for b in theirs]
    for a, b in zip(ours, theirs):
        np.testing.assert_allclose(a, b, rtol=0, atol=tol)
    back = D.waverec(ours, wavelet, precision=precision)
    np.testing.assert_allclose(back, pywt.waverec(theirs, wavelet, mode="periodization"), rtol=0, atol=2 * tol)
    np.testing.assert_allclose(back, x, rtol=0, atol=2 * tol)  # perfect reconstruction
    # the reference's matrices agree as well
    for a, b in zip(ours, R.wavedec(x, wavelet, levels)):
        np.testing.assert_allclose(a, b, rtol=0, atol=tol)


class _nowarn:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: object) -> None:
        return None


@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("mode", D.THRESHOLDS)
def test_threshold_matches_pywt(mode: str, precision: str) -> None:
    rng = np.random.default_rng(7)
    c = _f32(rng.normal(size=500))
    lam = 0.75  # exactly representable; no |c| within a float32 ulp of it (checked)
    assert np.min(np.abs(np.abs(c) - lam)) > 1e-6
    ours = D.threshold(c, lam, mode, precision=precision)
    # one rounding in the C code, a different one in pywt's c·(1 − λ/|c|)
    np.testing.assert_allclose(ours, pywt.threshold(c, lam, mode=mode), rtol=0, atol=4 * U[precision] * 4)
    np.testing.assert_array_equal(ours, R.threshold(c, lam, mode).astype(np.float32 if precision == "f32"
                                                                          else np.float64))
    assert np.array_equal(D.threshold(c, 0.0, "soft"), c)


def test_noise_sigma_and_universal_threshold() -> None:
    rng = np.random.default_rng(11)
    for n in (1, 2, 5, 64, 101, 1000):
        d = rng.normal(size=n) * 0.3
        # median of n values: the same order statistics, one rounding each way
        assert D.noise_sigma(d) == pytest.approx(R.mad_sigma(d), rel=4 * U["f64"])
        assert D.noise_sigma(d, precision="f32") == pytest.approx(R.mad_sigma(_f32(d)), rel=8 * U["f32"])
    assert R.MAD_NORMAL == pytest.approx(0.6744897501960817, rel=1e-15)
    assert D.universal_threshold(2.0, 256) == pytest.approx(2.0 * math.sqrt(2 * math.log(256)), rel=4 * U["f64"])
    # white noise of σ = 1 has MAD σ ≈ 1 (within 3 standard errors: 1.1/√n... for n = 20 000: ±0.02)
    assert D.noise_sigma(np.random.default_rng(3).normal(size=20_000)) == pytest.approx(1.0, abs=0.025)


def _pywt_block(x: np.ndarray, wavelet: str, levels: int, mode: str) -> tuple[np.ndarray, float, float]:
    """The textbook chain with PyWavelets: wavedec, σ = median|cD1|/0.6745, λ = σ√(2 ln n),
    threshold every detail level, waverec. Returns (y, σ, λ)."""
    c = pywt.wavedec(x, wavelet, mode="periodization", level=levels)
    sigma = float(np.median(np.abs(c[-1]))) / R.MAD_NORMAL
    lam = sigma * math.sqrt(2 * math.log(len(x)))
    y = pywt.waverec([c[0]] + [pywt.threshold(d, lam, mode=mode) for d in c[1:]], wavelet,
                     mode="periodization")
    return y, sigma, lam


@pytest.mark.filterwarnings("ignore:Level value of 7 is too high")  # pywt: a wrapping filter is fine here
@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("mode", D.THRESHOLDS)
@pytest.mark.parametrize("wavelet", D.WAVELETS)
@pytest.mark.parametrize(("n", "levels"), [(64, 3), (256, 4), (128, 7)])
def test_denoise_block_matches_pywt(wavelet: str, mode: str, n: int, levels: int, precision: str) -> None:
    """Decomposition, thresholding and reconstruction of one block, no detrending."""
    t = np.arange(n) / n
    for seed in range(20):  # the first seed without a coefficient at the hard threshold's jump
        rng = np.random.default_rng(seed)
        x = _f32(np.sin(2 * np.pi * 3 * t) + 0.4 * (t > 0.55) + 0.1 * rng.normal(size=n))
        y_ref, sigma_ref, lam = _pywt_block(x, wavelet, levels, mode)
        tol = _tol(wavelet, levels, float(np.max(np.abs(x))), precision)
        details = np.concatenate(pywt.wavedec(x, wavelet, mode="periodization", level=levels)[1:])
        if np.min(np.abs(np.abs(details) - lam)) > 10 * tol:
            break
    else:  # pragma: no cover - would need a different signal
        pytest.fail("every seed puts a coefficient at the threshold")
    y, sigma = D.denoise_block(x, D.DenoiseConfig(wavelet=wavelet, levels=levels, block=n, edge_start=0, edge_end=0,
                                                  threshold=mode, detrend=False), precision=precision)
    # σ: a median of coefficients each good to tol, divided once
    assert sigma == pytest.approx(sigma_ref, abs=tol / R.MAD_NORMAL + 4 * U[precision] * sigma_ref)
    # y: the transform's bound, plus λ's error (tol·√(2 ln n)/0.6745) moved into
    # every shrunk coefficient, through the orthonormal inverse (gain ≤ √n·max)
    lam_err = tol / R.MAD_NORMAL * math.sqrt(2 * math.log(n)) * math.sqrt(n)
    np.testing.assert_allclose(y, y_ref, rtol=0, atol=2 * tol + lam_err)


@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("wavelet", D.WAVELETS)
def test_denoise_block_with_detrend_matches_reference(wavelet: str, precision: str) -> None:
    rng = np.random.default_rng(5)
    n, levels = 128, 4
    x = _f32(0.5 + 0.01 * np.arange(n) + 0.05 * rng.normal(size=n))
    y, sigma = D.denoise_block(x, D.DenoiseConfig(wavelet=wavelet, levels=levels, block=n, edge_start=0,
                                                  edge_end=0),
                               precision=precision)
    y_ref, sigma_ref = R.denoise_block(x, wavelet, levels, "soft", True)
    scale = float(np.max(np.abs(x)))
    # the line fit adds a few roundings per sample on top of the transform (factor 2)
    tol = 2 * _tol(wavelet, levels, scale, precision)
    assert sigma == pytest.approx(sigma_ref, abs=tol)
    np.testing.assert_allclose(y, y_ref, rtol=0, atol=tol * (1 + math.sqrt(2 * math.log(n)) * math.sqrt(n)))
    assert abs(y.sum() - x.sum()) <= n * tol  # details have zero sum: the block's sum is kept


# -- the stream -----------------------------------------------------------------

CONFIGS = [
    D.DenoiseConfig(),
    D.DenoiseConfig(edge_start=0, edge_end=0),
    D.DenoiseConfig(wavelet="haar", levels=2, block=32, edge_start=3, edge_end=3, threshold="hard"),
    D.DenoiseConfig(wavelet="db2", levels=4, block=128, edge_start=40, edge_end=30, detrend=False),
    D.DenoiseConfig(block=64, edge_start=2, edge_end=61),
]


@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("cfg", CONFIGS, ids=lambda c: f"{c.wavelet}-L{c.levels}-N{c.block}-E{c.edge_start},{c.edge_end}-"
                                                        f"{c.threshold}-{'d' if c.detrend else 'nod'}")
def test_stream_matches_reference(cfg: D.DenoiseConfig, precision: str) -> None:
    rng = np.random.default_rng(cfg.block + cfg.edge_start)
    n = 1000 + cfg.edge_end  # not a multiple of the hop: the flush window overlaps the last one
    t = np.arange(n) * 0.005
    x = _f32(np.column_stack([0.2 * np.sin(2 * np.pi * 0.4 * t), 0.01 + 0 * t, -0.3 + 0.02 * t])
             + 0.01 * rng.normal(size=(n, 3)))
    y = D.denoise(x, cfg, precision=precision)
    y_ref = R.denoise(x, cfg.wavelet, cfg.levels, cfg.block, cfg.edge_start, cfg.edge_end,
                        cfg.threshold, cfg.detrend)
    scale = float(np.max(np.abs(x)))
    # per window as the block test above, plus the segment constant (sums of ≤ N terms)
    tol = 2 * _tol(cfg.wavelet, cfg.levels, scale, precision) * (
        1 + math.sqrt(2 * math.log(cfg.block)) * math.sqrt(cfg.block)) + 4 * cfg.block * U[precision] * scale
    if precision == "f32" and cfg.threshold == "hard":
        # a float32 rounding can move a coefficient across λ: the output then
        # differs by that coefficient's basis function (≤ λ·max|φ|); allow it
        # on at most a few samples
        bad = np.abs(y - y_ref) > tol
        assert bad.sum() <= 3 * cfg.block, bad.sum()
    else:
        np.testing.assert_allclose(y, y_ref, rtol=0, atol=tol)
    # the mean is kept: every output segment has the input's sum
    np.testing.assert_allclose(y.mean(axis=0), x.mean(axis=0), rtol=0, atol=4 * cfg.block * U[precision] * scale)


@pytest.mark.parametrize("cfg", CONFIGS[:4], ids=lambda c: f"{c.wavelet}-N{c.block}-{c.threshold}")
def test_stream_matches_pywt_per_window(cfg: D.DenoiseConfig) -> None:
    """The whole stream with PyWavelets doing every block (bench/denoise.py's
    pywt_stream: the windows of the reference, the line fit in closed form)."""
    from bench.denoise import pywt_stream

    rng = np.random.default_rng(4)
    x = 0.01 + np.cumsum(rng.normal(size=(900, 3)), axis=0) * 1e-3
    y = D.denoise(x, cfg)
    scale = float(np.max(np.abs(x)))
    # as test_stream_matches_reference (f64)
    tol = 2 * _tol(cfg.wavelet, cfg.levels, scale, "f64") * (
        1 + math.sqrt(2 * math.log(cfg.block)) * math.sqrt(cfg.block)) + 4 * cfg.block * U["f64"] * scale
    np.testing.assert_allclose(y, pywt_stream(x, cfg), rtol=0, atol=tol)


def test_stream_bursts_latency_and_segment_sums() -> None:
    cfg = D.DenoiseConfig(levels=3, block=64, edge_start=24, edge_end=8)  # hop 32
    rng = np.random.default_rng(2)
    x = 0.3 + 0.01 * rng.normal(size=(700, 2))
    d = D.Denoiser(cfg, channels=2)
    assert d.latency == cfg.latency == 39 and cfg.hop == 32
    assert cfg.latency_s(200.0) == pytest.approx(0.195)
    assert D.DenoiseConfig().latency == 71  # the defaults: N − 1 − Es = 128 − 1 − 56
    done = 0
    for i in range(len(x)):
        assert d.outputs(1) in (0, 32, 56)
        out = d.update(x[i])
        if len(out):
            # the burst is samples [done, done + len) and its first sample waited
            # N − 1 − Es samples (N − 1 for the first window)
            assert i - done == (63 if done == 0 else 39)
            assert len(out) == (56 if done == 0 else 32)
            np.testing.assert_allclose(out.sum(axis=0), x[done: done + len(out)].sum(axis=0), rtol=1e-14)
            done += len(out)
        assert d.pending == i + 1 - done
    assert d.windows == 1 + (700 - 64) // 32
    assert np.all(d.sigma > 0.005) and np.all(d.sigma < 0.02)  # σ = 0.01 estimated per window
    rest = d.flush()
    assert len(rest) == 700 - done and d.pending == 0 and d.windows == 0


def test_stream_chunking_does_not_matter() -> None:
    rng = np.random.default_rng(9)
    x = rng.normal(size=(777, 3))
    whole = D.denoise(x)
    d = D.Denoiser()
    parts = []
    i = 0
    for k in [1, 5, 63, 64, 100, 3, 200, 341]:
        parts.append(d.update(x[i: i + k]))
        i += k
    assert i == len(x)
    parts.append(d.flush())
    assert np.array_equal(np.vstack(parts), whole)
    # and one channel at a time is the same as three together
    assert np.array_equal(D.denoise(x[:, 1]), whole[:, 1])


@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("wavelet", D.WAVELETS)
@pytest.mark.parametrize("threshold", D.THRESHOLDS)
def test_constants_and_ramps_pass_unchanged(wavelet: str, threshold: str, precision: str) -> None:
    n = 1000
    t = np.arange(n)
    # a slope of 2^-9: the ramp is exact in float32 too (a rounded ramp is not a ramp)
    x = _f32(np.column_stack([np.full(n, 0.0123), 1.5 - t / 512, -3.0 + 0 * t]))
    for edges in ((0, 0), (24, 8), (5, 30)):
        cfg = D.DenoiseConfig(wavelet=wavelet, threshold=threshold, edge_start=edges[0], edge_end=edges[1])
        y = D.denoise(x, cfg, precision=precision)
        # the line fit and its restoration: a few roundings per sample of
        # values ≤ 3, plus the transform of a residual at rounding level
        np.testing.assert_allclose(y, x, rtol=0, atol=64 * U[precision] * 3 * _l1(wavelet) ** 3)


def test_denoising_reduces_white_noise() -> None:
    """The point of it: on white noise, the defaults cut the RMS to ~0.3 and the
    peak-to-peak to ~0.3 (docs/denoise.md); the mean is untouched."""
    rng = np.random.default_rng(1)
    x = 0.05 + 0.01 * rng.normal(size=(20_000, 1))
    y = D.denoise(x)
    assert np.std(y) / np.std(x) < 0.45
    assert np.ptp(y) / np.ptp(x) < 0.5
    assert abs(y.mean() - x.mean()) < 1e-15


# -- configuration and errors ------------------------------------------------------------

def test_defaults_come_from_the_library() -> None:
    ffi, lib = ffi_lib("f64")
    c = ffi.new("att_wden_config *")
    lib.att_wden_config_default(c)
    cfg = D.DenoiseConfig()
    assert (cfg.levels, cfg.block, cfg.edge_start, cfg.edge_end, cfg.detrend) == (
        c.levels, c.block, c.edge_start, c.edge_end, bool(c.detrend))
    assert D.WAVELETS.index(cfg.wavelet) == c.wavelet == lib.ATT_WDEN_DB4
    assert D.THRESHOLDS.index(cfg.threshold) == c.mode == lib.ATT_WDEN_SOFT
    assert len(D.WAVELETS) == lib.ATT_WDEN_WAVELET_COUNT and len(D.THRESHOLDS) == lib.ATT_WDEN_MODE_COUNT
    codes = [getattr(lib, n) for n in dir(lib) if n.startswith("ATT_E_WDEN_")]
    assert codes and all(-179 <= v <= -160 for v in codes)  # the range common.h reserves


@pytest.mark.parametrize(("kw", "exc", "words"), [
    ({"wavelet": "db8"}, InvalidArgument, "wavelet"),
    ({"wavelet": 2}, InvalidType, "wavelet"),
    ({"threshold": "garrote"}, InvalidArgument, "threshold"),
    ({"levels": 0}, InvalidArgument, "levels"),
    ({"levels": 17}, InvalidArgument, "levels"),
    ({"levels": 2.0}, InvalidType, "levels"),
    ({"levels": True}, InvalidType, "levels"),
    ({"block": 60}, InvalidArgument, r"multiple of 2\*\*levels"),
    ({"block": 1 << 15}, InvalidArgument, "block"),
    ({"edge_start": 100, "edge_end": 28}, InvalidArgument, "edge_start \\+ edge_end"),
    ({"edge_start": -1}, InvalidArgument, "edge_start"),
    ({"edge_end": 2.5}, InvalidType, "edge_end"),
    ({"detrend": 1}, InvalidType, "detrend"),
])
def test_config_errors_name_the_field(kw: dict, exc: type, words: str) -> None:
    with pytest.raises(exc, match=words):
        D.DenoiseConfig(**kw)


def test_argument_errors() -> None:
    x = np.zeros((200, 3))
    with pytest.raises(InvalidArgument, match="fewer than one block"):
        D.denoise(x[:127])
    with pytest.raises(InvalidArgument, match=r"shape \(N,\) or \(N, C\)"):
        D.denoise(np.zeros((200, 3, 1)))
    with pytest.raises(InvalidType, match="real numbers"):
        D.denoise(np.array(["a"] * 200))
    bad = x.copy()
    bad[70, 2] = np.nan
    with pytest.raises(NonFiniteError, match="sample 70") as ei:
        D.denoise(bad)
    assert ei.value.index == 70
    with pytest.raises(RangeError, match="float32"):
        D.denoise(np.full(200, 1e300), precision="f32")
    with pytest.raises(RangeError, match="overflows"):
        D.denoise(np.full(200, 1e306))  # finite, but τ·x of the line fit overflows
    with pytest.raises(InvalidType, match="config"):
        D.denoise(x, config={"block": 64})  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="precision"):
        D.denoise(x, precision="f16")
    d = D.Denoiser(channels=3)
    with pytest.raises(InvalidArgument, match=r"\(M, 3\)"):
        d.update(np.zeros((4, 2)))
    d.update(np.zeros((10, 3)))
    with pytest.raises(InvalidArgument, match="only 10 samples"):
        d.flush()
    assert d.pending == 10  # nothing lost by the failed flush
    with pytest.raises(InvalidArgument, match="multiple of 2\\*\\*levels"):
        D.wavedec(np.zeros(60), "db4", 3)
    with pytest.raises(InvalidArgument, match=r"coeffs\[2\]"):
        D.waverec([np.zeros(8), np.zeros(8), np.zeros(8)])
    with pytest.raises(InvalidArgument, match="value must be >= 0"):
        D.threshold(np.zeros(4), -1.0)
    with pytest.raises(NonFiniteError, match="value"):
        D.threshold(np.zeros(4), float("inf"))
    with pytest.raises(InvalidArgument, match="mode"):
        D.threshold(np.zeros(4), 1.0, "medium")  # type: ignore[arg-type]


def test_overflow_resets_the_stream() -> None:
    d = D.Denoiser(channels=1)
    d.update(np.zeros((30, 1)))
    with pytest.raises(RangeError, match="reset"):
        d.update(np.full((140, 1), 1e306))
    assert d.pending == 0
