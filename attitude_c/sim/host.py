"""Stage 7 of the simulator (docs/architecture.md): the host's decoding.

What the Linux computer does with the delivered records before it
integrates: the library's block decoder and sequence tracker number them
(``att_block_seq_decode`` through :class:`attitude_c.link.block.SeqTracker`,
the stream's OVERSAMPLE included), and the library's sensor converter turns
each sample's words into angle increments (``att_sensor_increments`` through
:class:`attitude_c.sensor.Sensor`) — the same C that ``attitude-rx`` runs.
Samples the stream reports lost (GAVE_UP, OVERRUN, ADC_ERROR, a sample above
its stream's limit) are filled as ``attitude-rx`` fills them: the last good
sample is held over them (before the first good sample there is nothing to
hold). Samples lost without a report (the modeled board's link gave up) are
simply missing.

:class:`Calibration` is the host's knowledge of the gyros: the zero-rate
reading per channel (measured while the gyros sit still) and the nominal
rad/s per code.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..link import block
from ..sensor import Sensor
from .link import Delivered

__all__ = ["Calibration", "Decoded", "HostDecoder"]


@dataclass
class Calibration:
    """``zero``: the zero-rate reading per channel in codes of one conversion (3,);
    ``rad_per_s_per_code``: the nominal scale; ``oversample``: conversions per word
    of the stream it was measured on (for the record only: the stream says n)."""

    zero: np.ndarray
    rad_per_s_per_code: float
    oversample: int = 1

    @classmethod
    def from_static(cls, words: np.ndarray, oversample: int, rad_per_s_per_code: float) -> Calibration:
        """The mean of the words (n, 3) of still gyros, per conversion."""
        return cls(np.asarray(words, dtype=float).mean(axis=0) / oversample, rad_per_s_per_code, oversample)

    def sensor(self) -> Sensor:
        return Sensor(self.zero, self.rad_per_s_per_code)

    def to_dict(self) -> dict[str, Any]:
        return {"zero_code": np.asarray(self.zero).tolist(), "rad_per_s_per_code": self.rad_per_s_per_code,
                "oversample": self.oversample}


@dataclass
class Decoded:
    """The host's increments: ``increments`` (m, 3) rad, one per sample period it
    integrates; ``sample_index`` (m,) the true sample number of each; ``words``
    (m, 3) the words behind each; ``held`` the sample numbers filled by holding;
    ``reports`` the kinds of the report records, in order."""

    increments: np.ndarray
    sample_index: np.ndarray
    words: np.ndarray
    held: list[int] = field(default_factory=list)
    reports: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class HostDecoder:
    """Delivered records → increments, with the ``calibration`` and the sample ``period`` (s)."""

    calibration: Calibration
    period: float

    def decode(self, delivered: Delivered, stream_sample: np.ndarray | None = None) -> Decoded:
        """Decode and number ``delivered``. ``stream_sample`` (the board stream's
        record → sample map) with ``delivered.source`` gives each delivered sample
        its true number (a duplicate or an unreported loss shifts the stream's own
        numbering, not the truth); without them the stream's numbering is the truth."""
        tr = block.SeqTracker()
        rows: list[tuple[int, int, tuple[int, int, int], bool]] = []  # (number, n, words, held)
        held: list[int] = []
        reports: list[str] = []
        last: tuple[int, tuple[int, int, int]] | None = None
        for j, raw in enumerate(delivered.records):
            rec, span, st = tr.decode(raw)
            if rec is None or span is None:
                continue  # no place in the numbering (a record that breaks the format)
            if rec.kind == "sample" and st == 0:
                k = span.first
                if stream_sample is not None and delivered.source is not None:
                    k = int(stream_sample[delivered.source[j]])
                last = (tr.oversample, rec.codes)
                rows.append((k, last[0], last[1], False))
                continue
            if rec.kind != "sample":
                reports.append(rec.kind)
            if (rec.is_loss or rec.kind == "sample") and last is not None:  # a sample never to integrate
                for k in range(span.first, span.first + span.count):
                    rows.append((k, last[0], last[1], True))
                    held.append(k)
        number = np.array([r[0] for r in rows], dtype=np.int64)
        words = np.array([r[2] for r in rows], dtype=np.int64).reshape(-1, 3)
        n_of = np.array([r[1] for r in rows], dtype=np.int64)
        inc = np.zeros((len(rows), 3))
        sensor = self.calibration.sensor()
        for n in np.unique(n_of):
            sel = n_of == n
            inc[sel] = sensor.increments(words[sel], int(n), self.period)
        return Decoded(inc, number, words, held, reports)
