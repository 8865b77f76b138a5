"""Stage 7½ of the simulator (docs/architecture.md): wavelet denoising of the gyro rates.

Between the host's decoding and the estimator: the host's rates
(``Decoded.increments / period``, in the order the host has them) go through
the library's wavelet threshold denoiser (:class:`attitude_c.denoise.Denoiser`,
the C stream of docs/denoise.md: ``update`` then ``flush``) and come back as
increments on the same rows. The denoiser keeps every output segment's sum,
so the integrated angle at each segment boundary is the raw one
(docs/denoise.md, sec. 2 and 5).

Two timings:

* ``"aligned"`` (post-processing): denoised sample k stands for raw sample k;
  the attitude is judged at the same times as without denoising;
* ``"realtime"``: a running system has denoised sample k only
  ``DenoiseConfig.latency`` samples later, so every attitude is judged that
  much later than the interval it integrates (the lag costs rate × latency).

The stage also measures what it did to the rates (peak-to-peak and RMS about
the mean, per axis, before and after; the mean's change) for the summary:
on a still gyro (``--trajectory static``) that is the FPGA+DSP paper's
experiment (sec. 3.4, Fig. 5–6).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Literal, get_args

import numpy as np

from ..denoise import DenoiseConfig, Denoiser
from ..errors import InvalidArgument
from .host import Decoded

__all__ = ["DENOISE_TIMINGS", "Denoise", "DenoiseTiming", "rate_statistics"]

DenoiseTiming = Literal["aligned", "realtime"]
DENOISE_TIMINGS: tuple[str, ...] = get_args(DenoiseTiming)


def rate_statistics(raw: np.ndarray, den: np.ndarray) -> dict[str, Any]:
    """Per axis: peak-to-peak and RMS about the mean of raw and denoised rates
    (rad/s), their ratios, and the change of the mean relative to max |raw|."""
    def ptp(x: np.ndarray) -> np.ndarray:
        return np.ptp(x, axis=0) if len(x) else np.zeros(3)

    def rms(x: np.ndarray) -> np.ndarray:
        return x.std(axis=0) if len(x) else np.zeros(3)

    p0, p1, r0, r1 = ptp(raw), ptp(den), rms(raw), rms(den)
    with np.errstate(divide="ignore", invalid="ignore"):
        pr = np.where(p0 > 0, p1 / p0, np.nan)
        rr = np.where(r0 > 0, r1 / r0, np.nan)
    scale = float(np.max(np.abs(raw))) if len(raw) else 0.0
    dmean = float(np.max(np.abs(den.mean(axis=0) - raw.mean(axis=0)))) if len(raw) else 0.0
    return {"ptp_raw_rad_s": p0.tolist(), "ptp_denoised_rad_s": p1.tolist(), "ptp_ratio": pr.tolist(),
            "rms_raw_rad_s": r0.tolist(), "rms_denoised_rad_s": r1.tolist(), "rms_ratio": rr.tolist(),
            "mean_change_rel": dmean / scale if scale > 0 else 0.0}


@dataclass(frozen=True)
class Denoise:
    """The denoiser as a stage: ``config`` (wavelet, levels, threshold mode, block,
    edges: :class:`attitude_c.denoise.DenoiseConfig`), ``timing``, ``precision``
    of the C build that runs it."""

    config: DenoiseConfig
    timing: DenoiseTiming = "aligned"
    precision: str = "f64"

    def __post_init__(self) -> None:
        if self.timing not in DENOISE_TIMINGS:
            raise InvalidArgument(f"denoise timing must be one of {DENOISE_TIMINGS}, got {self.timing!r}")

    def delay(self, period: float) -> float:
        """How much later than without the stage each attitude is judged (s)."""
        return self.config.latency * period if self.timing == "realtime" else 0.0

    def run(self, decoded: Decoded, period: float) -> tuple[Decoded, dict[str, Any]]:
        """Denoise the rates of ``decoded``; returns the new rows and the stage's summary."""
        n = len(decoded.increments)
        if n < self.config.block:
            raise InvalidArgument(f"denoising needs at least one block of {self.config.block} samples, the run "
                                  f"has {n}: run longer or choose a shorter block")
        raw = np.asarray(decoded.increments, dtype=float) / period
        d = Denoiser(self.config, channels=3, precision=self.precision)
        parts = [d.update(raw), d.flush()]
        den = np.vstack([p for p in parts if len(p)])
        if den.shape != raw.shape:  # the stream returns every sample it took, in order
            raise RuntimeError(f"denoiser returned {den.shape[0]} samples for {n}")
        cfg = self.config
        summary = {"wavelet": cfg.wavelet, "levels": cfg.levels, "threshold": cfg.threshold, "block": cfg.block,
                   "edge_start": cfg.edge_start, "edge_end": cfg.edge_end, "detrend": cfg.detrend,
                   "timing": self.timing, "latency_samples": cfg.latency, "latency_s": cfg.latency * period,
                   "rates": rate_statistics(raw, den)}
        return replace(decoded, increments=den * period), summary
