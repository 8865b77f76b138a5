"""attitude-rx's GNSS input (issue 30; docs/gnss.md "attitude-rx's GNSS input"): a receiver's
fixes read from a serial port (the library's own NMEA / UBX parser) or from gpsd (libgps,
replayed by gpsd's gpsfake), time-aligned with the board's aided stream (link v2 on a pty),
given to the filter and printed in the JSON Lines.

Truth: the simulator's GNSS fixes (attitude_c.sim.gnss_model on a car at rest, the first 4 s
of `car-brake`) written as NMEA and UBX logs by attitude_c.sim.gnss_log; every "gnss" object
attitude-rx prints is compared with the fix it came from within the log format's resolution.
Errors: a bad --gnss, a port that is not there, gpsd unreachable: one line and the documented
exit code."""

from __future__ import annotations

import json
import math
import os
import select
import signal
import socket
import subprocess
import threading
import time
import tty
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import require_target, require_tools
from test_attitude_rx_aided import DT, _records, _static_board

pytestmark = pytest.mark.system  # builds and runs attitude-rx, gpsd and gpsfake

KNOT = 1852.0 / 3600.0
GNSS_EVERY = 20  # board samples per GNSS epoch: 100 Hz board, 5 Hz receiver (neo-m8n)
N_FIXES = 20
FIX_NAMES = {0: "none", 2: "2d", 3: "3d"}  # the simulator's fix_type codes (UBX's) -> JSON


@pytest.fixture(scope="module")
def rx_host(tmp_path_factory: pytest.TempPathFactory) -> list[str]:
    """attitude-rx for the host (invoke cross-build), gpsd support built in when libgps is there."""
    from toolchain.tasks.cross import cross_build_target

    require_target("host")
    return [str(cross_build_target("host", out=tmp_path_factory.mktemp("rx-gnss") / "host")["app"])]


@pytest.fixture(scope="module")
def fixes() -> np.ndarray:
    """N_FIXES epochs of a neo-m8n receiver on a car at rest (car-brake's first 5 s), seed 7."""
    from attitude_c.sim.gnss_model import GnssReceiver
    from attitude_c.sim.vehicle import car_brake

    f = GnssReceiver().fixes(car_brake(), (N_FIXES - 1) * 0.2, seed=7)
    assert len(f) == N_FIXES and (f["fix_type"] == 3).all()
    return f


def _epoch(fix: Any, fmt: str) -> bytes:
    from attitude_c.sim import gnss_log

    return "".join(gnss_log.nmea_epoch(fix)).encode() if fmt == "nmea" else gnss_log.ubx_nav_pvt(fix)


def _tolerances(fmt: str, speed: float, source: str) -> tuple[float, float, float]:
    """Speed (m/s), track (deg) and velocity (m/s) error bounds: half the last digit written.
    NMEA: speed 0.001 kn, course 0.01°, the velocity from both (speed error + speed × course
    error in rad); UBX NAV-PVT: gSpeed and velN/velE in mm/s, headMot 1e-5°. Through gpsd, its
    JSON rounds again: speed and velocities to 0.001 m/s, track to 0.0001°."""
    if fmt == "nmea":
        ds, dt = 0.0005 * KNOT, 0.005
        dv = ds + speed * math.radians(dt)
    else:
        ds, dt, dv = 0.0005, 0.5e-5, 0.0005
    if source == "gpsd":
        ds, dt, dv = ds + 0.0005, dt + 0.00005, dv + 0.0005 + speed * math.radians(0.00005)
    return ds, dt, dv


