"""Stopping a command on SIGINT/SIGTERM whatever it is blocked in, as attitude-rx does
(docs/attitude-rx.md, "Stopping: bounded, whatever is blocked").

A signal handler that only sets an event is not enough when the command is blocked
writing to a full stdout (a pipe nobody reads): Python retries an interrupted write
(PEP 475) and the event is never looked at. :class:`Stop` also wakes a self-pipe, and
:class:`LineWriter` waits for stdout in ``poll()`` beside that pipe: after a stop, what
is being written gets :data:`GRACE_S`; past it, lines are counted (``lost``), not written.
"""

from __future__ import annotations

import os
import select
import signal
import sys
import threading
import time
from typing import Any

#: Seconds a line being written gets after a stop before it is counted as lost (attitude-rx's).
GRACE_S = 0.5


class Stop:
    """``event`` set by SIGINT and SIGTERM (handlers installed from the main thread only),
    ``at``: when (time.monotonic()), and a self-pipe (``wake_fd``) readable from then on."""

    def __init__(self) -> None:
        self.event = threading.Event()
        self.at: float | None = None
        self.wake_fd, self._w = os.pipe()
        os.set_blocking(self.wake_fd, False)
        os.set_blocking(self._w, False)
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, self._handler)
            signal.signal(signal.SIGTERM, self._handler)

    def _handler(self, signum: int, frame: Any) -> None:
        self.set()

    def set(self) -> None:
        if self.at is None:
            self.at = time.monotonic()
        self.event.set()
        try:
            os.write(self._w, b"\0")
        except BlockingIOError:  # already awake
            pass


class LineWriter:
    """``write(line)``: one line to ``stream`` (default sys.stdout) that a stop does not wait
    for past :data:`GRACE_S`. ``lost`` counts the lines a blocked stdout kept after it.
    A stream without a descriptor (tests' capture) is written with print()."""

    def __init__(self, stop: Stop, stream: Any = None, grace: float = GRACE_S) -> None:
        self.stop, self.grace, self.lost = stop, grace, 0
        self.stream = sys.stdout if stream is None else stream
        try:
            self.fd: int | None = self.stream.fileno()
        except (AttributeError, OSError, ValueError):
            self.fd = None
        self.stream.flush()  # what print() buffered goes first

    def write(self, line: str) -> None:
        fd = self.fd
        if fd is None:
            print(line, file=self.stream, flush=True)
            return
        if self.lost:  # stdout given up after a stop: count the rest
            self.lost += 1
            return
        data = (line + "\n").encode()
        poller = select.poll()
        poller.register(fd, select.POLLOUT)
        poller.register(self.stop.wake_fd, select.POLLIN)
        while data:
            if not self._wait(poller, fd):
                self.lost += 1
                return
            n = os.write(fd, data[:select.PIPE_BUF])  # never more than poll() said fits
            data = data[n:]

    def _wait(self, poller: select.poll, fd: int) -> bool:
        """Wait until stdout takes bytes: True; False once the grace time after a stop is over."""
        while True:
            timeout = None
            if self.stop.at is not None:
                timeout = max(0.0, self.stop.at + self.grace - time.monotonic()) * 1000.0
            events = dict(poller.poll(timeout))
            if events.get(fd):
                return True
            if not events:
                return False
            try:  # the stop's wake-up: go round with the grace time
                os.read(self.stop.wake_fd, 64)
            except BlockingIOError:
                pass
