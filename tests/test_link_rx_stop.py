"""``attitude link-rx`` stops on SIGTERM while its stdout is a full pipe (issue 29, item 11).

The receiver is handed a block (legacy) or a record (link v2) it must print into a pipe
that is already full and that nobody reads. Python retries a write interrupted by a
signal (PEP 475), so a handler that only sets an event never ends such a command; link-rx
waits for stdout in poll() beside a self-pipe the handler wakes (attitude_c/cli/stopping.py)
and ends after the grace time, its statistics on stderr with the lines it could not print.

The test plays the sender byte by byte on a pseudo-terminal, so each step is known to
have happened before the next: link-rx has opened the port (its "listening" line), has
answered the handshake (0xBB / a SYNACK frame), has read the data (its read count in
/proc/PID/io), then SIGTERM."""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager

import pytest
from conftest import ROOT

from attitude_c.cli.link import EXIT_RX_BLOCKED
from attitude_c.cli.stopping import GRACE_S
from attitude_c.link.protocol import SYN, SYN_ACK, checksum
from attitude_c.link.v2 import Sender2

pytestmark = pytest.mark.system  # runs link-rx as a process

ENV = {**os.environ, "PYTHONPATH": str(ROOT)}
RECORD = bytes([0x08, 0x00, 0x08, 0x10, 0x07, 0xF0])  # one 6-byte record (codes 2048, 2064, 2032)
#: A failure bound, not a synchronization: the step is already due when the wait starts.
STEP_S = 20.0
#: SIGTERM to exit: a failure bound, not a timing. link-rx gives up on stdout GRACE_S after the
#: signal (exit 3 and lines_lost say it did); the rest is the interpreter's shutdown, which
#: under `pytest -n 2` on a loaded 2-core machine (load 16 measured) took over 4 s. Before the
#: fix link-rx never exits (blocked in write), so the bound only has to be finite.
EXIT_S = GRACE_S + 30.0


def _full_pipe() -> tuple[int, int]:
    """A pipe whose buffer is full (a reader that stopped reading)."""
    r, w = os.pipe()
    os.set_blocking(w, False)
    for chunk in (65536, 1):
        try:
            while True:
                os.write(w, b"x" * chunk)
        except BlockingIOError:
            pass
    os.set_blocking(w, True)
    return r, w


def _read_some(fd: int) -> bytes:
    ready, _, _ = select.select([fd], [], [], STEP_S)
    assert ready, "link-rx did not answer"
    return os.read(fd, 256)


def _rchar(pid: int) -> int:
    """Bytes process ``pid`` has read so far (/proc/PID/io)."""
    with open(f"/proc/{pid}/io") as f:
        return next(int(ln.split()[1]) for ln in f if ln.startswith("rchar:"))


def _until_read(pid: int, want: int) -> None:
    """Wait until link-rx has read ``want`` bytes in all (the count taken before the write:
    taken after it, a read that came first would be missed and the wait never end)."""
    deadline = time.monotonic() + STEP_S
    while _rchar(pid) < want:
        assert time.monotonic() < deadline, "link-rx did not read its port"
        select.select([], [], [], 0.001)


def _send_legacy(master: int) -> bytes:
    """The handshake; returns the block to send (data and checksum)."""
    os.write(master, bytes([SYN]))
    assert _read_some(master) == bytes([SYN_ACK])
    return RECORD + bytes([checksum(RECORD)])


def _send_v2(master: int) -> bytes:
    """The session's start (SYN, SYNACK); returns the DATA frame carrying the record."""
    tx = Sender2(4, 1, 32767)  # tick 0 throughout: no retransmission
    tx.push(RECORD)

    def frame() -> bytes:
        out = bytearray()
        while (r := tx.poll(0))[1] is not None:
            out.append(r[1])
        return bytes(out)

    os.write(master, frame())  # SYN
    while tx.session != "run":  # until the SYNACK
        for b in _read_some(master):
            tx.sink(b, 0)
    return frame()


@contextmanager
def _link_rx(*argv: str) -> Iterator[tuple[subprocess.Popen, int]]:
    master, slave = os.openpty()
    r, w = _full_pipe()
    proc = subprocess.Popen([sys.executable, "-m", "attitude_c", "link-rx", "--port", os.ttyname(slave), *argv],
                            stdout=w, stderr=subprocess.PIPE, env=ENV, text=True)
    os.close(w)
    try:
        assert proc.stderr is not None
        assert "listening on" in proc.stderr.readline()  # the port is open
        yield proc, master
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        for fd in (master, slave, r):
            os.close(fd)


@pytest.mark.parametrize("protocol", ["legacy", "v2"])
@pytest.mark.parametrize("decode", [False, True])
def test_link_rx_stops_on_sigterm_with_stdout_full(protocol: str, decode: bool) -> None:
    # the legacy receiver drops a block whose bytes are more than --gap-timeout-ms apart: this
    # test, not a UART, sends the block after reading 0xBB, so it gets the longest gap allowed
    gap = ["--gap-timeout-ms", "32767"] if protocol == "legacy" else []
    argv = ["--protocol", protocol, *gap, *(["--decode"] if decode else [])]
    with _link_rx(*argv) as (proc, master):
        data = (_send_v2 if protocol == "v2" else _send_legacy)(master)
        before = _rchar(proc.pid)
        os.write(master, data)
        _until_read(proc.pid, before + len(data))  # the record is in link-rx's hands: it must print it
        proc.send_signal(signal.SIGTERM)
        try:
            err = proc.communicate(timeout=EXIT_S)[1]
        except subprocess.TimeoutExpired:
            pytest.fail(f"link-rx still running {EXIT_S:g} s after SIGTERM with stdout full")
    assert proc.returncode == EXIT_RX_BLOCKED, err
    stats = next(ln for ln in err.splitlines() if ln.startswith("link-rx stats: "))
    counters = json.loads(stats[len("link-rx stats: "):stats.rindex(" (ended by")])
    assert counters["lines_lost"] == 1, err
    assert "(ended by stop)" in stats and "Traceback" not in err, err
