"""Real serial transports for the link (pyserial) and real-time loops that
run either end, C or Python, on a port.

- :func:`open_port`: any pyserial URL or device (``/dev/ttyS1``,
  ``loop://``, ``socket://host:port``, ``spy://...``), 9600 8N1, raw
  (pyserial puts a POSIX tty in raw mode: the same as ``cfmakeraw``);
- :class:`PtyPair`: two real pseudo-terminals (raw) joined by a bridge
  thread, optionally paced at a baud rate and passed through the channel
  model (:class:`~attitude_c.link.sim.ChannelConfig`);
- :class:`SocketRelay`: a local TCP relay joining two ``socket://`` clients,
  with the same options;
- :func:`run_sender` / :func:`run_receiver`: the ends on a port, ticks in
  milliseconds of ``time.monotonic``.

Every wait has a timeout; a dead port raises :class:`LinkError` after the
blocks already accepted were handed to the caller.
"""

from __future__ import annotations

import os
import select
import socket
import threading
import time
import tty
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any, Callable, Literal

import serial

from ..errors import InvalidArgument, LinkError
from .cends import Impl, make_receiver, make_sender
from .protocol import (
    BLOCK_DEFAULT,
    DEFAULT_ANSWER_TIMEOUT_MS,
    DEFAULT_GAP_TIMEOUT_MS,
    DEFAULT_MAX_ATTEMPTS,
    DEFAULT_SYN_TIMEOUT_MS,
    Result,
)
from .sim import BITS_PER_BYTE, Channel, ChannelConfig

#: What :func:`run_sender` does when a block is given up after the first handshake.
GiveUpPolicy = Literal["skip", "fail"]
GIVE_UP_POLICIES: tuple[GiveUpPolicy, ...] = ("skip", "fail")


def open_port(url: str, baud: int = 9600, timeout: float = 0.005) -> serial.SerialBase:
    """Open a pyserial URL or device at ``baud`` 8N1, no flow control, raw."""
    if not isinstance(url, str) or not url:
        raise InvalidArgument(f"port must be a non-empty device path or pyserial URL, got {url!r}")
    if isinstance(baud, bool) or not isinstance(baud, int) or baud <= 0:
        raise InvalidArgument(f"baud must be a positive int, got {baud!r}")
    try:
        port = serial.serial_for_url(
            url, baudrate=baud, bytesize=serial.EIGHTBITS, parity=serial.PARITY_NONE,
            stopbits=serial.STOPBITS_ONE, timeout=timeout, write_timeout=2.0,
            xonxoff=False, rtscts=False, dsrdtr=False)
    except (serial.SerialException, ValueError, OSError) as exc:
        raise LinkError(f"cannot open port {url!r}: {exc}") from exc
    return port


# -- bridges -------------------------------------------------------------


class _Bridge:
    """Forward bytes both ways between two endpoints, optionally paced at
    ``baud`` (one byte per 10 bit times) and through a channel model."""

    def __init__(self, baud: int | None, channel: ChannelConfig | None) -> None:
        self.baud = baud
        self._channel = Channel(channel, baud or 9600) if channel is not None else None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._t0 = time.monotonic()
        self.forwarded = [0, 0]

    def _start(self, read0: Callable[[], bytes], write0: Callable[[bytes], None],
               read1: Callable[[], bytes], write1: Callable[[bytes], None]) -> None:
        for d, (rd, wr) in enumerate(((read0, write1), (read1, write0))):
            th = threading.Thread(target=self._pump, args=(d, rd, wr), daemon=True,
                                  name=f"link-bridge-{d}")
            th.start()
            self._threads.append(th)

    def _pump(self, direction: int, read: Callable[[], bytes], write: Callable[[bytes], None]) -> None:
        next_free = 0.0
        byte_time = BITS_PER_BYTE / self.baud if self.baud else 0.0
        while not self._stop.is_set():
            try:
                data = read()
            except OSError:
                return
            if data is None:
                continue
            if data == b"":
                return  # end closed
            for b in data:
                now = time.monotonic()
                if byte_time:
                    start = max(now, next_free)
                    next_free = start + byte_time
                    if next_free > now:
                        time.sleep(next_free - now)  # the byte arrives when fully shifted in
                else:
                    start = now
                out = bytes([b])
                if self._channel is not None:
                    tick = int((start - self._t0) * (self.baud or 9600))
                    with self._lock:
                        out = self._channel.transmit(direction, b, tick)
                if out:
                    try:
                        write(out)
                    except OSError:
                        return
                    self.forwarded[direction] += len(out)

    def channel_stats(self) -> dict[str, dict[str, int]] | None:
        return self._channel.stats() if self._channel is not None else None

    def _stop_threads(self) -> None:
        self._stop.set()
        for th in self._threads:
            th.join(timeout=2.0)


