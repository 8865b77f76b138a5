"""The link protocol of the paper (sec. 3.3), written in Python from the
specification in ``docs/link.md`` -- the second opinion on the C machines.

Both ends are byte-at-a-time machines with the same calling convention as
the C ones (:mod:`attitude_c.link.cends`): ``sink(byte, tick)`` for every
byte received, ``poll(tick) -> (Result, byte or None)`` for the next byte
to send and for timer events. Ticks are a free-running counter in a unit
of the caller's choice; only its low 16 bits matter (wrap-safe
arithmetic, as on the 8051), and every timeout is 1..32767 ticks.
"""

from __future__ import annotations

import enum
from dataclasses import asdict, dataclass

from ..errors import InvalidArgument, InvalidType, LinkBusy

SYN = 0xAA  # A -> B: may I send?
SYN_ACK = 0xBB  # B -> A: go ahead
ACK = 0x00  # B -> A: checksum matched
NAK = 0xFF  # B -> A: checksum mismatch, send again
BLOCK_MIN = 1
BLOCK_MAX = 64
BLOCK_DEFAULT = 6
TIMEOUT_MAX = 32767

#: Default timeouts in milliseconds (9600 baud, a Linux receiver); see docs/link.md.
DEFAULT_SYN_TIMEOUT_MS = 50
DEFAULT_ANSWER_TIMEOUT_MS = 50
DEFAULT_GAP_TIMEOUT_MS = 20
DEFAULT_MAX_ATTEMPTS = 5


class Result(enum.IntEnum):
    """What one sink or poll call did (same values as C ``att_link_result``)."""

    NONE = 0
    IDLE = 1
    SEND = 2
    DISCARDED = 3
    SYN_RX = 4
    DATA_RX = 5
    ACCEPTED = 6
    REJECTED = 7
    TIMEOUT = 8
    GAVE_UP = 9


@dataclass
class SenderStats:
    blocks_sent: int = 0  # data blocks transmitted (every attempt reaching the checksum)
    blocks_accepted: int = 0  # 0x00 answers received
    naks: int = 0  # 0xFF answers received
    timeouts: int = 0  # waits for 0xBB or for the answer that expired
    gave_up: int = 0  # blocks abandoned after max_attempts
    bytes_discarded: int = 0  # received bytes not expected in the current state

    @property
    def retries(self) -> int:
        """Restarts from 0xAA for the same block (= naks + timeouts - gave_up)."""
        return self.naks + self.timeouts - self.gave_up

    def as_dict(self) -> dict[str, int]:
        d = asdict(self)
        d["retries"] = self.retries
        return d


@dataclass
class ReceiverStats:
    syns: int = 0  # 0xAA received while idle (answered 0xBB)
    blocks_accepted: int = 0  # checksum matched (answered 0x00)
    naks: int = 0  # checksum mismatch (answered 0xFF)
    timeouts: int = 0  # partial blocks dropped after a too long gap
    resyncs: int = 0  # handshakes found after discarding bytes while idle
    bytes_discarded: int = 0  # bytes ignored while idle + bytes of dropped partial blocks

    def as_dict(self) -> dict[str, int]:
        return asdict(self)


def checksum(data: bytes | bytearray) -> int:
    """The protocol's checksum: sum of the data bytes modulo 256."""
    return sum(data) % 256


