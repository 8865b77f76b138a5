"""A recording in SI units as the aided board's 12-bit TLC2543 codes, and the
attitude-rx configuration that converts them back (issue 26: real recordings
through the whole chain).

Each channel maps its quantity linearly about mid-scale, then quantizes:

    code = clip(round(ZERO + clip(x, ±limit) · per_unit), lo, hi),   ZERO = 2048

(round to nearest: a TLC2543 with REF+ at the rail, code = round(v / REF+ · 4096);
the zero input is code 2048 exactly). The quantization step is ``1 / per_unit``
(:attr:`CodeChannel.lsb`, in SI units), the error of one code at most half of it
inside the range. The numbers come from the presets, once:

* accelerometer: :data:`attitude_c.sim.frontend.ACCEL_FRONTENDS` ``adxl335``
  (ratiometric, ``codes_per_g``; range ``range_g``; the output's swing to the rails
  ``swing_v`` of ``supply_v``), in m/s²;
* magnetometer: ``MAG_FRONTENDS`` ``hmc1043-ad623`` (``codes_per_ut`` of one set
  conversion about mid-scale; range ``range_gauss``; swing to the rails), in µT;
* gyros: a stated choice, not a preset (the simulator's gyro presets saturate at
  90-300 °/s, and BROAD's fast trials reach 1450 °/s): a ±``gyro_range_dps`` rate
  sensor (default 2000 °/s, the range of BROAD's own IMU) through the simulator's
  :class:`attitude_c.sim.conditioning.Conditioning` (its ``span``: the range uses
  0.9 of the ADC half-range), in rad/s.

:func:`rx_config` writes the ``gyro-*``, ``acc-*``, ``mag-*`` keys of attitude-rx's
configuration (docs/attitude-rx.md) from the same channels: zero 2048, scale
``1 / per_unit`` printed to round trip, so attitude-rx's conversion
``(code − zero) · scale`` is :func:`values` bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidArgument
from .accelmag import G0
from .conditioning import Conditioning
from .frontend import ACCEL_FRONTENDS, MAG_FRONTENDS

__all__ = ["ZERO", "BoardRecording", "CodeChannel", "board_channels", "codes", "resample", "rx_config", "values"]

#: The code of a zero input (mid-scale of the 12-bit range).
ZERO = 2048
_FULL = 4096
_UT_PER_GAUSS = 100.0


@dataclass(frozen=True)
class CodeChannel:
    """One sensor's conversion: ``per_unit`` codes per SI unit about :data:`ZERO`,
    inputs clipped to ±``limit`` (SI: the sensor's range), codes to ``lo``..``hi``
    (the output's swing to the rails)."""

    name: str  #: ``gyro``, ``acc`` or ``mag`` (attitude-rx's key prefix)
    unit: str  #: SI unit of the input
    per_unit: float
    limit: float
    lo: int
    hi: int

    @property
    def lsb(self) -> float:
        """Quantization step in SI units (the scale attitude-rx multiplies by)."""
        return 1.0 / self.per_unit

    @property
    def clip(self) -> float:
        """Largest magnitude represented without clipping (SI): the range or the rails."""
        rails = min(self.hi - ZERO, ZERO - self.lo) / self.per_unit
        return min(self.limit, rails)


def _rails(swing_v: float, supply_v: float) -> tuple[int, int]:
    return math.ceil(swing_v / supply_v * _FULL), math.floor((supply_v - swing_v) / supply_v * _FULL)


def board_channels(gyro_range_dps: float = 2000.0) -> dict[str, CodeChannel]:
    """The aided board's three conversions (see the module docstring)."""
    if not (math.isfinite(gyro_range_dps) and gyro_range_dps > 0):
        raise InvalidArgument(f"gyro_range_dps must be > 0, got {gyro_range_dps!r}")
    acc = ACCEL_FRONTENDS["adxl335"]
    mag = MAG_FRONTENDS["hmc1043-ad623"]
    span = Conditioning().span
    g_range = math.radians(gyro_range_dps)
    return {
        "gyro": CodeChannel("gyro", "rad/s", span * (_FULL / 2) / g_range, g_range, 0, _FULL - 1),
        "acc": CodeChannel("acc", "m/s²", acc.codes_per_g / G0, acc.range_g * G0,
                           *_rails(acc.swing_v, acc.supply_v)),
        "mag": CodeChannel("mag", "µT", mag.codes_per_ut, mag.range_gauss * _UT_PER_GAUSS,
                           *_rails(mag.swing_v, mag.supply_v)),
    }


def codes(x: ArrayLike, ch: CodeChannel) -> NDArray[np.int64]:
    """SI values (N, 3) → the channel's codes (N, 3)."""
    a = np.asarray(x, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3 or not np.all(np.isfinite(a)):
        raise InvalidArgument(f"x must be finite values of shape (N, 3), got shape {a.shape}")
    c = np.rint(ZERO + np.clip(a, -ch.limit, ch.limit) * ch.per_unit)
    return np.clip(c, ch.lo, ch.hi).astype(np.int64)


def values(c: ArrayLike, ch: CodeChannel, n: int = 1) -> NDArray[np.float64]:
    """Codes (sums of ``n`` codes: an oversampled stream's words) → SI values as attitude-rx
    converts them with :func:`rx_config`'s keys: ``(word / n − zero) · scale`` in double."""
    if not (isinstance(n, int) and 1 <= n <= 16):
        raise InvalidArgument(f"n must be 1..16 conversions per word, got {n!r}")
    w = np.asarray(c, dtype=np.float64)
    return ((w / n if n > 1 else w) - float(ZERO)) * ch.lsb


def rx_config(channels: dict[str, CodeChannel]) -> str:
    """attitude-rx configuration lines for the channels (zero and scale of each)."""
    lines = []
    for ch in channels.values():
        lines += [f"{ch.name}-zero = {ZERO}", f"{ch.name}-scale = {ch.lsb!r}"]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class BoardRecording:
    """A recording at the board's sampling instants ``t = t0 + n · period``: the SI
    values (interpolated), their codes, and the reference attitude there. With gyro
    oversampling (``oversample`` > 1) the gyros are converted ``oversample`` times per
    sample (:attr:`gyro_conversions`), and ``codes["gyro"]`` holds their sums, the words
    the board sends (``si["gyro"]`` the mean of the converted rates)."""

    period: float  #: s
    t: NDArray[np.float64]  #: (n,) s, in the recording's time
    si: dict[str, NDArray[np.float64]]  #: ``gyro``/``acc``/``mag`` → (n, 3) SI values
    codes: dict[str, NDArray[np.int64]]  #: the same → (n, 3) codes (gyro: sums of ``oversample``)
    quat: NDArray[np.float64]  #: (n, 4) reference w, x, y, z (NaN where lost)
    movement: NDArray[np.bool_]  #: (n,) the samples the metric counts
    channels: dict[str, CodeChannel]
    oversample: int = 1  #: gyro conversions summed per sample
    gyro_conversions: NDArray[np.int64] | None = None  #: (n, oversample, 3) each conversion's codes, in time order
    mean: bool = False  #: ``codes["gyro"]`` is the rounded mean code of the conversions (a plain stream), not the sum

    @property
    def stream_n(self) -> int:
        """Conversions per gyro word a receiver divides by: ``oversample``, or 1 for means."""
        return 1 if self.mean else self.oversample

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    def clipped(self) -> dict[str, int]:
        """Codes at a channel's limit or rail, per channel (count of values)."""
        return {k: int(np.count_nonzero(np.abs(v) >= self.channels[k].clip)) for k, v in self.si.items()}


def _interp(x: NDArray[np.float64], rate: float, t: NDArray[np.float64]) -> NDArray[np.float64]:
    src = np.arange(x.shape[0]) / rate
    return np.stack([np.interp(t, src, x[:, j]) for j in range(x.shape[1])], axis=1)


def _nlerp(q: NDArray[np.float64], rate: float, t: NDArray[np.float64]) -> NDArray[np.float64]:
    """Normalized linear interpolation between the neighbouring reference quaternions
    (the nearer's sign; NaN if either is lost)."""
    pos = t * rate
    i = np.minimum(np.floor(pos).astype(np.int64), q.shape[0] - 2)
    f = (pos - i)[:, None]
    a, b = q[i], q[i + 1]
    b = np.where(np.sum(a * b, axis=1, keepdims=True) < 0, -b, b)
    r = (1 - f) * a + f * b
    return r / np.linalg.norm(r, axis=1, keepdims=True)


def resample(trial: Any, period: float, channels: dict[str, CodeChannel], start: float = 0.0,
             duration: float | None = None, oversample: int = 1, mean: bool = False) -> BoardRecording:
    """A :class:`attitude_c.broad.Trial` (or anything with ``rate``, ``gyr``, ``acc``,
    ``mag``, ``quat``, ``movement``) at the board's instants from ``start`` (s) for
    ``duration`` (s; None: to the end): gyro, accelerometer and field linearly
    interpolated (point samples, as the board's converter takes them), the reference by
    normalized linear interpolation, ``movement`` of the nearest sample; then coded.
    ``oversample`` = N > 1: the gyros converted N times per sample, ``period / N`` apart
    with the last at the sample's instant t (the midpoints of the N sub-intervals of
    (t − period + period/2N, t + period/2N], as the aided firmware's sub-scans: docs/firmware.md),
    the codes summed (``mean``: their rounded mean, ``(sum + N/2) // N``, as the firmware's
    FW_GYRO_MEAN sends it); instants before the recording's start take its first value."""
    if not (isinstance(oversample, int) and 1 <= oversample <= 16):
        raise InvalidArgument(f"oversample must be 1..16, got {oversample!r}")
    rate = float(trial.rate)
    n_src = int(trial.gyr.shape[0])
    end = (n_src - 1) / rate if duration is None else min((n_src - 1) / rate, start + duration)
    if not (period > 0 and 0 <= start < end):
        raise InvalidArgument(f"need period > 0 and 0 <= start < end of the recording, got period={period!r}, "
                              f"start={start!r}, end={end!r}")
    t = (start + np.arange(math.floor((end - start) / period) + 1) * period).astype(np.float64)
    si = {k: _interp(np.asarray(a, np.float64), rate, t)
          for k, a in (("acc", trial.acc), ("mag", trial.mag))}
    cs = {k: codes(v, channels[k]) for k, v in si.items()}
    n, m = t.shape[0], oversample
    sub = (t[:, None] - (m - 1 - np.arange(m))[None, :] * (period / m)).reshape(-1)  # (n·m,) in time order
    g = _interp(np.asarray(trial.gyr, np.float64), rate, sub)  # np.interp: the first value before the start
    conv = codes(g, channels["gyro"]).reshape(n, m, 3)
    words = (conv.sum(axis=1) + m // 2) // m if mean else conv.sum(axis=1)
    si, cs = {"gyro": g.reshape(n, m, 3).mean(axis=1), **si}, {"gyro": words, **cs}
    near = np.minimum(np.rint(t * rate).astype(np.int64), n_src - 1)
    return BoardRecording(period=period, t=t, si=si, codes=cs, quat=_nlerp(np.asarray(trial.quat, np.float64), rate, t),
                          movement=np.asarray(trial.movement, bool)[near], channels=channels, oversample=m,
                          gyro_conversions=conv, mean=mean)