def _paths_claimed_by_others() -> set[str]:
    """/dev/pts paths named on the command line of other processes. A stray
    program that reopens ``--port /dev/pts/N`` by path (e.g. a leaked
    receiver in a retry loop) would read bytes off a new pty that reuses
    that number, so PtyPair does not hand such ptys out."""
    out: set[str] = set()
    me = os.getpid()
    try:
        pids = [int(p) for p in os.listdir("/proc") if p.isdigit()]
    except OSError:
        return out
    for pid in pids:
        if pid == me:
            continue
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                args = f.read().split(b"\0")
        except OSError:
            continue
        for a in args:
            if a.startswith(b"/dev/pts/"):
                out.add(a.decode(errors="replace"))
    return out


class PtyPair(_Bridge):
    """Two raw pseudo-terminals joined by a bridge: open ``.paths[0]`` for one
    end and ``.paths[1]`` for the other (``with PtyPair() as (p0, p1): ...``)."""

    def __init__(self, baud: int | None = None, channel: ChannelConfig | None = None) -> None:
        super().__init__(baud, channel)
        self._fds: list[int] = []
        masters: list[int] = []
        self.paths: list[str] = []
        claimed = _paths_claimed_by_others()
        for _ in range(64):
            if len(masters) == 2:
                break
            m, s = os.openpty()
            self._fds += [m, s]  # a skipped pty stays open until close(): not handed out again
            path = os.ttyname(s)
            if path in claimed:
                continue
            tty.setraw(s)  # cfmakeraw on the tty side
            masters.append(m)
            self.paths.append(path)
        if len(masters) != 2:
            self.close()
            raise LinkError("PtyPair: could not get two pseudo-terminals nobody else claims")
        self._masters = masters

        def reader(fd: int) -> Callable[[], bytes]:
            def read() -> bytes:
                r, _, _ = select.select([fd], [], [], 0.05)
                if not r:
                    return None  # type: ignore[return-value]
                try:
                    return os.read(fd, 256)
                except OSError:  # EIO: no process has the tty open right now
                    time.sleep(0.01)
                    return None  # type: ignore[return-value]
            return read

        def writer(fd: int) -> Callable[[bytes], None]:
            def write(data: bytes) -> None:
                while data:
                    n = os.write(fd, data)
                    data = data[n:]
            return write

        self._start(reader(masters[0]), writer(masters[0]), reader(masters[1]), writer(masters[1]))

    def close(self) -> None:
        self._stop_threads()
        for fd in self._fds:
            try:
                os.close(fd)
            except OSError:
                pass
        self._fds = []

    def __enter__(self) -> list[str]:
        return self.paths

    def __exit__(self, *exc: object) -> None:
        self.close()


class SocketRelay(_Bridge):
    """A TCP relay on 127.0.0.1: the first two clients (``.url`` each, a
    pyserial ``socket://`` URL) are joined. ``with SocketRelay() as url: ...``"""

    def __init__(self, baud: int | None = None, channel: ChannelConfig | None = None,
                 accept_timeout: float = 10.0) -> None:
        super().__init__(baud, channel)
        self._srv = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._srv.bind(("127.0.0.1", 0))
        self._srv.listen(2)
        self._srv.settimeout(accept_timeout)
        self.port = self._srv.getsockname()[1]
        self.url = f"socket://127.0.0.1:{self.port}"
        self._conns: list[socket.socket] = []
        self._acceptor = threading.Thread(target=self._accept, daemon=True, name="link-relay-accept")
        self._acceptor.start()

    def _accept(self) -> None:
        try:
            for _ in range(2):
                c, _addr = self._srv.accept()
                c.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                c.settimeout(0.05)
                self._conns.append(c)
        except OSError:
            return

        def reader(c: socket.socket) -> Callable[[], bytes]:
            def read() -> bytes:
                try:
                    return c.recv(256)
                except socket.timeout:
                    return None  # type: ignore[return-value]
            return read

        def writer(c: socket.socket) -> Callable[[bytes], None]:
            return c.sendall

        a, b = self._conns
        self._start(reader(a), writer(a), reader(b), writer(b))

    def close(self) -> None:
        self._stop_threads()
        for c in self._conns:
            try:
                c.close()
            except OSError:
                pass
        self._srv.close()
        self._acceptor.join(timeout=2.0)

    def __enter__(self) -> str:
        return self.url

    def __exit__(self, *exc: object) -> None:
        self.close()