def _check_gnss(obj: dict[str, Any], fixes: np.ndarray, fmt: str, source: str) -> int | None:
    """The index of the fix `obj` is, its every field checked against the fix (None: a report
    without speed, which gpsd may send before an epoch's RMC: nothing to match it by)."""
    if obj["speed"] is None and source == "gpsd":
        assert obj["track_deg"] is None and obj["vel_enu"] is None and obj["fix"] in ("2d", "3d"), obj
        return None
    k = int(np.argmin(np.abs(fixes["speed"] - obj["speed"]) + np.abs(fixes["track"] - obj["track_deg"])))
    f = fixes[k]
    ds, dtrk, dv = _tolerances(fmt, float(f["speed"]), source)
    # gpsd reports an NMEA epoch after each sentence until it has learnt the receiver's cycle: its
    # first report of an epoch (RMC: the velocity) may say 2-D before the GGA's altitude came
    fix_ok = ("2d", "3d") if (source, fmt) == ("gpsd", "nmea") else (FIX_NAMES[int(f["fix_type"])],)
    assert obj["fix"] in fix_ok and obj["valid"] is True and obj["source"] == source
    assert abs(obj["speed"] - f["speed"]) <= ds and abs(obj["track_deg"] - f["track"]) <= dtrk, (obj, f)
    if fmt == "nmea":  # NMEA: the velocity from speed and course, no vertical
        tr = math.radians(float(f["track"]))
        want = [float(f["speed"]) * math.sin(tr), float(f["speed"]) * math.cos(tr), None]
    else:
        want = [float(f["ve"]), float(f["vn"]), -float(f["vd"])]
    if source == "gpsd":
        want[2] = None  # gpsd 3.22 gives no NED velocity here: the vertical is not passed on
    for got, w in zip(obj["vel_enu"], want):
        assert (got is None and w is None) or abs(got - w) <= dv + 1e-9, (obj, f)
    if obj["sats"] is not None or source == "serial":
        assert obj["sats"] == int(f["nsat"])
    if obj["pdop"] is not None or source == "serial":
        assert abs(obj["pdop"] - f["pdop"]) <= 0.005  # written with 2 decimals
    assert obj["age_s"] >= -DT  # valid at most one sample period after the line (the step's end)
    return k


class Stdout:
    """attitude-rx's stdout read by a thread, line by line (the pipe never fills)."""

    def __init__(self, proc: subprocess.Popen) -> None:
        self.lines: list[dict[str, Any]] = []
        self._t = threading.Thread(target=self._run, args=(proc,), daemon=True)
        self._t.start()

    def _run(self, proc: subprocess.Popen) -> None:
        assert proc.stdout is not None
        for raw in proc.stdout:
            self.lines.append(json.loads(raw))

    def join(self) -> list[dict[str, Any]]:
        self._t.join(timeout=60)
        assert not self._t.is_alive()
        return self.lines


def _stderr_until(proc: subprocess.Popen, marker: bytes, timeout: float = 30) -> bytes:
    """stderr up to the line holding `marker` (attitude-rx's start-up lines)."""
    assert proc.stderr is not None
    text = b""
    end = time.monotonic() + timeout
    while marker not in text or not text.endswith(b"\n"):
        r, _, _ = select.select([proc.stderr], [], [], max(end - time.monotonic(), 0))
        assert r, f"attitude-rx did not start: {text!r}"
        chunk = os.read(proc.stderr.fileno(), 4096)
        assert chunk, f"attitude-rx ended: {text!r}"
        text += chunk
    return text


def _stats(err: str) -> dict[str, str]:
    line = next(x for x in err.splitlines() if x.startswith("attitude-rx: gnss: source="))
    return dict(kv.split("=") for kv in line.split(":", 2)[2].split())


