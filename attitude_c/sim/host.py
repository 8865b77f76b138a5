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

The accelerometer and the magnetometer (:mod:`attitude_c.sim.accelmag`) do
not travel over the paper's link, which carries the three gyro words: the
host reads them itself, as the UAV thesis's S3C2440 reads its AD7927 over
SPI and its HMR3000 over a UART. An analog part's per-period sums of codes
are converted with the same C converter and the part's nominal zero and
scale (:class:`AuxCalibration`: a gravity or field reference cannot be
zeroed by keeping still, so no calibration run); a digital part's readings
are averaged per period. :class:`AuxStream` holds one such stream, one row
per sample period, beside its exact truth.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..link import block
from ..sensor import Sensor
from .link import Delivered

__all__ = ["AuxCalibration", "AuxStream", "Calibration", "Decoded", "HostDecoder"]


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
class AuxCalibration:
    """An analog vector sensor as the host converts it: ``zero`` the nominal code
    of its zero output per channel (one conversion), ``units_per_code`` (m/s² or
    µT per code)."""

    zero: np.ndarray
    units_per_code: float

    def sensor(self) -> Sensor:
        return Sensor(self.zero, self.units_per_code)

    def convert(self, words: np.ndarray, oversample: int) -> np.ndarray:
        """Words (n, 3), sums of ``oversample`` codes → values (n, 3) (the C converter)."""
        return np.asarray(self.sensor().convert(words, oversample), dtype=float)

    def to_dict(self) -> dict[str, Any]:
        return {"zero_code": np.asarray(self.zero).tolist(), "units_per_code": self.units_per_code}


@dataclass
class AuxStream:
    """One accelerometer or magnetometer stream as the host has it, one row per
    sample period k (spanning [t0 + k h, t0 + (k+1) h]): ``values`` (n, 3) the
    host's reading (the period's mean), ``truth`` (n, 3) the exact mean of the
    measured quantity over the period (specific force, or the geomagnetic field
    without disturbances), ``disturbance`` (n, 3) the mean disturbance field
    (magnetometer; zeros otherwise), ``saturated`` (n,) whether any reading of
    the period hit the range, ``unit``, ``part`` (the model's name), the
    ``calibration`` of an analog part (None: digital) and the part's ``errors``
    drawn for the run (bias, scale, misalignment: the truth of its errors)."""

    name: str
    part: str
    unit: str
    values: np.ndarray
    truth: np.ndarray
    disturbance: np.ndarray
    saturated: np.ndarray
    calibration: AuxCalibration | None = None
    errors: dict[str, Any] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        """Error statistics of the readings against the truth (+ disturbance), per axis,
        over the rows holding a reading (NaN rows: the aided board's samples without one)."""
        e = self.values - self.truth - self.disturbance
        e = e[~np.isnan(e).any(axis=1)]
        return {"part": self.part, "unit": self.unit, "samples": len(e),
                "mean_error": e.mean(axis=0).tolist() if len(e) else [0.0] * 3,
                "rms_error": np.sqrt((e * e).mean(axis=0)).tolist() if len(e) else [0.0] * 3,
                "max_abs_error": np.abs(e).max(axis=0).tolist() if len(e) else [0.0] * 3,
                "saturated_samples": int(np.count_nonzero(self.saturated)),
                "disturbed_samples": int(np.count_nonzero(np.any(self.disturbance != 0, axis=1))),
                "calibration": None if self.calibration is None else self.calibration.to_dict(),
                "errors": self.errors}


@dataclass
class Decoded:
    """The host's increments: ``increments`` (m, 3) rad, one per sample period it
    integrates; ``sample_index`` (m,) the true sample number of each; ``words``
    (m, 3) the words behind each; ``held`` the sample numbers filled by holding;
    ``reports`` the kinds of the report records, in order; ``aux`` the other
    sensors' readings on the same rows (``"accel"`` m/s², ``"mag"`` µT; (m, 3)
    each, the period of ``sample_index``)."""

    increments: np.ndarray
    sample_index: np.ndarray
    words: np.ndarray
    held: list[int] = field(default_factory=list)
    reports: list[str] = field(default_factory=list)
    aux: dict[str, np.ndarray] = field(default_factory=dict)


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