# -- real-time ends -------------------------------------------------------


class _Clock:
    """Millisecond ticks since creation."""

    def __init__(self) -> None:
        self._t0 = time.monotonic()

    def __call__(self) -> int:
        return int((time.monotonic() - self._t0) * 1000.0)


def _read(port: Any, wait_s: float) -> bytes:
    try:
        port.timeout = wait_s
        n = port.in_waiting if hasattr(port, "in_waiting") else 0
        return port.read(max(1, n))
    except (serial.SerialException, OSError) as exc:
        raise LinkError(f"port {getattr(port, 'name', port)!r} failed: {exc}") from exc
    except (TypeError, AttributeError) as exc:  # pyserial after close() from another thread
        raise LinkError(f"port {getattr(port, 'name', port)!r} was closed") from exc


def _write(port: Any, data: bytes) -> None:
    try:
        port.write(data)
        port.flush()
    except (serial.SerialException, serial.SerialTimeoutException, OSError) as exc:
        raise LinkError(f"port {getattr(port, 'name', port)!r} failed on write: {exc}") from exc


class _Limits:
    """The ends of a real-time loop that are not the protocol's: ``stop`` set, ``duration``
    seconds past (reported as ``late``), ``eof_after`` seconds without a byte."""

    def __init__(self, stop: threading.Event | None, duration: float | None, eof_after: float | None = None,
                 late: str = "duration") -> None:
        self.stop, self.eof_after, self.late = stop, eof_after, late
        self.t_end = None if duration is None else time.monotonic() + duration
        self.last_byte = time.monotonic()

    def ended(self) -> str:
        """``"stop"``, ``late`` when the time is up, else ``""``."""
        if self.stop is not None and self.stop.is_set():
            return "stop"
        if self.t_end is not None and time.monotonic() >= self.t_end:
            return self.late
        return ""

    def read(self, port: Any, wait_s: float) -> bytes | None:
        """The bytes read within ``wait_s``; None after ``eof_after`` s without one."""
        data = _read(port, wait_s)
        now = time.monotonic()
        if data:
            self.last_byte = now
        elif self.eof_after is not None and now - self.last_byte > self.eof_after:
            return None
        return data


def _wait_s(ticks_left: int | None) -> float:
    """How long a legacy end may wait for a byte (s): until its timer is due (ms ticks),
    0.5 .. 20 ms."""
    return 0.02 if ticks_left is None else min(0.02, max(0.0005, ticks_left / 1000.0))


def _drain(rx: Any, tick: int, out: bytearray) -> None:
    """Collect every byte receiver ``rx`` wants to send now (its answers) into ``out``."""
    while True:
        r, o = rx.poll(tick)
        if r is Result.SEND:
            out.append(o)
        elif r in (Result.NONE, Result.IDLE):
            return


#: What happened to a block (:attr:`BlockReport.outcome`).
OUTCOME_ACCEPTED = "accepted"  # B answered 0x00
OUTCOME_GAVE_UP = "gave up"  # max_attempts failed after B had answered once: the block is lost
OUTCOME_NO_RECEIVER = "no receiver"  # the wait for B's first handshake ran out: block not sent
OUTCOME_INTERRUPTED = "interrupted"  # ``stop`` was set while the block was in progress


@dataclass
class BlockReport:
    """What happened to one block A sent."""

    index: int
    block: bytes
    outcome: str  # one of the OUTCOME_* strings
    attempts: int
    naks: int = 0
    timeouts: int = 0


@dataclass
class ReceiverReport:
    blocks: list[bytes] = field(default_factory=list)
    stats: dict[str, int] = field(default_factory=dict)
    ended_by: str = ""  # "count", "duration", "stop", "eof", "error"
    error: str | None = None