def _run_rx(cmd: list[str], gnss_args: list[str], records: Iterator[bytes], count: int,
            marker: bytes) -> tuple[list[dict[str, Any]], str]:
    """attitude-rx --format jsonl --count with the board on link v2 (a pty pair) sending
    `records`; its JSON records and stderr."""
    import serial

    from attitude_c.link.transport import PtyPair
    from attitude_c.link.transport2 import run_sender2

    with PtyPair() as (rx_port, board_port):
        proc = subprocess.Popen([*cmd, "--port", rx_port, "--format", "jsonl", "--count", str(count),
                                 "--queue", "4096", *gnss_args], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        try:
            head = _stderr_until(proc, marker)
            out = Stdout(proc)
            ended = threading.Event()
            threading.Thread(target=lambda: (proc.wait(), ended.set()), daemon=True).start()  # type: ignore[func-returns-value]
            with serial.Serial(board_port, 115200, timeout=0.01, write_timeout=10) as port:
                run_sender2(port, records, impl="python", timeout=120, stop=ended)
            _, err = proc.communicate(timeout=60)
        finally:
            if proc.poll() is None:
                proc.send_signal(signal.SIGKILL)
                proc.wait()
    text = head.decode() + err.decode()
    assert proc.returncode == 0, text
    return out.join(), text


def _board(n: int) -> list[bytes]:
    """A level aided board at rest facing 30°, n samples (test_attitude_rx_aided's)."""
    return _records(*_static_board(n, 30.0))


def _check_lines(lines: list[dict[str, Any]], fixes: np.ndarray, fmt: str, source: str) -> list[int]:
    """The gnss objects: each a fix of the log, in the log's order; the filter aided after the first."""
    att = [x for x in lines if "q" in x]
    matched = [(i, _check_gnss(x["gnss"], fixes, fmt, source)) for i, x in enumerate(att) if "gnss" in x]
    got = [(i, k) for i, k in matched if k is not None]
    assert got, "no GNSS fix reached the attitude lines"
    ks = [k for _, k in got]
    assert ks == sorted(set(ks)), ks  # each fix once, in time order
    assert any("gnss_aided" in x["flags"] for x in att[got[0][0]:])
    assert not any("gnss_aided" in x["flags"] for x in att[:got[0][0]])  # no velocity before the first
    return ks


@pytest.mark.parametrize("fmt", ["nmea", "ubx"])
def test_rx_gnss_serial_end_to_end(rx_host, fixes, fmt) -> None:
    """--gnss PTY: epoch k written to the receiver's pty just before board samples
    20k .. 20k + 19; every fix reaches the filter (used), the lines carry them in order,
    each equal to the log's fix, and the parser's counters account for every byte."""
    master, slave = os.openpty()
    tty.setraw(slave)
    path = os.ttyname(slave)
    board = _board(N_FIXES * GNSS_EVERY)
    n_head = 2  # BOOT, CHANNELS

    def records() -> Iterator[bytes]:
        yield from board[:n_head]
        for n in range(N_FIXES * GNSS_EVERY):
            if n % GNSS_EVERY == 0:
                os.write(master, _epoch(fixes[n // GNSS_EVERY], fmt))
            yield from board[n_head + 3 * n:n_head + 3 * n + 3]

    try:
        lines, err = _run_rx(rx_host, ["--gnss", f"{path}:115200"], records(), N_FIXES * GNSS_EVERY,
                             b"gnss: ")
    finally:
        os.close(master)
        os.close(slave)
    _check_lines(lines, fixes, fmt, "serial")
    st = _stats(err)
    size = len(b"".join(_epoch(f, fmt) for f in fixes))
    # every epoch written before the last samples: read, parsed and counted at the stop at the latest
    assert (st["fixes"], st["bytes"], st["bad_checksum"], st["dropped"]) == (str(N_FIXES), str(size), "0", "0")
    assert st["nmea" if fmt == "nmea" else "ubx"] == str(4 * N_FIXES if fmt == "nmea" else N_FIXES)
    assert int(st["used"]) >= 1 and int(st["used"]) + int(st["rejected"]) + int(st["late"]) <= N_FIXES


def test_rx_gnss_integrator_reports_only(rx_host, fixes) -> None:
    """--estimator integrator: the fixes are printed, never given to a filter (used=0)."""
    master, slave = os.openpty()
    tty.setraw(slave)
    board = _board(8 * GNSS_EVERY)

    def records() -> Iterator[bytes]:
        yield from board[:2]
        for n in range(8 * GNSS_EVERY):
            if n % GNSS_EVERY == 0:
                os.write(master, _epoch(fixes[n // GNSS_EVERY], "ubx"))
            yield from board[2 + 3 * n:2 + 3 * n + 3]

    try:
        lines, err = _run_rx(rx_host, ["--gnss", os.ttyname(slave), "--estimator", "integrator",
                                       "--method", "rv1"], records(), 8 * GNSS_EVERY, b"gnss: ")
    finally:
        os.close(master)
        os.close(slave)
    objs = [x["gnss"] for x in lines if "gnss" in x]
    assert objs and all(_check_gnss(o, fixes, "ubx", "serial") is not None for o in objs)
    assert _stats(err)["used"] == "0" and _stats(err)["fixes"] == "8"


# ---- gpsd: gpsd and gpsfake replaying the simulator's logs ----

def _reserved_port() -> socket.socket:
    """A TCP port for gpsfake's gpsd, held bound (SO_REUSEADDR, not listening) so no other
    test's bind to port 0 gets it; gpsd (SO_REUSEADDR too) can still bind and listen on it."""
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    s.bind(("127.0.0.1", 0))
    return s


def _wait_listening(port: int, proc: subprocess.Popen, timeout: float = 30) -> None:
    """Until something accepts connections on the port (gpsfake's gpsd is up): connect attempts
    until one succeeds, each a condition check, bounded."""
    end = time.monotonic() + timeout
    while True:
        assert proc.poll() is None, f"gpsfake ended (exit {proc.returncode})"
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return
        except OSError:
            assert time.monotonic() < end, f"gpsd did not listen on {port} within {timeout} s"
            time.sleep(0.05)  # a poll of the condition, not a guess at its time


def _group_members(pgid: int) -> list[int]:
    """The processes of process group `pgid` (gpsfake's: it and the gpsd it started)."""
    out = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                if os.getpgid(int(d)) == pgid:
                    out.append(int(d))
            except ProcessLookupError:
                pass
    return out


def _stop_gpsfake(proc: subprocess.Popen, port: int) -> None:
    """End gpsfake and its gpsd: SIGTERM to the group (gpsd exits; gpsfake's handler would only
    stop its gpsd and keep looping), wait for gpsd's end on its pidfd, then SIGKILL gpsfake; remove
    the shared-memory segment gpsd exported under the key gpsfake derives from the port."""
    fds = [os.pidfd_open(p) for p in _group_members(proc.pid) if p != proc.pid]
    os.killpg(proc.pid, signal.SIGTERM)
    for fd in fds:
        assert select.select([fd], [], [], 30)[0], "gpsd did not end on SIGTERM within 30 s"
        os.close(fd)
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)
    subprocess.run(["ipcrm", "-M", f"0x4770{port:04X}"], capture_output=True, check=False)


@pytest.fixture
def gpsfake_log(tmp_path: Path, fixes) -> Iterator[Any]:
    """Start gpsfake on a log of the fixes: yields start(fmt) -> port."""
    require_tools("gpsfake", "gpsd", "ipcrm", apt="gpsd gpsd-clients util-linux")
    running: list[tuple[subprocess.Popen, socket.socket, int]] = []

    def start(fmt: str) -> int:
        from attitude_c.sim.gnss_log import write_gnss_log

        log = write_gnss_log(tmp_path / f"fixes.{fmt}", fixes)
        s = _reserved_port()
        port = s.getsockname()[1]
        # -1: the log once; -c: seconds between sentences (an epoch every 0.2 s, the receiver's
        # 5 Hz); -q quiet; TMPDIR: gpsfake's control socket in this test's directory; a session of
        # its own, so that gpsfake and its gpsd are one process group
        cycle = 0.05 if fmt == "nmea" else 0.2
        proc = subprocess.Popen(["gpsfake", "-1", "-q", "-c", str(cycle), "-P", str(port), str(log)],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                env={**os.environ, "TMPDIR": str(tmp_path)}, start_new_session=True)
        running.append((proc, s, port))
        _wait_listening(port, proc)
        return port

    yield start
    for proc, s, port in running:
        s.close()
        _stop_gpsfake(proc, port)


def _needs_gpsd(cmd: list[str]) -> None:
    out = subprocess.run([*cmd, "--version"], capture_output=True, text=True, check=True).stdout
    if "gpsd support: yes" not in out:
        from conftest import _missing

        _missing(f"attitude-rx was built without gpsd support ({out.strip()}): apt-get install libgps-dev")


@pytest.mark.parametrize("fmt", ["nmea", "ubx"])
def test_rx_gnss_gpsd_gpsfake(rx_host, fixes, gpsfake_log, fmt) -> None:
    """--gnss gpsd:127.0.0.1:PORT with gpsfake replaying the log at the receiver's 5 Hz while the
    board streams in real time (100 samples/s): the fixes gpsd reports reach the lines, each equal
    to the log's, in order, and the filter is aided."""
    _needs_gpsd(rx_host)
    port = gpsfake_log(fmt)
    n = (N_FIXES + 10) * GNSS_EVERY  # the board outlasts the replay
    board = _board(n)

    def records() -> Iterator[bytes]:  # a board in real time: sample n not before n × DT
        yield from board[:2]
        t0 = time.monotonic()
        for k in range(n):
            delay = t0 + k * DT - time.monotonic()
            if delay > 0:
                time.sleep(delay)  # the board's sample clock, not a wait for a condition
            yield from board[2 + 3 * k:2 + 3 * k + 3]

    lines, err = _run_rx(rx_host, ["--gnss", f"gpsd:127.0.0.1:{port}"], records(), n, b"gnss: gpsd")
    _check_lines(lines, fixes, fmt, "gpsd")
    assert int(_stats(err)["fixes"]) >= 1


# ---- errors: one line, the documented exit code ----

@pytest.mark.parametrize(("arg", "code", "text"), [
    ("bogus", 78, "gnss: 'bogus' must be gpsd[:HOST[:PORT]] or a serial device /dev/...[:BAUD]"),
    ("/dev/ttyS0:1234", 78, "gnss: baud '1234' is not a supported rate"),
    ("gpsd:", 78, "gnss: 'gpsd:' must be gpsd, gpsd:HOST or gpsd:HOST:PORT"),
    ("gpsd:localhost:0", 78, "gnss: gpsd port '0' must be 1..65535"),
    ("/dev/no-such-gnss", 66, "gnss: cannot open port /dev/no-such-gnss: No such file or directory"),
])
def test_rx_gnss_argument_errors(rx_host, arg, code, text) -> None:
    master, slave = os.openpty()
    try:
        p = subprocess.run([*rx_host, "--port", os.ttyname(slave), "--gnss", arg], check=False,
                           capture_output=True,
                           text=True, timeout=30)
    finally:
        os.close(master)
        os.close(slave)
    assert p.returncode == code and p.stdout == ""
    assert p.stderr.startswith(f"attitude-rx: {text}") and p.stderr.count("\n") == 1, p.stderr


def test_rx_gnss_gpsd_unreachable(rx_host) -> None:
    """No gpsd on the port: exit 69 with one line (or, built without libgps, the line saying so)."""
    s = _reserved_port()  # bound, not listening: connections to it are refused
    master, slave = os.openpty()
    try:
        p = subprocess.run([*rx_host, "--port", os.ttyname(slave), "--gnss",
                            f"gpsd:127.0.0.1:{s.getsockname()[1]}"], check=False, capture_output=True, text=True,
                           timeout=30)
    finally:
        s.close()
        os.close(master)
        os.close(slave)
    assert p.returncode == 69 and p.stderr.count("\n") == 1, p.stderr
    assert ("is unreachable" in p.stderr) or ("built without gpsd support" in p.stderr)
