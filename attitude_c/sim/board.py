"""Stage 5 of the simulator (docs/architecture.md): the acquisition board.

The paper's AT89S51 board (sec. 2, Fig. 1–3) as the simulator models it: it
converts each axis ``oversample`` times per sample period at the midpoints of
equal sub-intervals (delayed by the gyro filter's group delay when
``delay_comp``: the board knows its sensors), sums the codes per axis, and
sends each sample as one record of the library's block format
(docs/block.md): BOOT and an OVERSAMPLE report first, then one sample
record of the three sums per period, encoded by the C encoders
(``att_block_encode_*`` through :mod:`attitude_c.link.block`). The sums keep
their 1/``oversample``-code resolution; a sum the format cannot carry (above
0xFDFF, possible only for 16 conversions within 0.8 % of the ADC's top) is
sent as an ADC_ERROR report in its place, as the firmware does with a code it
cannot encode.

The real firmware (firmware/main.c) does one conversion per period and is an
acquisition source of its own (docs/architecture.md, "Sources").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..errors import InvalidArgument
from ..link import block
from ..names import C

__all__ = ["Board", "BoardStream"]

#: Line rate the modeled board announces in BOOT (the paper's 9600 baud).
BAUD = 9600


@dataclass(frozen=True)
class BoardStream:
    """What the board sends: ``records`` (6 bytes each) in order; ``sample[i]`` is
    the sample number record i stands for (-1 for the header reports BOOT and
    OVERSAMPLE); ``oversample`` conversions per word."""

    records: list[bytes]
    sample: np.ndarray
    oversample: int

    @property
    def header(self) -> int:
        """Number of header reports before the first sample record."""
        return int(np.count_nonzero(self.sample < 0))


@dataclass(frozen=True)
class Board:
    """Increment formation and sample blocks: ``oversample`` conversions per axis
    per period (1..16), at the midpoints of equal sub-intervals (``sample_at="mid"``)
    or at their starts (``"start"``: the naive design), delayed by the gyro
    filter's group delay when ``delay_comp``."""

    oversample: int = 16
    delay_comp: bool = True
    sample_at: Literal["mid", "start"] = "mid"

    def check(self, bits: int) -> None:
        if self.sample_at not in ("mid", "start"):
            raise InvalidArgument(f"sample_at must be 'mid' or 'start', got {self.sample_at!r}")
        if not (isinstance(bits, int) and 1 <= bits <= 12):
            raise InvalidArgument(f"ADC bits must be 1..12 (the block format carries 12-bit codes), got {bits!r}")
        top = block.fmt().oversample_max
        if not (isinstance(self.oversample, int) and 1 <= self.oversample <= top):
            raise InvalidArgument(f"oversample must be 1..{top} (the block format's OVERSAMPLE), "
                                  f"got {self.oversample!r}")

    def instants(self, t0: float, n: int, period: float, delay: float) -> np.ndarray:
        """Conversion instants (n · oversample,) of n periods from t0 (s), shifted by ``delay``."""
        m = self.oversample
        dt = period / m
        frac = 0.5 if self.sample_at == "mid" else 0.0
        return t0 + (np.arange(n * m) + frac) * dt + (delay if self.delay_comp else 0.0)

    def sums(self, codes: np.ndarray) -> np.ndarray:
        """Codes (n · oversample, 3) → the n words per axis (n, 3): the sums of each period's codes."""
        return np.asarray(codes, dtype=np.int64).reshape(-1, self.oversample, 3).sum(axis=1)

    def stream(self, words: np.ndarray, period: float) -> BoardStream:
        """The records of n samples' words (n, 3): BOOT (the period in 1/3600 s ticks,
        rounded: the format's unit), OVERSAMPLE, then one record per sample."""
        m = self.oversample
        f = block.fmt()
        ticks = min(max(1, round(period * f.tick_hz)), f.period_max)
        records = [block.encode_boot(ticks, BAUD), block.encode_oversample(m)]
        w = np.asarray(words, dtype=np.int64).reshape(-1, 3)
        limit = block.sum_limit(m)
        code_error = C["ATT_BLOCK_E_CODE"]
        for k, row in enumerate(w):
            if 0 <= row.min() and row.max() <= limit:
                records.append(block.encode_sums(row.tolist(), m))
            else:  # the format cannot carry it: reported lost in its place
                records.append(block.encode_adc_error(k & 0xFFFF, code_error))
        sample = np.concatenate([np.full(2, -1), np.arange(len(w))]).astype(np.int64)
        return BoardStream(records, sample, m)