def serve(port: Any, end: Any, limits: _Limits, count: int | None,
          on_item: Callable[[bytes], None] | None, keep: list[bytes] | None) -> tuple[str, str]:
    """The receive loop of both protocols' receivers on a real port: read what came (waiting
    ``end.wait_s()``), hand it to ``end.feed(data) -> (delivered, answers)``, pass each
    delivered block or record to ``keep`` and ``on_item`` *before* writing the answers that
    acknowledge it, until ``limits`` end it, ``end.delivered >= count``, or the port fails.
    Returns (``ended_by``, the port's error or "")."""
    try:
        while True:
            ended = limits.ended()
            if ended:
                return ended, ""
            data = limits.read(port, end.wait_s())
            if data is None:
                return "eof", ""
            items, out = end.feed(data)
            for item in items:
                if keep is not None:
                    keep.append(item)
                if on_item is not None:
                    on_item(item)
            if out:
                _write(port, out)
            if count is not None and end.delivered >= count:
                return "count", ""
    except LinkError as exc:
        return "error", str(exc)


class _LegacyEnd:
    """Receiver B of the paper's protocol for :func:`serve`: millisecond ticks, an answer
    drained after every byte, one block per acceptance."""

    def __init__(self, rx: Any) -> None:
        self.rx, self.clock = rx, _Clock()

    @property
    def delivered(self) -> int:
        return int(self.rx.stats.blocks_accepted)

    def wait_s(self) -> float:
        return _wait_s(self.rx.ticks_left(self.clock()))

    def feed(self, data: bytes) -> tuple[list[bytes], bytes]:
        tick, out, got = self.clock(), bytearray(), []
        for b in data:
            if self.rx.sink(b, tick) is Result.ACCEPTED:
                got.append(self.rx.block)
            _drain(self.rx, tick, out)  # answer as soon as the byte asks for it
        _drain(self.rx, tick, out)
        return got, bytes(out)


def run_receiver(port: Any, *, impl: Impl = "c", block_size: int = BLOCK_DEFAULT,
                 gap_timeout_ms: int = DEFAULT_GAP_TIMEOUT_MS, count: int | None = None,
                 duration: float | None = None, on_block: Callable[[bytes], None] | None = None,
                 stop: threading.Event | None = None, eof_after: float | None = None,
                 keep_blocks: bool = True, receiver: Any = None) -> ReceiverReport:
    """Run receiver B on an open ``port`` until ``count`` blocks, ``duration``
    seconds, ``stop`` is set, or ``eof_after`` seconds of silence.
    A port failure ends the loop with ``ended_by="error"`` (the blocks
    accepted so far are in the report and were passed to ``on_block``).
    ``receiver``: an end from :func:`make_receiver` to run (its ``stats`` can
    then be read while the loop runs); default: a new one from ``impl``,
    ``block_size`` and ``gap_timeout_ms``."""
    rx = receiver if receiver is not None else make_receiver(impl, block_size=block_size,
                                                             gap_timeout=gap_timeout_ms)
    rep = ReceiverReport()
    ended_by, error = serve(port, _LegacyEnd(rx), _Limits(stop, duration, eof_after), count, on_block,
                            rep.blocks if keep_blocks else None)
    rep.ended_by, rep.error = ended_by, error or None
    rep.stats = rx.stats.as_dict()
    return rep


