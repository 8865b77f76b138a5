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
from .transport import _Clock, _read, _write
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


def _impl(impl: str) -> None:
    if impl not in ("c", "python"):
        raise InvalidArgument(f'impl must be "c" or "python", got {impl!r}')


def run_receiver2(port: Any, *, impl: Impl = "c", count: int | None = None, duration: float | None = None,
                  on_record: Callable[[bytes], None] | None = None, room: Callable[[], int] | None = None,
                  stop: threading.Event | None = None, eof_after: float | None = None,
                  keep_records: bool = True) -> Receiver2Report:
    """Run receiver B until ``count`` records, ``duration`` s, ``stop`` or ``eof_after`` s of
    silence. ``room()`` says how many records the caller can take now (default: always
    room); every record handed to ``on_record`` is acknowledged, none other."""
    _impl(impl)
    rx: Any = CReceiver2() if impl == "c" else Receiver2()
    rep = Receiver2Report()
    t_end = None if duration is None else time.monotonic() + duration
    last = time.monotonic()
    n = 0
    try:
        while True:
            if stop is not None and stop.is_set():
                rep.ended_by = "stop"
                break
            if t_end is not None and time.monotonic() >= t_end:
                rep.ended_by = "duration"
                break
            rx.set_room(min(0xFFFF, max(0, room())) if room is not None else 0xFFFF)
            data = _read(port, 0.01)
            now = time.monotonic()
            if data:
                last = now
            elif eof_after is not None and now - last > eof_after:
                rep.ended_by = "eof"
                break
            out = bytearray()
            for b in data:
                if rx.sink(b) == Result2.DELIVERED:
                    for rec in rx.delivered:
                        n += 1
                        if keep_records:
                            rep.records.append(rec)
                        if on_record is not None:
                            on_record(rec)
                while True:  # answer at once
                    r, o = rx.poll()
                    if r != Result2.SEND or o is None:
                        break
                    out.append(o)
            while True:
                r, o = rx.poll()
                if r != Result2.SEND or o is None:
                    break
                out.append(o)
            if out:
                _write(port, bytes(out))
            if count is not None and n >= count:
                rep.ended_by = "count"
                break
    except LinkError as exc:
        rep.ended_by, rep.error = "error", str(exc)
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
    t_end = None if timeout is None else time.monotonic() + timeout
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
            if exhausted and tx.pending == 0:
                rep.ended_by = "done"
                break
            if stop is not None and stop.is_set():
                rep.ended_by = "stop"
                break
            if t_end is not None and time.monotonic() >= t_end:
                rep.ended_by = "timeout"
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