def _check_int(name: str, value: object, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise InvalidType(f"{name} must be an int, got {type(value).__name__}")
    if not lo <= value <= hi:
        raise InvalidArgument(f"{name} must be in {lo}..{hi}, got {value}")
    return value


def _byte(value: object) -> int:
    return _check_int("byte", value, 0, 255)


def _elapsed(now: int, start: int) -> int:
    """Ticks from start to now on a 16-bit wrapping counter."""
    return (now - start) & 0xFFFF


class Sender:
    """Sender A in Python (see docs/link.md, "Sender A")."""

    def __init__(self, block_size: int = BLOCK_DEFAULT, syn_timeout: int = DEFAULT_SYN_TIMEOUT_MS,
                 answer_timeout: int = DEFAULT_ANSWER_TIMEOUT_MS,
                 max_attempts: int = DEFAULT_MAX_ATTEMPTS) -> None:
        self.block_size = _check_int("block_size", block_size, BLOCK_MIN, BLOCK_MAX)
        self.syn_timeout = _check_int("syn_timeout", syn_timeout, 1, TIMEOUT_MAX)
        self.answer_timeout = _check_int("answer_timeout", answer_timeout, 1, TIMEOUT_MAX)
        self.max_attempts = _check_int("max_attempts", max_attempts, 1, 255)
        self.stats = SenderStats()
        self.reset()

    def reset(self) -> None:
        """Forget the block in progress (a reboot); statistics are kept."""
        self._phase = "idle"
        self._block = b""
        self._next = 0  # next data byte
        self._tries = 0  # attempts started for this block
        self._since = 0  # tick the running wait began

    @property
    def idle(self) -> bool:
        return self._phase == "idle"

    def start(self, block: bytes, tick: int) -> None:
        block = bytes(block)
        if len(block) != self.block_size:
            raise InvalidArgument(f"block must have {self.block_size} bytes, got {len(block)}")
        if self._phase != "idle":
            raise LinkBusy("Sender.start: the previous block is still in progress")
        self._block = block
        self._tries = 0
        self._next = 0
        self._since = tick & 0xFFFF
        self._phase = "send AA"

    # The two waits and how long they may last.
    def _limit(self) -> int | None:
        if self._phase == "wait BB":
            return self.syn_timeout
        if self._phase == "wait answer":
            return self.answer_timeout
        return None

    def _expired(self, tick: int) -> bool:
        limit = self._limit()
        return limit is not None and _elapsed(tick, self._since) > limit

    def _attempt_failed(self) -> str:
        return "send AA" if self._tries < self.max_attempts else "give up"

    def sink(self, byte: int, tick: int) -> Result:
        byte = _byte(byte)
        if self._expired(tick):  # the byte came too late: the wait is already over
            self.stats.timeouts += 1
            self._phase = "timed out"
        if self._phase == "wait BB" and byte == SYN_ACK:
            self._phase = "send data"
            self._next = 0
            return Result.SYN_RX
        if self._phase == "wait answer" and byte == ACK:
            self.stats.blocks_accepted += 1
            self._phase = "idle"
            return Result.ACCEPTED
        if self._phase == "wait answer" and byte == NAK:
            self.stats.naks += 1
            self._phase = self._attempt_failed()
            return Result.REJECTED
        self.stats.bytes_discarded += 1
        return Result.DISCARDED

    def poll(self, tick: int) -> tuple[Result, int | None]:
        tick &= 0xFFFF
        phase = self._phase
        if phase == "idle":
            return Result.IDLE, None
        if phase == "send AA":
            self._tries += 1
            self._since = tick
            self._phase = "wait BB"
            return Result.SEND, SYN
        if phase == "send data":
            byte = self._block[self._next]
            self._next += 1
            if self._next == self.block_size:
                self._phase = "send sum"
            return Result.SEND, byte
        if phase == "send sum":
            self.stats.blocks_sent += 1
            self._since = tick
            self._phase = "wait answer"
            return Result.SEND, checksum(self._block)
        if phase in ("wait BB", "wait answer"):
            if not self._expired(tick):
                return Result.NONE, None
            self.stats.timeouts += 1
            self._phase = self._attempt_failed()
            return Result.TIMEOUT, None
        if phase == "timed out":
            self._phase = self._attempt_failed()
            return Result.TIMEOUT, None
        # "give up"
        self.stats.gave_up += 1
        self._phase = "idle"
        return Result.GAVE_UP, None

    def ticks_left(self, now: int) -> int | None:
        """Ticks until poll acts on a timer (0: now), None if idle."""
        if self._phase == "idle":
            return None
        limit = self._limit()
        if limit is None:
            return 0
        el = _elapsed(now, self._since)
        return 0 if el > limit else limit - el + 1


class Receiver:
    """Receiver B in Python (see docs/link.md, "Receiver B")."""

    def __init__(self, block_size: int = BLOCK_DEFAULT,
                 gap_timeout: int = DEFAULT_GAP_TIMEOUT_MS) -> None:
        self.block_size = _check_int("block_size", block_size, BLOCK_MIN, BLOCK_MAX)
        self.gap_timeout = _check_int("gap_timeout", gap_timeout, 1, TIMEOUT_MAX)
        self.stats = ReceiverStats()
        self.block = b""  # the last accepted block
        self.reset()

    def reset(self) -> None:
        """Back to idle (a reboot): partial block and queued answer forgotten."""
        self._in_block = False
        self._data = bytearray()
        self._last = 0  # tick of the last byte of the block (or of 0xBB leaving)
        self._out: int | None = None
        self._timeout_to_report = False
        self._garbage = False  # bytes discarded while idle since the last handshake

    def _gap_over(self, tick: int) -> bool:
        return self._in_block and _elapsed(tick, self._last) > self.gap_timeout

    def _drop(self) -> None:
        self.stats.timeouts += 1
        self.stats.bytes_discarded += len(self._data)
        self._in_block = False
        self._data = bytearray()
        if self._out == SYN_ACK:
            self._out = None  # a 0xBB not sent yet is void now

    def sink(self, byte: int, tick: int) -> Result:
        byte = _byte(byte)
        tick &= 0xFFFF
        if self._gap_over(tick):
            self._drop()
            self._timeout_to_report = True
        if not self._in_block:
            if byte != SYN:
                self.stats.bytes_discarded += 1
                self._garbage = True
                return Result.DISCARDED
            self.stats.syns += 1
            if self._garbage:
                self.stats.resyncs += 1
                self._garbage = False
            self._in_block = True
            self._data = bytearray()
            self._last = tick
            self._out = SYN_ACK
            return Result.SYN_RX
        if len(self._data) < self.block_size:
            self._data.append(byte)
            self._last = tick
            return Result.DATA_RX
        # this byte is the checksum
        good = byte == checksum(self._data)
        self._in_block = False
        if good:
            self.block = bytes(self._data)
            self.stats.blocks_accepted += 1
            self._out = ACK
            return Result.ACCEPTED
        self.stats.naks += 1
        self._out = NAK
        return Result.REJECTED

    def poll(self, tick: int) -> tuple[Result, int | None]:
        tick &= 0xFFFF
        if self._gap_over(tick):
            self._drop()
            return Result.TIMEOUT, None
        if self._timeout_to_report:
            self._timeout_to_report = False
            return Result.TIMEOUT, None
        if self._out is not None:
            out, self._out = self._out, None
            if out == SYN_ACK and self._in_block and not self._data:
                self._last = tick  # the gap is counted from 0xBB leaving
            return Result.SEND, out
        return (Result.NONE if self._in_block else Result.IDLE), None

    def ticks_left(self, now: int) -> int | None:
        if self._out is not None or self._timeout_to_report:
            return 0
        if not self._in_block:
            return None
        el = _elapsed(now, self._last)
        return 0 if el > self.gap_timeout else self.gap_timeout - el + 1