def run_sender(port: Any, blocks: Iterable[bytes], *, impl: Impl = "c", block_size: int = BLOCK_DEFAULT,
               syn_timeout_ms: int = DEFAULT_SYN_TIMEOUT_MS,
               answer_timeout_ms: int = DEFAULT_ANSWER_TIMEOUT_MS,
               max_attempts: int = DEFAULT_MAX_ATTEMPTS,
               on_result: Callable[[BlockReport], None] | None = None,
               stop: threading.Event | None = None,
               wait_first: float | None = 0.0,
               on_waiting: Callable[[float], None] | None = None,
               waiting_every: float = 5.0,
               on_give_up: GiveUpPolicy = "skip") -> tuple[list[BlockReport], dict[str, int]]:
    """Run sender A on an open ``port`` over ``blocks`` (each ``block_size``
    bytes). Returns one :class:`BlockReport` per block handled and A's
    statistics. Raises :class:`LinkError` if the port fails (reports so far
    are passed to ``on_result`` first).

    ``wait_first``: seconds A keeps offering its first block until B answers
    a first handshake (``0xBB``): ``None`` waits for ever, ``0`` (the
    default, the live-sampler behaviour of the firmware) treats the first
    block like any other. While waiting, A restarts the block's attempts
    instead of giving up (no ``gave_up`` is counted: only the unanswered
    ``0xAA`` as ``timeouts``) and calls ``on_waiting(seconds)`` every
    ``waiting_every`` seconds. If the wait runs out, the block is reported
    as ``"no receiver"`` and nothing more is sent.

    ``on_give_up``: what a give-up after B has answered once does:
    ``"skip"`` reports ``"gave up"`` and moves on to the next block (the
    firmware's behaviour), ``"fail"`` reports it and sends nothing more
    (the caller sees the block as the last report).

    If ``stop`` is set while a block is in progress, that block is reported
    as ``"interrupted"``."""
    if on_give_up not in GIVE_UP_POLICIES:
        raise InvalidArgument(f"on_give_up must be one of {GIVE_UP_POLICIES}, got {on_give_up!r}")
    if wait_first is not None and not (isinstance(wait_first, (int, float)) and wait_first >= 0):
        raise InvalidArgument(f"wait_first must be None or a number of seconds >= 0, got {wait_first!r}")
    if not (isinstance(waiting_every, (int, float)) and waiting_every > 0):
        raise InvalidArgument(f"waiting_every must be a number of seconds > 0, got {waiting_every!r}")
    tx = make_sender(impl, block_size=block_size, syn_timeout=syn_timeout_ms,
                     answer_timeout=answer_timeout_ms, max_attempts=max_attempts)
    clock = _Clock()
    reports: list[BlockReport] = []
    it = iter(blocks)
    cur: BlockReport | None = None
    index = 0
    # Until B has answered once, a lost handshake means "B not there yet", not a bad line.
    waiting = wait_first is None or wait_first > 0
    t_wait0 = time.monotonic()
    next_note = t_wait0 + waiting_every

    def finish(outcome: str, ok: bool = False) -> None:
        nonlocal cur
        assert cur is not None
        cur.outcome = outcome
        cur.attempts = cur.naks + cur.timeouts + (1 if ok else 0)
        reports.append(cur)
        if on_result is not None:
            on_result(cur)
        cur = None

    ended = False
    while not ended:
        if stop is not None and stop.is_set():
            if cur is not None:
                tx.reset()
                finish(OUTCOME_INTERRUPTED)
            break
        tick = clock()
        out = bytearray()
        if waiting and cur is not None:
            now = time.monotonic()
            if wait_first is not None and now - t_wait0 >= wait_first:
                tx.reset()
                finish(OUTCOME_NO_RECEIVER)
                break
            if now >= next_note:
                next_note = now + waiting_every
                if on_waiting is not None:
                    on_waiting(now - t_wait0)
        while True:
            r, o = tx.poll(tick)
            if r is Result.IDLE:
                try:
                    blk = bytes(next(it))
                except StopIteration:
                    ended = True
                    break
                tx.start(blk, tick)
                cur = BlockReport(index=index, block=blk, outcome="", attempts=0)
                index += 1
                continue
            if r is Result.SEND:
                out.append(o)  # type: ignore[arg-type]  # SEND always carries a byte
                continue
            if r is Result.TIMEOUT and cur is not None:
                cur.timeouts += 1
                if waiting:  # offer the block again, from a fresh set of attempts
                    tx.reset()
                    tx.start(cur.block, tick)
                continue
            if r is Result.GAVE_UP and cur is not None:
                finish(OUTCOME_GAVE_UP)
                if on_give_up == "fail":
                    ended = True
                    break
                continue
            break  # NONE
        if out:
            _write(port, bytes(out))
        if ended:
            break
        data = _read(port, _wait_s(tx.ticks_left(clock())))
        tick = clock()
        for b in data:
            r = tx.sink(b, tick)
            if r is Result.SYN_RX:
                waiting = False  # B is there
            elif r is Result.ACCEPTED and cur is not None:
                finish(OUTCOME_ACCEPTED, ok=True)
            elif r is Result.REJECTED and cur is not None:
                cur.naks += 1
    return reports, tx.stats.as_dict()
