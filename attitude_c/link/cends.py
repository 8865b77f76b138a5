"""The C link machines (csrc/src/link_sender.c, link_receiver.c) behind the
same Python interface as :mod:`attitude_c.link.protocol`.
"""

from __future__ import annotations

from typing import Any, Literal

from .._lib import ffi_lib
from ..errors import InvalidArgument
from ..names import raise_for_status
from .protocol import (
    BLOCK_DEFAULT,
    DEFAULT_ANSWER_TIMEOUT_MS,
    DEFAULT_GAP_TIMEOUT_MS,
    DEFAULT_MAX_ATTEMPTS,
    DEFAULT_SYN_TIMEOUT_MS,
    LinkBusy,
    ReceiverStats,
    Result,
    SenderStats,
    _byte,
    _check_int,
)

#: Which implementation of an end: the C machine or the Python one.
Impl = Literal["c", "python"]

_SENDER_FIELDS = ("blocks_sent", "blocks_accepted", "naks", "timeouts", "gave_up", "bytes_discarded")
_RECEIVER_FIELDS = ("syns", "blocks_accepted", "naks", "timeouts", "resyncs", "bytes_discarded")
_NO_TIMER = 0xFFFF


def _result(code: int, what: str) -> Result:
    if code < 0:
        raise_for_status(code, what)
    return Result(code)


class CSender:
    """Sender A: the C machine (``att_link_sender``)."""

    def __init__(self, block_size: int = BLOCK_DEFAULT, syn_timeout: int = DEFAULT_SYN_TIMEOUT_MS,
                 answer_timeout: int = DEFAULT_ANSWER_TIMEOUT_MS,
                 max_attempts: int = DEFAULT_MAX_ATTEMPTS) -> None:
        # same argument checks as the Python end, so both raise the same errors
        _check_int("block_size", block_size, 1, 64)
        _check_int("syn_timeout", syn_timeout, 1, 32767)
        _check_int("answer_timeout", answer_timeout, 1, 32767)
        _check_int("max_attempts", max_attempts, 1, 255)
        self._ffi, self._lib = ffi_lib("f64")
        ffi, lib = self._ffi, self._lib
        self._s: Any = ffi.new("att_link_sender *")
        cfg = ffi.new("att_link_sender_config *")
        lib.att_link_sender_config_init(cfg, block_size)
        cfg.syn_timeout = syn_timeout
        cfg.answer_timeout = answer_timeout
        cfg.max_attempts = max_attempts
        raise_for_status(lib.att_link_sender_init(self._s, cfg), "att_link_sender_init")
        self.block_size = block_size
        self.syn_timeout, self.answer_timeout, self.max_attempts = syn_timeout, answer_timeout, max_attempts
        self._block: Any = ffi.new("uint8_t[]", block_size)
        self._out: Any = ffi.new("uint8_t *")
        # the C counters are 16-bit (8051 RAM): extend them here
        self._total = SenderStats()
        self._last = [0] * len(_SENDER_FIELDS)

    @property
    def stats(self) -> SenderStats:
        c = self._s.stats
        for i, name in enumerate(_SENDER_FIELDS):
            v = getattr(c, name)
            setattr(self._total, name, getattr(self._total, name) + ((v - self._last[i]) & 0xFFFF))
            self._last[i] = v
        return self._total

    @property
    def idle(self) -> bool:
        return self._lib.att_link_sender_ticks_left(self._s, 0) == _NO_TIMER

    def reset(self) -> None:
        self._lib.att_link_sender_reset(self._s)

    def start(self, block: bytes, tick: int) -> None:
        block = bytes(block)
        if len(block) != self.block_size:
            raise InvalidArgument(f"block must have {self.block_size} bytes, got {len(block)}")
        if not self.idle:
            raise LinkBusy("CSender.start: the previous block is still in progress")
        self._ffi.memmove(self._block, block, self.block_size)
        raise_for_status(self._lib.att_link_sender_start(self._s, self._block, tick & 0xFFFF),
                         "att_link_sender_start")

    def sink(self, byte: int, tick: int) -> Result:
        r = _result(self._lib.att_link_sender_sink(self._s, _byte(byte), tick & 0xFFFF),
                    "att_link_sender_sink")
        if r is Result.DISCARDED:
            _ = self.stats  # keep the 16-bit extension exact under a flood of garbage
        return r

    def poll(self, tick: int) -> tuple[Result, int | None]:
        r = _result(self._lib.att_link_sender_poll(self._s, tick & 0xFFFF, self._out),
                    "att_link_sender_poll")
        if r is Result.SEND:
            return r, self._out[0]
        return r, None

    def ticks_left(self, now: int) -> int | None:
        v = self._lib.att_link_sender_ticks_left(self._s, now & 0xFFFF)
        return None if v == _NO_TIMER else int(v)


