"""Link v2, written in Python from the specification in ``docs/link.md``
("Link v2") -- the second opinion on the C machines (``attitude/link2.h``).

Where the C sender makes each frame byte from its ring when it is due (the
8051 has no RAM for a frame), this end builds the whole frame, checks and
encodes it at once, and queues the wire bytes; where the C receiver decodes
in fixed buffers, this one works on ``bytes``. Both follow the same rules, so
the differential tests compare them byte for byte and result for result.

Calling convention as for the legacy ends: ``sink(byte[, tick]) -> Result2``,
``poll([tick]) -> (Result2, byte | None)``; ticks are a free-running counter
in the caller's unit of which only the low 16 bits matter.
"""

from __future__ import annotations

import enum
from dataclasses import asdict, dataclass

from ..errors import InvalidArgument, InvalidType, LinkBusy

DELIM = 0x00
RECORD = 6
SAMPLES_MAX = 24
SAMPLES_DEFAULT = 16
RING_MAX = 64
WINDOW_MAX = 127
T_DATA, T_RAW, T_SYN, T_ACK = 0x00, 0x40, 0x80, 0xC0
E_BIT = 0x20
F_GAP, F_SYNACK, F_NOSESSION, F_EPOCH = 0x01, 0x02, 0x04, 0x08
TIMEOUT_MAX = 32767
NO_TIMER = 0xFFFF
#: Default retransmission timeout in ms (1 ms ticks, 9600 baud; see docs/link.md).
DEFAULT_RTO_MS = 200


class Result2(enum.IntEnum):
    """What one sink or poll call did (same values as C ``att_link2_result``)."""

    NONE = 0
    IDLE = 1
    SEND = 2
    FRAME = 3
    DELIVERED = 4
    BAD_FRAME = 5
    DISCARDED = 6
    TIMEOUT = 7


# ---------------------------------------------------------------- CRC-32C, rCOBS, packing

def _crc32c_table() -> list[int]:
    poly = 0x82F63B78  # Castagnoli 0x1EDC6F41, bit-reversed (LSB-first register)
    table = []
    for i in range(256):
        c = i
        for _ in range(8):
            c = (c >> 1) ^ poly if c & 1 else c >> 1
        table.append(c)
    return table


_CRC_TABLE = _crc32c_table()


def crc32c(data: bytes) -> int:
    """CRC-32C (iSCSI, RFC 3720): ``crc32c(b"123456789") == 0xE3069283``."""
    c = 0xFFFFFFFF
    for b in data:
        c = _CRC_TABLE[(c ^ b) & 0xFF] ^ (c >> 8)
    return c ^ 0xFFFFFFFF


def rcobs_encode(data: bytes) -> bytes:
    """Reverse COBS: each 0x00 becomes 1 + the bytes since the previous code,
    0xFF follows 254 bytes without a zero, a final code closes. No 0x00 in the
    result; the delimiter is not included."""
    out = bytearray()
    run = 0
    for b in data:
        if b == 0:
            out.append(run + 1)
            run = 0
        else:
            out.append(b)
            run += 1
            if run == 254:
                out.append(0xFF)
                run = 0
    out.append(run + 1)
    return bytes(out)


def rcobs_decode(enc: bytes) -> bytes | None:
    """Inverse of :func:`rcobs_encode` (read from the end); None if malformed."""
    if not enc or 0 in enc or enc[-1] == 0xFF:
        return None
    parts: list[bytes] = []
    p = len(enc)
    final = True
    while p > 0:
        code = enc[p - 1]
        run = 254 if code == 0xFF else code - 1
        if run > p - 1:
            return None
        chunk = enc[p - 1 - run:p - 1]
        parts.append(chunk if final or code == 0xFF else chunk + b"\x00")
        p -= 1 + run
        final = False
    return b"".join(reversed(parts))


def pack_samples(records: list[bytes]) -> bytes:
    """Three 12-bit codes per record, two codes in 3 bytes, an odd last code in 2 (low 4 bits 0)."""
    codes = [int.from_bytes(r[i:i + 2], "big") for r in records for i in (0, 2, 4)]
    bits = 0
    for c in codes:
        bits = (bits << 12) | c
    nbits = 12 * len(codes)
    nbytes = (nbits + 7) // 8
    return (bits << (8 * nbytes - nbits)).to_bytes(nbytes, "big") if codes else b""


def unpack_samples(payload: bytes, n: int) -> list[bytes]:
    nbits = 36 * n
    bits = int.from_bytes(payload, "big") >> (8 * len(payload) - nbits)
    codes = [(bits >> (12 * (3 * n - 1 - k))) & 0xFFF for k in range(3 * n)]
    return [b"".join(codes[3 * i + j].to_bytes(2, "big") for j in range(3)) for i in range(n)]


