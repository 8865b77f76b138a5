"""Link v2 ends on a real port (pyserial URL or device, a pty, ``socket://``),
in real time with millisecond ticks: :func:`run_sender2` streams records,
:func:`run_receiver2` delivers them (docs/link.md, "Link v2")."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any, Callable, Literal

import serial

from ..errors import InvalidArgument, LinkError
from .transport import _Clock, _Limits, _read, _write, serve
from .v2 import RECORD, Receiver2, Result2, Sender2
from .v2c import CReceiver2, CSender2

Impl = Literal["c", "python"]
#: Retransmission timeout on real ports (ms): a full frame and its ACK (95 ms at 9600 baud) plus
#: OS buffering and scheduling latency of both ends.
PORT_RTO_MS = 300


@dataclass
class Receiver2Report:
    records: list[bytes] = field(default_factory=list)
    ended_by: str = ""  # "count", "duration", "stop", "eof", "error"
    error: str = ""
    stats: dict[str, int] = field(default_factory=dict)


@dataclass
class Sender2Report:
    pushed: int = 0
    acknowledged: int = 0
    ended_by: str = ""  # "done", "timeout", "stop", "error"
    error: str = ""
    stats: dict[str, int] = field(default_factory=dict)


def _out_waiting(port: Any) -> int:
    """Bytes written but not yet sent (TIOCOUTQ); 0 where a port cannot tell (sockets)."""
    try:
        return int(port.out_waiting)
    except (AttributeError, OSError, NotImplementedError, ValueError, serial.SerialException):
        return 0


def _drain2(end: Any, out: bytearray) -> None:
    """Collect every byte a link v2 receiver wants to send now (its answers) into ``out``."""
    while True:
        r, o = end.poll()
        if r != Result2.SEND or o is None:
            return
        out.append(o)


def _impl(impl: str) -> None:
    if impl not in ("c", "python"):
        raise InvalidArgument(f'impl must be "c" or "python", got {impl!r}')


class _V2End:
    """Receiver B of link v2 for :func:`~attitude_c.link.transport.serve`: the caller's room
    set before each read, answers drained after every byte, the records a frame delivers."""

    def __init__(self, rx: Any, room: Callable[[], int] | None) -> None:
        self.rx, self.room, self.delivered = rx, room, 0

    def wait_s(self) -> float:
        self.rx.set_room(min(0xFFFF, max(0, self.room())) if self.room is not None else 0xFFFF)
        return 0.01

    def feed(self, data: bytes) -> tuple[list[bytes], bytes]:
        out, got = bytearray(), []
        for b in data:
            if self.rx.sink(b) == Result2.DELIVERED:
                got.extend(self.rx.delivered)
            _drain2(self.rx, out)  # answer at once
        _drain2(self.rx, out)
        self.delivered += len(got)
        return got, bytes(out)


def run_receiver2(port: Any, *, impl: Impl = "c", count: int | None = None, duration: float | None = None,
                  on_record: Callable[[bytes], None] | None = None, room: Callable[[], int] | None = None,
                  stop: threading.Event | None = None, eof_after: float | None = None,
                  keep_records: bool = True, receiver: Any = None) -> Receiver2Report:
    """Run receiver B until ``count`` records, ``duration`` s, ``stop`` or ``eof_after`` s of
    silence. ``room()`` says how many records the caller can take now (default: always
    room); every record handed to ``on_record`` is acknowledged, none other. ``receiver``:
    a receiver to go on with (:func:`listen_auto`'s), default a new one of ``impl``."""
    _impl(impl)
    rx: Any = receiver if receiver is not None else (CReceiver2() if impl == "c" else Receiver2())
    rep = Receiver2Report()
    rep.ended_by, rep.error = serve(port, _V2End(rx, room), _Limits(stop, duration, eof_after), count,
                                    on_record, rep.records if keep_records else None)
    rep.stats = rx.stats.as_dict()
    return rep


def run_sender2(port: Any, records: Iterable[bytes], *, impl: Impl = "c", rto_ms: int = PORT_RTO_MS,
                max_samples: int = 16, ring_size: int = 64, timeout: float | None = None,
                stop: threading.Event | None = None) -> Sender2Report:
    """Stream ``records`` (6-byte block-format records) with sender A until every one is
    acknowledged, ``timeout`` s pass or ``stop`` is set."""
    _impl(impl)
    tx: Any = (CSender2 if impl == "c" else Sender2)(ring_size, max_samples, rto_ms)
    it = iter(records)
    pending: bytes | None = None
    exhausted = False
    clock = _Clock()
    rep = Sender2Report()
    limits = _Limits(stop, timeout, late="timeout")
    baud = getattr(port, "baudrate", None)
    byte_s = 10.0 / baud if isinstance(baud, int) and baud > 0 else 0.0  # 8N1
    busy_until = 0.0
    try:
        while True:
            while not exhausted and tx.room > 0:
                if pending is None:
                    nxt = next(it, None)
                    if nxt is None:
                        exhausted = True
                        break
                    if len(nxt) != RECORD:
                        raise InvalidArgument(f"record {rep.pushed} must be {RECORD} bytes, got {len(nxt)}")
                    pending = bytes(nxt)
                tx.push(pending)
                pending = None
                rep.pushed += 1
            rep.ended_by = "done" if exhausted and tx.pending == 0 else limits.ended()
            if rep.ended_by:
                break
            out = bytearray()
            # one frame at a time, once the line has carried the last one (a UART's "transmitter
            # free"): A's timer runs from a frame's end, so frames must not queue up in buffers
            # (the kernel's, a bridge's) where the timer cannot see them; the port's nominal rate
            # says when the line is free
            free = time.monotonic() >= busy_until and _out_waiting(port) == 0
            while free:
                r, o = tx.poll(clock())
                if r == Result2.SEND and o is not None:
                    out.append(o)
                    if o == 0 and len(out) > 1:
                        break  # the delimiter that ends a frame
                elif r != Result2.TIMEOUT:
                    break
            if out:
                _write(port, bytes(out))
                busy_until = max(time.monotonic(), busy_until) + len(out) * byte_s
            left = tx.ticks_left(clock())
            wait = min(0.01, max(0.0005, left / 1000.0), max(0.0005, busy_until - time.monotonic()))
            data = _read(port, wait)
            for b in data:
                tx.sink(b, clock())
    except LinkError as exc:
        rep.ended_by, rep.error = "error", str(exc)
    rep.acknowledged = rep.pushed - tx.pending
    rep.stats = tx.stats.as_dict()
    return rep


# ---- --protocol auto: which protocol does the board speak? ----

@dataclass
class Heard:
    """What :func:`listen_auto` heard. ``protocol`` "legacy" or "v2" (``""``: the listening
    ended first, ``ended_by`` says why); ``legacy`` / ``v2``: the two receivers, to go on with
    (``run_receiver(..., receiver=heard.legacy)`` / ``run_receiver2(..., receiver=heard.v2)``)
    on ``heard.port``, which hands out first the bytes read after the deciding one."""

    protocol: str
    legacy: Any
    v2: Any
    port: Any
    records: int = 0  # v2 records handed to on_record while listening (0 unless a SYN came first)
    ended_by: str = ""
    error: str = ""


class _Prefixed:
    """``port`` whose reads return ``data`` first (what was read past the deciding byte)."""

    def __init__(self, port: Any, data: bytes) -> None:
        self.port = port
        self.data = bytearray(data)
        self.name = getattr(port, "name", port)

    @property
    def timeout(self) -> Any:
        return self.port.timeout

    @timeout.setter
    def timeout(self, value: Any) -> None:
        self.port.timeout = value

    @property
    def in_waiting(self) -> int:
        return len(self.data) if self.data else int(getattr(self.port, "in_waiting", 0))

    def read(self, n: int = 1) -> bytes:
        if self.data:
            out = bytes(self.data[:n])
            del self.data[:n]
            return out
        return bytes(self.port.read(n))

    def write(self, data: bytes) -> Any:
        return self.port.write(data)

    def flush(self) -> None:
        self.port.flush()


def _decodes(block: bytes) -> bool:
    """Every 6-byte record of a legacy block decodes alone (attitude/block.h)."""
    from .block import try_decode

    return all(try_decode(block[k:k + RECORD])[1] == 0 for k in range(0, len(block) - RECORD + 1, RECORD))


def listen_auto(port: Any, *, impl: Impl = "c", block_size: int = 6, gap_timeout_ms: int = 20,
                on_block: Callable[[bytes], None] | None = None,
                on_record: Callable[[bytes], None] | None = None, stop: threading.Event | None = None,
                duration: float | None = None, eof_after: float | None = None) -> Heard:
    """Feed every byte to a legacy receiver (answering it) and a link v2 receiver until one hears
    its protocol: a valid v2 frame (answered here: a SYN's SYNACK, a DATA frame's F_NOSESSION,
    so the sender sends its records again), or a legacy block whose records all decode
    (handed to ``on_block`` and acknowledged here). A legacy block that does not decode (a v2
    frame's bytes pass the 8-bit sum 1 time in 256) is handed to ``on_block`` as the legacy
    link would, and decides nothing. As attitude-rx ``--link auto`` (docs/link.md)."""
    from .cends import make_receiver
    from .protocol import Result
    from .transport import _drain

    _impl(impl)
    old = make_receiver(impl, block_size=block_size, gap_timeout=gap_timeout_ms)
    new: Any = CReceiver2() if impl == "c" else Receiver2()
    new.set_room(0xFFFF)
    clock = _Clock()
    limits = _Limits(stop, duration, eof_after)
    heard = Heard("", old, new, port)
    try:
        while True:
            heard.ended_by = limits.ended()
            if heard.ended_by:
                return heard
            data = limits.read(port, 0.01)
            if data is None:
                heard.ended_by = "eof"
                return heard
            tick = clock()
            out = bytearray()
            for i, b in enumerate(data):
                st = new.sink(b)
                if st in (Result2.FRAME, Result2.DELIVERED):
                    heard.protocol = "v2"
                    for rec in (new.delivered if st == Result2.DELIVERED else []):
                        heard.records += 1
                        if on_record is not None:
                            on_record(rec)
                    _drain2(new, out)
                elif old.sink(b, tick) is Result.ACCEPTED:
                    blk = bytes(old.block)
                    if on_block is not None:
                        on_block(blk)
                    if _decodes(blk):
                        heard.protocol = "legacy"
                    _drain(old, tick, out)
                else:
                    _drain(old, tick, out)
                if heard.protocol:
                    heard.port = _Prefixed(port, bytes(data[i + 1:]))
                    break
            if not heard.protocol:
                _drain(old, tick, out)  # a timeout's answer
            if out:
                _write(port, bytes(out))
            if heard.protocol:
                return heard
    except LinkError as exc:
        heard.ended_by, heard.error = "error", str(exc)
        return heard
