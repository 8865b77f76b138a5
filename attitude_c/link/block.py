"""The block format of the acquisition link, through the C library.

A thin typed layer over ``csrc/src/block.c`` / ``block_decode.c``
(``csrc/include/attitude/block.h`` is the format's one description): the
constants, record kinds and every range check come from the compiled
library (``lib.ATT_BLOCK_*``); nothing of the format is written again here.

- :func:`decode` (raises :class:`~attitude_c.errors.BlockFormatError`) and
  :func:`try_decode` (returns the C status) turn 6 bytes read alone into a
  :class:`Record`;
- ``encode_*`` build records (what the firmware sends; ``encode_oversample``
  and ``encode_sums``: a board that sends sums of n conversions;
  ``encode_channels``: a board that sends more than the gyros);
- :class:`SeqTracker` decodes the records of one stream (its limit for sample
  words included), numbers the samples, tells which record of its sample's
  group each sample record is (gyro, accelerometer, magnetometer: ``Span.part``)
  and places every loss report (``att_block_seq_*``); :func:`number_stream`
  does that for a list of blocks.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Union

from .._lib import ffi_lib
from ..errors import BlockFormatError, InvalidArgument, InvalidType
from ..names import raise_for_status

Kind = Literal["sample", "boot", "selftest", "gave_up", "overrun", "adc_error", "oversample", "channels"]
#: CHANNELS' board types (``att_block_board``: ATT_BLOCK_BOARD_GYRO3, _AIDED9)
Board = Literal["gyro3", "aided9"]
#: the channels of a stream (``att_block_channel`` bits), and which record of a group a
#: sample record is (``att_block_part``): the same three names
Channel = Literal["gyr", "acc", "mag"]
LossKind = Literal["gave_up", "overrun"]
Bytes = Union[bytes, bytearray, memoryview]

__all__ = [
    "Board",
    "Channel",
    "Format",
    "Kind",
    "LossKind",
    "Record",
    "SeqTracker",
    "Span",
    "decode",
    "encode_adc_error",
    "encode_boot",
    "encode_channels",
    "encode_loss",
    "encode_oversample",
    "encode_sample",
    "encode_selftest",
    "encode_sums",
    "fmt",
    "number_stream",
    "try_decode",
]


@dataclass(frozen=True)
class Format:
    """The format's constants, as compiled into the library."""

    size: int          #: bytes per record
    code_max: int      #: largest sample code
    mark: int          #: byte 0 of a report
    version: int       #: format version BOOT carries
    tick_hz: int       #: BOOT period unit (ticks per second)
    period_max: int    #: largest BOOT period (ticks)
    baud_unit: int     #: BOOT baud_div unit
    oversample_max: int  #: largest OVERSAMPLE n
    sum_max: int       #: largest word of an oversampled sample
    boot_link2: int    #: BOOT period word: the flag of a link v2 board
    kinds: dict[int, Kind] = field(repr=False)  #: C kind value -> name
    boards: dict[int, Board] = field(repr=False)  #: CHANNELS board value -> name
    channel_bits: dict[Channel, int] = field(repr=False)  #: channel name -> its bit in the set
    parts: dict[int, Channel] = field(repr=False)  #: att_block_part value -> name
    errors: dict[int, str] = field(repr=False)  #: C status -> what it means


_fmt: Format | None = None


def _c() -> tuple[Any, Any]:
    return ffi_lib("f64")


def _enum(ffi: Any, ctype: str, prefix: str) -> dict[int, Any]:
    """A C enum of block.h as value -> lower-case name without the prefix."""
    return {v: n[len(prefix):].lower() for v, n in ffi.typeof(ctype).elements.items()}


def fmt() -> Format:
    """The block format's constants (loaded from the C library on first use)."""
    global _fmt
    if _fmt is None:
        ffi, lib = _c()
        kinds: dict[int, Kind] = _enum(ffi, "att_block_kind", "ATT_BLOCK_")
        errors = {lib.ATT_BLOCK_E_CODE: f"sample code above {lib.ATT_BLOCK_CODE_MAX}",  # plain streams
                  lib.ATT_BLOCK_E_KIND: "unknown report kind",
                  lib.ATT_BLOCK_E_FIELD: "report field out of range",
                  lib.ATT_BLOCK_E_SEQ: "report out of sequence"}  # a slip, or a group cut short
        _fmt = Format(size=lib.ATT_BLOCK_SIZE, code_max=lib.ATT_BLOCK_CODE_MAX, mark=lib.ATT_BLOCK_MARK,
                      version=lib.ATT_BLOCK_VERSION, tick_hz=lib.ATT_BLOCK_TICK_HZ,
                      period_max=lib.ATT_BLOCK_PERIOD_MAX, baud_unit=lib.ATT_BLOCK_BAUD_UNIT,
                      oversample_max=lib.ATT_BLOCK_OVERSAMPLE_MAX, sum_max=lib.ATT_BLOCK_SUM_MAX,
                      boot_link2=lib.ATT_BLOCK_BOOT_LINK2, kinds=kinds,
                      boards=_enum(ffi, "att_block_board", "ATT_BLOCK_BOARD_"),
                      channel_bits={n: v for v, n in _enum(ffi, "att_block_channel", "ATT_BLOCK_CH_").items()},
                      parts=_enum(ffi, "att_block_part", "ATT_BLOCK_PART_"), errors=errors)
    return _fmt