class CReceiver:
    """Receiver B: the C machine (``att_link_receiver``)."""

    def __init__(self, block_size: int = BLOCK_DEFAULT,
                 gap_timeout: int = DEFAULT_GAP_TIMEOUT_MS) -> None:
        _check_int("block_size", block_size, 1, 64)
        _check_int("gap_timeout", gap_timeout, 1, 32767)
        self._ffi, self._lib = ffi_lib("f64")
        ffi, lib = self._ffi, self._lib
        self._r: Any = ffi.new("att_link_receiver *")
        self._buf: Any = ffi.new("uint8_t[]", block_size)
        cfg = ffi.new("att_link_receiver_config *")
        lib.att_link_receiver_config_init(cfg, block_size)
        cfg.gap_timeout = gap_timeout
        raise_for_status(lib.att_link_receiver_init(self._r, cfg, self._buf),
                         "att_link_receiver_init")
        self.block_size = block_size
        self.gap_timeout = gap_timeout
        self.block = b""
        self._out: Any = ffi.new("uint8_t *")

    @property
    def stats(self) -> ReceiverStats:
        c = self._r.stats
        return ReceiverStats(**{name: int(getattr(c, name)) for name in _RECEIVER_FIELDS})

    def reset(self) -> None:
        self._lib.att_link_receiver_reset(self._r)

    def sink(self, byte: int, tick: int) -> Result:
        r = _result(self._lib.att_link_receiver_sink(self._r, _byte(byte), tick & 0xFFFF),
                    "att_link_receiver_sink")
        if r is Result.ACCEPTED:
            self.block = bytes(self._ffi.buffer(self._buf, self.block_size))
        return r

    def poll(self, tick: int) -> tuple[Result, int | None]:
        r = _result(self._lib.att_link_receiver_poll(self._r, tick & 0xFFFF, self._out),
                    "att_link_receiver_poll")
        if r is Result.SEND:
            return r, self._out[0]
        return r, None

    def ticks_left(self, now: int) -> int | None:
        v = self._lib.att_link_receiver_ticks_left(self._r, now & 0xFFFF)
        return None if v == _NO_TIMER else int(v)


def make_sender(impl: Impl = "c", **kw: int) -> CSender | Any:
    """A sender A: ``impl`` is ``"c"`` or ``"python"``; keywords as :class:`CSender`."""
    from .protocol import Sender

    if impl == "c":
        return CSender(**kw)
    if impl == "python":
        return Sender(**kw)
    raise InvalidArgument(f"impl must be 'c' or 'python', got {impl!r}")


def make_receiver(impl: Impl = "c", **kw: int) -> CReceiver | Any:
    """A receiver B: ``impl`` is ``"c"`` or ``"python"``; keywords as :class:`CReceiver`."""
    from .protocol import Receiver

    if impl == "c":
        return CReceiver(**kw)
    if impl == "python":
        return Receiver(**kw)
    raise InvalidArgument(f"impl must be 'c' or 'python', got {impl!r}")