def payload_len(n: int) -> int:
    return (9 * n + 1) // 2


def packable(rec: bytes) -> bool:
    """A sample record whose codes fit 12 bits (byte 0, 2, 4 below 0x10) travels packed."""
    return rec[0] < 16 and rec[2] < 16 and rec[4] < 16


def make_frame(head: int, seq: int, payload: bytes = b"") -> bytes:
    body = bytes([head, seq & 0xFF]) + payload
    return body + crc32c(body).to_bytes(4, "big")


def _u8(x: int) -> int:
    return x & 0xFF


def _check_int(name: str, value: object, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise InvalidType(f"{name} must be an int, got {type(value).__name__}")
    if not lo <= value <= hi:
        raise InvalidArgument(f"{name} must be {lo}..{hi}, got {value}")
    return value


def _byte(name: str, value: object) -> int:
    return _check_int(name, value, 0, 255)


# ---------------------------------------------------------------- sender A

@dataclass
class Sender2Stats:
    frames: int = 0
    records: int = 0
    resent: int = 0
    acks: int = 0
    bad_frames: int = 0
    timeouts: int = 0
    gobacks: int = 0
    syns: int = 0

    def as_dict(self) -> dict[str, int]:
        return asdict(self)


class Sender2:
    """Sender A of link v2, from the spec. ``push(record)`` queues a 6-byte
    block-format record (``LinkBusy`` when the window is full)."""

    def __init__(self, ring_size: int = RING_MAX, max_samples: int = SAMPLES_DEFAULT,
                 rto: int = DEFAULT_RTO_MS) -> None:
        _check_int("ring_size", ring_size, 1, RING_MAX)
        if ring_size & (ring_size - 1):
            raise InvalidArgument(f"ring_size must be a power of two, got {ring_size}")
        self.ring_size = ring_size
        self.max_samples = _check_int("max_samples", max_samples, 1, SAMPLES_MAX)
        self.rto = _check_int("rto", rto, 1, TIMEOUT_MAX)
        self.stats = Sender2Stats()
        self.reset()

    def reset(self) -> None:
        """A new session with an empty window (a rebooted board); statistics kept."""
        self._records: dict[int, bytes] = {}  # seq -> record, base <= seq < head (mod 256)
        self.head = self.base = self.next = self.hi = self.limit = 0
        self.session = "syn"  # "syn" (SYN due), "wait" (SYN sent), "run"
        self.cur = self.max_samples
        self.epoch = 0
        self.t0 = 0
        self._line_idle = True
        self._wire: list[int] = []  # bytes of the frame being sent
        self._frame_seq = 0
        self._rx = bytearray()
        self._rx_skip = False

    # window bookkeeping
    def _used(self) -> int:
        n = _u8(self.head - self.base)
        if self._wire and _u8(self.head - self._frame_seq) > n:  # a frame still reads these records
            n = _u8(self.head - self._frame_seq)
        return n

    @property
    def room(self) -> int:
        return self.ring_size - self._used()

    @property
    def pending(self) -> int:
        return _u8(self.head - self.base)

    def push(self, record: bytes) -> None:
        if not isinstance(record, (bytes, bytearray)) or len(record) != RECORD:
            raise InvalidArgument(f"record must be {RECORD} bytes, got {record!r}")
        if self._used() >= self.ring_size:
            raise LinkBusy("link v2 sender ring full")
        self._records[self.head] = bytes(record)
        self.head = _u8(self.head + 1)

    def _open(self, seq: int) -> bool:
        return 1 <= _u8(self.limit - seq) <= WINDOW_MAX

    # ---- receiving ACKs
    def sink(self, byte: int, tick: int = 0) -> Result2:
        byte = _byte("byte", byte)
        if byte != DELIM:
            if self._rx_skip or len(self._rx) >= 8:
                self._rx_skip = True
                return Result2.DISCARDED
            self._rx.append(byte)
            return Result2.NONE
        enc, skipped = bytes(self._rx), self._rx_skip
        self._rx, self._rx_skip = bytearray(), False
        if not enc and not skipped:
            return Result2.NONE
        frame = None if skipped or len(enc) != 8 else rcobs_decode(enc)
        if (frame is None or len(frame) != 7 or frame[0] & 0xF0 != T_ACK
                or crc32c(frame[:3]) != int.from_bytes(frame[3:], "big")):
            self.stats.bad_frames += 1
            return Result2.BAD_FRAME
        return self._ack(frame[0] & 0x0F, frame[1], frame[2], tick & 0xFFFF)

    def _ack(self, flags: int, ack: int, limit: int, tick: int) -> Result2:
        self.stats.acks += 1
        if flags & F_NOSESSION:  # B lost its session: start again at base, keep the window
            self.session = "syn"
            self.next = self.hi = self.limit = self.base
            return Result2.FRAME
        if self.session == "wait":
            if not flags & F_SYNACK or ack != self.base:
                return Result2.FRAME
            self.session = "run"
            self.t0 = tick
        elif self.session != "run":
            return Result2.FRAME
        adv = _u8(ack - self.base)
        if adv > _u8(self.hi - self.base):
            self.stats.bad_frames += 1
            return Result2.BAD_FRAME
        if adv:
            if _u8(self.next - self.base) < adv:
                self.next = ack
            self.base = ack
            self.t0 = tick
            self.cur = min(self.cur + 1, self.max_samples)
        if _u8(limit - ack) <= WINDOW_MAX:
            self.limit = limit
        if flags & F_GAP and self.hi != self.base and bool(flags & F_EPOCH) == bool(self.epoch):
            self.next = self.base
            self.cur = (self.cur + 1) // 2
            self.epoch ^= 1
            self.stats.gobacks += 1
            self.t0 = tick
        return Result2.FRAME

    # ---- sending
    def poll(self, tick: int = 0) -> tuple[Result2, int | None]:
        tick &= 0xFFFF
        if self._wire:
            b = self._wire.pop(0)
            if not self._wire:
                self.t0 = tick  # the timer counts from the end of the last frame
            return Result2.SEND, b
        if self.session == "syn":
            self.session = "wait"
            self.stats.syns += 1
            return self._send(make_frame(T_SYN, self.base), self.base)
        waiting = (self.session == "wait" or self.hi != self.base
                   or (self.next != self.head and not self._open(self.next)))
        if waiting and ((tick - self.t0) & 0xFFFF) > self.rto:
            self.stats.timeouts += 1
            self.t0 = tick
            if self.session == "wait":
                self.session = "syn"
                return Result2.TIMEOUT, None
            if self.hi != self.base:  # no progress: go back to the first unacknowledged record
                self.next = self.base
                self.cur = (self.cur + 1) // 2
                self.epoch ^= 1
            if self._open(self.next):
                return Result2.TIMEOUT, None
            # B's limit blocks A, or A missed the ACK that opened it: ask with an empty frame
            return self._send(make_frame(T_DATA | E_BIT * self.epoch, self.next), self.next)  # probe
        if self.session == "run" and self.next != self.head and self._open(self.next):
            return self._send_data()
        self._line_idle = True
        return (Result2.IDLE if self.session == "run" and self.head == self.base else Result2.NONE), None

    def _send_data(self) -> tuple[Result2, int | None]:
        seq = self.next
        first = self._records[seq]
        if not packable(first):
            recs = [first]
            frame = make_frame(T_RAW | E_BIT * self.epoch, seq, first)
        else:
            recs = [first]
            while len(recs) < self.cur:
                s = _u8(seq + len(recs))
                if s == self.head or not self._open(s) or not packable(self._records[s]):
                    break
                recs.append(self._records[s])
            frame = make_frame(len(recs) | E_BIT * self.epoch, seq, pack_samples(recs))
        n = len(recs)
        old = _u8(self.hi - self.next) if _u8(self.next - self.base) < _u8(self.hi - self.base) else 0
        self.stats.resent += min(old, n)
        if n > old:
            self.stats.records += n - old
            self.hi = _u8(seq + n)
        self.next = _u8(seq + n)
        return self._send(frame, seq)

    def _send(self, frame: bytes, seq: int) -> tuple[Result2, int | None]:
        self.stats.frames += 1
        self._frame_seq = seq
        self._wire = ([DELIM] if self._line_idle else []) + list(rcobs_encode(frame)) + [DELIM]
        self._line_idle = False
        return Result2.SEND, self._wire.pop(0)

    def ticks_left(self, now: int) -> int:
        if self._wire or self.session == "syn" or (
                self.session == "run" and self.next != self.head and self._open(self.next)):
            return 0
        if self.session != "wait" and self.hi == self.base and self.next == self.head:
            return NO_TIMER
        elapsed = (now - self.t0) & 0xFFFF
        return 0 if elapsed > self.rto else self.rto - elapsed + 1


# ---------------------------------------------------------------- receiver B

@dataclass
class Receiver2Stats:
    frames: int = 0
    bad_frames: int = 0
    records: int = 0
    duplicates: int = 0
    gaps: int = 0
    refused: int = 0
    syns: int = 0
    no_session: int = 0
    acks: int = 0
    bytes_discarded: int = 0

    def as_dict(self) -> dict[str, int]:
        return asdict(self)


WIRE_MAX = 115


@dataclass
class _AckDue:
    flags: int = 0
    due: bool = False


class Receiver2:
    """Receiver B of link v2, from the spec. After ``Result2.DELIVERED``,
    ``delivered`` holds the new records (6-byte block-format records)."""

    def __init__(self, room: int = 0) -> None:
        self.stats = Receiver2Stats()
        self.room = _check_int("room", room, 0, 0xFFFF)
        self.delivered: list[bytes] = []
        self.reset()

    def reset(self) -> None:
        self.synced = False
        self.expected = 0
        self.last_limit = 0
        self._ack = _AckDue()
        self._buf = bytearray()
        self._skip = False
        self._tx: list[int] = []
        self.delivered = []

    def set_room(self, room: int) -> None:
        room = _check_int("room", room, 0, 0xFFFF)
        old = _u8(self.last_limit - self.expected)
        self.room = room
        if self.synced and old < SAMPLES_MAX and min(room, WINDOW_MAX) > old:
            self._ack.due = True

    def _queue(self, flag: int) -> None:
        self._ack = _AckDue((flag | (self._ack.flags & F_SYNACK)) if self._ack.due else flag, True)

    def sink(self, byte: int, tick: int = 0) -> Result2:
        byte = _byte("byte", byte)
        self.delivered = []
        if byte != DELIM:
            if self._skip:
                self.stats.bytes_discarded += 1
                return Result2.DISCARDED
            if len(self._buf) == WIRE_MAX:
                self.stats.bytes_discarded += WIRE_MAX + 1
                self._skip = True
                self._buf = bytearray()
                return Result2.DISCARDED
            self._buf.append(byte)
            return Result2.NONE
        enc, skipped = bytes(self._buf), self._skip
        self._buf, self._skip = bytearray(), False
        if skipped:
            self.stats.bad_frames += 1
            return Result2.BAD_FRAME
        if not enc:
            return Result2.NONE
        frame = rcobs_decode(enc)
        if frame is None or len(frame) < 6 or crc32c(frame[:-4]) != int.from_bytes(frame[-4:], "big"):
            self.stats.bad_frames += 1
            return Result2.BAD_FRAME
        return self._frame(frame)

    def _frame(self, f: bytes) -> Result2:
        h, seq, body = f[0], f[1], f[2:-4]
        kind = h & 0xC0
        if kind == T_DATA:
            n = h & 0x1F
            if n > SAMPLES_MAX or len(body) != payload_len(n) or (n % 2 == 1 and body[-1] & 0x0F):
                self.stats.bad_frames += 1
                return Result2.BAD_FRAME
            self.stats.frames += 1
            return self._data(h, seq, unpack_samples(body, n) if n else [])
        if kind == T_RAW and h & ~E_BIT & 0xFF == T_RAW and len(body) == RECORD:
            self.stats.frames += 1
            return self._data(h, seq, [body])
        if h == T_SYN and not body:
            self.stats.frames += 1
            self.stats.syns += 1
            self.synced = True
            self.expected = seq
            self._queue(F_SYNACK)
            return Result2.FRAME
        self.stats.bad_frames += 1
        return Result2.BAD_FRAME

    def _data(self, h: int, seq: int, recs: list[bytes]) -> Result2:
        echo = F_EPOCH if h & E_BIT else 0
        if not self.synced:
            self.stats.no_session += 1
            self._queue(F_NOSESSION)
            return Result2.FRAME
        behind = _u8(self.expected - seq)  # records of this frame already delivered
        if behind > WINDOW_MAX:
            self.stats.gaps += 1
            self._queue(F_GAP | echo)
            return Result2.FRAME
        self._queue(echo)
        new = recs[behind:]
        self.stats.duplicates += min(behind, len(recs))
        take = new[:self.room]
        self.stats.refused += len(new) - len(take)
        if not take:
            return Result2.FRAME
        self.expected = _u8(self.expected + len(take))
        self.room -= len(take)
        self.stats.records += len(take)
        self.delivered = take
        return Result2.DELIVERED

    def poll(self, tick: int = 0) -> tuple[Result2, int | None]:
        if self._tx:
            return Result2.SEND, self._tx.pop(0)
        if not self._ack.due:
            return Result2.IDLE, None
        ack, limit = (self.expected, _u8(self.expected + min(self.room, WINDOW_MAX))) if self.synced else (0, 0)
        self.last_limit = limit
        frame = make_frame(T_ACK | self._ack.flags, ack, bytes([limit]))
        self._ack = _AckDue()
        self.stats.acks += 1
        self._tx = [DELIM] + list(rcobs_encode(frame)) + [DELIM]
        return Result2.SEND, self._tx.pop(0)