def _kind_value(kind: str) -> int:
    for v, n in fmt().kinds.items():
        if n == kind:
            return v
    raise InvalidArgument(f"kind must be one of {sorted(fmt().kinds.values())}, got {kind!r}")


@dataclass(frozen=True)
class Record:
    """One decoded record. Fields its kind does not use are 0."""

    kind: Kind
    raw: bytes
    codes: tuple[int, int, int] = (0, 0, 0)  #: sample: X, Y, Z codes
    first: int = 0         #: gave_up, overrun, adc_error: first lost sample (mod 2^16)
    count: int = 0         #: gave_up, overrun: samples lost; adc_error: 1
    period_ticks: int = 0  #: boot: sampling period in ticks of 1/tick_hz s
    baud: int = 0          #: boot: line rate (baud)
    version: int = 0       #: boot: format version
    status: int = 0        #: selftest, adc_error: the failure's att_status
    bad_code: int = 0      #: selftest: code read from the failed test input
    attempt: int = 0       #: selftest: attempt number
    oversample: int = 0    #: oversample: conversions summed per word of the samples that follow
    link: Literal["legacy", "v2"] = "legacy"  #: boot: the board's link protocol (top bit of the period word)
    board: Board | None = None  #: channels: the board type (None for other kinds, or a value out of range)
    channels: tuple[Channel, ...] = ()  #: channels: the channel set, in record order ("gyr" first)
    acc_every: int = 0     #: channels: an accelerometer record in sample n when n % acc_every == 0 (0: none)
    mag_every: int = 0     #: channels: the same for the magnetometer

    @property
    def is_report(self) -> bool:
        return self.kind != "sample"

    @property
    def is_loss(self) -> bool:
        return self.kind in ("gave_up", "overrun", "adc_error")

    @property
    def period_s(self) -> float:
        """boot: the sampling period in seconds."""
        return self.period_ticks / fmt().tick_hz

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: ``{"codes": [...]}`` or ``{"report": "BOOT", ...}`` (attitude-rx's fields)."""
        if self.kind == "sample":
            return {"codes": list(self.codes)}
        out: dict[str, Any] = {"report": self.kind.upper()}
        if self.kind == "boot":
            out.update(version=self.version, period_ticks=self.period_ticks, period_s=self.period_s,
                       baud=self.baud)
            if self.link != "legacy":  # (a legacy BOOT keeps the fields attitude-rx prints)
                out["link"] = self.link
        elif self.kind == "selftest":
            out.update(status=self.status, bad_code=self.bad_code, attempt=self.attempt)
        elif self.kind == "oversample":
            out["n"] = self.oversample
        elif self.kind == "channels":
            out.update(board=self.board, channels=list(self.channels), acc_every=self.acc_every,
                       mag_every=self.mag_every)
        else:
            out.update(first=self.first, count=self.count)
            if self.kind == "adc_error":
                out["status"] = self.status
        return out


def _raw(raw: Bytes, what: str) -> bytes:
    if not isinstance(raw, (bytes, bytearray, memoryview)):
        raise InvalidType(f"{what} must be bytes, got {type(raw).__name__}")
    b = bytes(raw)
    if len(b) != fmt().size:
        raise InvalidArgument(f"{what} must have {fmt().size} bytes, got {len(b)}")
    return b


def _where(index: int | None) -> str:
    return "record" if index is None else f"record {index}"


def try_decode(raw: Bytes, index: int | None = None) -> tuple[Record | None, int]:
    """Decode 6 bytes: ``(record, status)``, status 0 or a ``lib.ATT_BLOCK_E_*`` code.

    On ``E_CODE`` the record is a sample with the codes as received (for a
    log: never integrate them); on ``E_FIELD`` it is the report as read; on
    ``E_KIND`` (a kind the format does not define) it is None. Only a wrong
    size or type raises.
    """
    b = _raw(raw, _where(index))
    ffi, lib = _c()
    out = ffi.new("att_block *")
    st = lib.att_block_decode(b, out)
    if st < 0 and st not in fmt().errors:
        raise_for_status(st, "att_block_decode")
    return _record(b, out), st


def _channel_names(bits: int) -> tuple[Channel, ...]:
    """The names of the channel bits set in ``bits``, in record order."""
    return tuple(n for n, v in sorted(fmt().channel_bits.items(), key=lambda kv: kv[1]) if bits & v)


def _record(b: bytes, out: Any) -> Record | None:
    """The Record of a decoded ``att_block`` (None for an unknown kind)."""
    kind = fmt().kinds.get(out.kind)
    if kind is None:
        return None
    return Record(kind=kind, raw=b, codes=(out.code[0], out.code[1], out.code[2]), first=out.first,
                  count=out.count, period_ticks=out.period_ticks, baud=out.baud_div * fmt().baud_unit,
                  version=out.version, status=out.status, bad_code=out.bad_code, attempt=out.attempt,
                  oversample=out.oversample, link="v2" if out.link == 2 else "legacy",
                  board=fmt().boards.get(out.board), channels=_channel_names(out.channels),
                  acc_every=out.acc_every, mag_every=out.mag_every)


def decode(raw: Bytes, index: int | None = None) -> Record:
    """Decode 6 bytes; a record that breaks the format raises :class:`BlockFormatError`
    naming the record (``index``) and its bytes."""
    rec, st = try_decode(raw, index)
    if st != 0 or rec is None:
        raise BlockFormatError(f"{_where(index)} {bytes(raw).hex(' ')}: {fmt().errors[st]}", st, index)
    return rec


def _encode(fn: str, *args: Any) -> bytes:
    ffi, lib = _c()
    buf = ffi.new("uint8_t[]", fmt().size)
    st = getattr(lib, fn)(buf, *args)
    if st != 0:
        raise_for_status(st, fn)  # every argument was checked before: not reached
    return bytes(ffi.buffer(buf))


def _check(name: str, v: int, lo: int, hi: int) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        try:
            import numpy as np

            if isinstance(v, np.integer):
                v = int(v)
            else:
                raise TypeError
        except TypeError:
            raise InvalidType(f"{name} must be an integer, got {type(v).__name__}") from None
    if not lo <= v <= hi:
        raise InvalidArgument(f"{name} must be {lo}..{hi}, got {v}")
    return v


def encode_sample(codes: Sequence[int]) -> bytes:
    """A sample record from the three codes X, Y, Z (each 0..4095)."""
    if len(codes) != 3:
        raise InvalidArgument(f"codes must hold 3 values (X, Y, Z), got {len(codes)}")
    c = [_check(f"codes[{i}]", v, 0, fmt().code_max) for i, v in enumerate(codes)]
    ffi, _ = _c()
    return _encode("att_block_encode_sample", ffi.new("uint16_t[3]", c))


def encode_boot(period_ticks: int, baud: int, link: Literal["legacy", "v2"] = "legacy") -> bytes:
    """BOOT: the sampling period in ticks of 1/3600 s, the line rate (a multiple of 1200) and
    the board's link protocol (``"v2"`` sets the top bit of the period word)."""
    _check("period_ticks", period_ticks, 1, fmt().period_max)
    u = fmt().baud_unit
    _check("baud", baud, u, 255 * u)
    if baud % u:
        raise InvalidArgument(f"baud must be a multiple of {u}, got {baud}")
    if link not in ("legacy", "v2"):
        raise InvalidArgument(f"link must be 'legacy' or 'v2', got {link!r}")
    flag = fmt().boot_link2 if link == "v2" else 0
    return _encode("att_block_encode_boot", period_ticks | flag, baud // u)


def encode_selftest(status: int, bad_code: int, attempt: int) -> bytes:
    """SELFTEST: the failed self-test's status (-128..-1), its code, the attempt (0..255)."""
    _check("status", status, -128, -1)
    _check("bad_code", bad_code, 0, fmt().code_max)
    _check("attempt", attempt, 0, 255)
    return _encode("att_block_encode_selftest", status, bad_code, attempt)


def encode_loss(kind: LossKind, first: int, count: int) -> bytes:
    """GAVE_UP or OVERRUN: samples first .. first + count - 1 (mod 2^16) lost."""
    if kind not in ("gave_up", "overrun"):
        raise InvalidArgument(f"kind must be 'gave_up' or 'overrun', got {kind!r}")
    _check("first", first, 0, 0xFFFF)
    _check("count", count, 1, 0xFFFF)
    return _encode("att_block_encode_loss", _kind_value(kind), first, count)


def encode_adc_error(first: int, status: int) -> bytes:
    """ADC_ERROR: sample ``first`` lost to a scan that failed with ``status`` (-128..-1)."""
    _check("first", first, 0, 0xFFFF)
    _check("status", status, -128, -1)
    return _encode("att_block_encode_adc_error", first, status)


def encode_oversample(n: int) -> bytes:
    """OVERSAMPLE: the sample records that follow carry sums of ``n`` conversions (1..16)."""
    _check("n", n, 1, fmt().oversample_max)
    return _encode("att_block_encode_oversample", n)


def sum_limit(n: int) -> int:
    """Largest word of a sample record of sums of ``n`` conversions: min(n × 4095, 0xFDFF)."""
    _check("n", n, 1, fmt().oversample_max)
    return min(n * fmt().code_max, fmt().sum_max)


def encode_sums(sums: Sequence[int], n: int) -> bytes:
    """A sample record of an oversampled stream: X, Y, Z, each the sum of ``n`` codes
    (0..:func:`sum_limit`); ``n = 1`` gives :func:`encode_sample`'s bytes."""
    if len(sums) != 3:
        raise InvalidArgument(f"sums must hold 3 values (X, Y, Z), got {len(sums)}")
    hi = sum_limit(n)
    c = [_check(f"sums[{i}]", v, 0, hi) for i, v in enumerate(sums)]
    ffi, _ = _c()
    return _encode("att_block_encode_sums", ffi.new("uint16_t[3]", c), n)


def encode_channels(board: Board, channels: Sequence[Channel], acc_every: int = 0, mag_every: int = 0) -> bytes:
    """CHANNELS: the board type, its channel set (``"gyr"`` always; ``"acc"``, ``"mag"``) and
    the decimations: sample n carries an accelerometer record when n % acc_every == 0
    (1..255 when ``"acc"`` is in the set, else 0), likewise ``mag_every``. A ``"gyro3"``
    board has the gyros alone."""
    if board not in fmt().boards.values():
        raise InvalidArgument(f"board must be one of {sorted(fmt().boards.values())}, got {board!r}")
    if isinstance(channels, str):
        raise InvalidType(f"channels must be a sequence of names, got the string {channels!r}")
    bits = 0
    for c in channels:
        if c not in fmt().channel_bits:
            raise InvalidArgument(f"channels must be among {list(fmt().channel_bits)}, got {c!r}")
        bits |= fmt().channel_bits[c]
    if "gyr" not in channels:
        raise InvalidArgument(f"channels must include 'gyr', got {list(channels)}")
    if board == "gyro3" and bits != fmt().channel_bits["gyr"]:
        raise InvalidArgument(f"a 'gyro3' board has the gyros alone, got channels {list(channels)}")
    for name, every, ch in (("acc_every", acc_every, "acc"), ("mag_every", mag_every, "mag")):
        if ch in channels:
            _check(name, every, 1, 255)
        elif _check(name, every, 0, 255) != 0:
            raise InvalidArgument(f"{name} must be 0 when {ch!r} is not in channels, got {every}")
    code = {n: v for v, n in fmt().boards.items()}[board]
    return _encode("att_block_encode_channels", code, bits, acc_every, mag_every)


@dataclass(frozen=True)
class Span:
    """Where a record falls in the numbering (``att_block_span``)."""

    first: int  #: sample: its number; loss report: first sample missing; boot/selftest: next number
    count: int  #: sample: 1; loss report: samples missing here (unreported gap included); else 0
    slip: int   #: loss report: its first minus the number expected (0 when the count agrees)
    #: sample: which record of sample ``first``'s group it is ("gyr" in a gyro-only stream); a
    #: report that cut a group short (status ``E_SEQ``): the record that was due; else "gyr"
    part: Channel = "gyr"


class SeqTracker:
    """One stream's decoder: numbers its samples, places each loss report and
    knows its limit for sample words (``att_block_seq``)."""

    def __init__(self) -> None:
        self._ffi, self._lib = _c()
        self._s: Any = self._ffi.new("att_block_seq *")
        self._b: Any = self._ffi.new("att_block *")
        self._span: Any = self._ffi.new("att_block_span *")
        self._lib.att_block_seq_init(self._s)

    @property
    def next(self) -> int:
        """Number of the next sample expected."""
        return int(self._s.next)

    @property
    def oversample(self) -> int:
        """Conversions per sample word: 1, or the stream's OVERSAMPLE n."""
        return max(1, int(self._s.oversample))

    @property
    def channels(self) -> tuple[Channel, ...]:
        """The stream's channel set: ``("gyr",)`` until a CHANNELS report (a BOOT: again)."""
        return _channel_names(self._s.channels) or ("gyr",)

    @property
    def acc_every(self) -> int:
        """CHANNELS' accelerometer decimation (0: no accelerometer records)."""
        return int(self._s.acc_every)

    @property
    def mag_every(self) -> int:
        """CHANNELS' magnetometer decimation (0: no magnetometer records)."""
        return int(self._s.mag_every)

    @property
    def part(self) -> Channel:
        """The record the next sample record is: "gyr" (a new sample's, and the last
        sample's group is complete), or "acc"/"mag" of the last sample's group."""
        return fmt().parts[self._s.part]

    @property
    def code_limit(self) -> int:
        """Largest sample word of this stream (4095, or min(n × 4095, 0xFDFF))."""
        return min(self.oversample * fmt().code_max, fmt().sum_max)

    def error(self, status: int) -> str:
        """What a ``lib.ATT_BLOCK_E_*`` status means in this stream."""
        if status == self._lib.ATT_BLOCK_E_CODE:
            return f"sample code above {self.code_limit}"
        return fmt().errors.get(status, f"status {status}")

    def decode(self, raw: Bytes, index: int | None = None) -> tuple[Record | None, Span | None, int]:
        """Decode and place one record of the stream (``att_block_seq_decode``):
        ``(record, span, status)``. status 0; ``lib.ATT_BLOCK_E_CODE`` (a sample
        above the stream's limit: numbered, never integrate it);
        ``lib.ATT_BLOCK_E_KIND`` / ``E_FIELD`` (span None: no place in the
        numbering; record None for an unknown kind); ``lib.ATT_BLOCK_E_SEQ``
        (a loss report after a slip: the numbering follows it from now on; or a
        report that cut a group short: ``span.part`` is the record that was due)."""
        b = _raw(raw, _where(index))
        st = self._lib.att_block_seq_decode(self._s, b, self._b, self._span)
        if st < 0 and st not in fmt().errors:
            raise_for_status(st, "att_block_seq_decode")
        rec = _record(b, self._b)
        placed = st in (0, self._lib.ATT_BLOCK_E_CODE, self._lib.ATT_BLOCK_E_SEQ)
        span = (Span(int(self._span.first), int(self._span.count), int(self._span.slip),
                     fmt().parts[self._span.part]) if placed else None)
        return rec, span, st

    def feed(self, rec: Record) -> tuple[Span, int]:
        """Place an already decoded ``rec``: ``(span, status)`` as :meth:`decode`;
        a record with no place in the numbering raises :class:`BlockFormatError`."""
        _, span, st = self.decode(rec.raw)
        if span is None:
            raise BlockFormatError(f"record {rec.raw.hex(' ')}: {self.error(st)}: it has no place in "
                                   "the numbering", st)
        return span, st


def number_stream(blocks: Iterable[Bytes], *, strict: bool = True) -> list[tuple[Record, Span]]:
    """Decode and number a stream of records (each link block may hold several),
    with one :class:`SeqTracker`.

    ``strict``: a record that breaks the format (for this stream: a sample
    above its limit) or a loss report that disagrees with the count raises
    :class:`BlockFormatError` naming the record's index; otherwise records
    with no place in the numbering are skipped, a bad sample keeps its
    number (and its status is dropped: check ``rec.codes`` against
    :attr:`SeqTracker.code_limit` before integrating) and slips are followed.
    """
    n = fmt().size
    tr = SeqTracker()
    out: list[tuple[Record, Span]] = []
    i = 0
    for blk in blocks:
        b = bytes(blk)
        if len(b) % n:
            raise InvalidArgument(f"block {len(out)} has {len(b)} bytes, not a multiple of {n}")
        for k in range(0, len(b), n):
            expected = tr.next
            rec, span, st = tr.decode(b[k:k + n], i)
            if st != 0 and strict:
                what = tr.error(st)
                if st == tr._lib.ATT_BLOCK_E_SEQ and span is not None and span.part != "gyr":
                    what += f" (it cut sample {expected - 1}'s group short before its {span.part} record)"
                elif st == tr._lib.ATT_BLOCK_E_SEQ and rec is not None:
                    what += f" (its first sample is {rec.first}, expected {expected & 0xFFFF})"
                raise BlockFormatError(f"record {i} {b[k:k + n].hex(' ')}: {what}", st, i)
            if rec is not None and span is not None:
                out.append((rec, span))
            i += 1
    return out
