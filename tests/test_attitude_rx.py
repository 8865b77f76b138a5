"""attitude-rx: the receiver app built for armv4t, run under qemu-arm on a
pseudo-terminal fed by the Python link sender (attitude_c.link.Sender)
with simulated gyro data; its attitude is compared with the host
integrator (attitude_c.integrate). Everything has timeouts."""

from __future__ import annotations

import math
import os
import select
import signal
import subprocess
import time
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest
from conftest import require_target, require_tools

pytestmark = pytest.mark.system  # builds and runs attitude-rx against pty links

SCALE = (90.0 * math.pi / 180.0) / 2048.0  # the app's default rad/s per code
PERIOD = 0.01


@pytest.fixture(autouse=True)
def _no_leftover_processes():
    """Whatever a test does (fail, skip), no attitude-rx it started survives it."""
    Rx.live.clear()
    yield
    for rx in Rx.live:
        if rx.proc.poll() is None:
            rx.proc.kill()
            rx.proc.wait()


@pytest.fixture(scope="module")
def rx_builds(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[str]]:
    """{"armv4t": [qemu-arm, exe], "host": [exe]} from invoke cross-build."""
    from toolchain.tasks.cross import cross_build_target

    out: dict[str, list[str]] = {}
    base = tmp_path_factory.mktemp("rx")
    t = require_target("armv4t")
    out["armv4t"] = [*t.run_cmd, str(cross_build_target("armv4t", out=base / "armv4t")["app"])]
    require_target("host")
    out["host"] = [str(cross_build_target("host", out=base / "host")["app"])]
    return out


def _tick() -> int:
    return int(time.monotonic() * 1000) & 0xFFFF


class Feeder:
    """The Python link sender A on the master side of a pty, in real time.

    ``channel`` (attitude_c.link.Channel) corrupts bytes in both directions.
    Counts what B put on the wire (before the channel): 0xBB, 0x00, 0xFF.
    """

    def __init__(self, master: int, channel=None, block_size: int = 6, timeout_ms: int = 2000,
                 impl: str = "python", max_attempts: int = 5) -> None:
        from attitude_c.link import make_sender

        self.master = master
        self.channel = channel
        # qemu-arm answers within a few ms; the default 2 s leaves room for a loaded CI
        # machine (a timeout here would make A resend a block B already accepted)
        self.sender = make_sender(impl, block_size=block_size, syn_timeout=timeout_ms,
                                  answer_timeout=timeout_ms, max_attempts=max_attempts)
        self.t0 = time.monotonic()
        self.b_bytes = {0xBB: 0, 0x00: 0, 0xFF: 0}
        self.other = 0

    def _bit_tick(self) -> int:
        return int((time.monotonic() - self.t0) * 9600)

    def _out(self, burst: list[int]) -> None:
        """Write what A handed out in one go (no artificial gaps between bytes)."""
        data = b"".join(self.channel.transmit(0, b, self._bit_tick()) for b in burst) \
            if self.channel else bytes(burst)
        if data:
            os.write(self.master, data)

    def _in(self, wait_ms: int) -> None:
        r, _, _ = select.select([self.master], [], [], wait_ms / 1000)
        if not r:
            return
        for b in os.read(self.master, 64):
            if b in self.b_bytes:
                self.b_bytes[b] += 1
            else:
                self.other += 1
            data = self.channel.transmit(1, b, self._bit_tick()) if self.channel else bytes([b])
            for d in data:
                self.sender.sink(d, _tick())

    def send(self, block: bytes, deadline: float = 10.0) -> bool:
        """Send one block (with the sender's retries) until the sender is idle again:
        True if B accepted it (A got 0x00), False if A gave up."""
        from attitude_c.link import Result

        end = time.monotonic() + deadline
        accepted = self.sender.stats.blocks_accepted
        self.sender.start(block, _tick())
        burst: list[int] = []
        while time.monotonic() < end:
            res, byte = self.sender.poll(_tick())
            if res == Result.SEND:
                burst.append(byte)
                continue
            if burst:
                self._out(burst)
                burst = []
            if res == Result.IDLE:
                return self.sender.stats.blocks_accepted > accepted
            elif res == Result.NONE:
                left = self.sender.ticks_left(_tick())
                self._in(min(left if left is not None else 20, 20))
        raise AssertionError(f"sender stuck: block not finished within {deadline} s")

    def drain(self, ms: int = 100) -> None:
        end = time.monotonic() + ms / 1000
        while time.monotonic() < end:
            self._in(10)


def _readline(stream, timeout: float = 20.0) -> str:
    """One line from a child's pipe, or fail after ``timeout`` s (never hang)."""
    r, _, _ = select.select([stream], [], [], timeout)
    assert r, f"no output within {timeout} s"
    return stream.readline().decode()


def _block(codes) -> bytes:
    return b"".join(int(c).to_bytes(2, "big") for c in codes)


class Rx:
    """attitude-rx on a fresh pty pair (killed by the autouse fixture if a test ends early)."""

    live: ClassVar[list[Rx]] = []

    def __init__(self, cmd: list[str], *args: str) -> None:
        self.master, self.slave = os.openpty()
        self.port = os.ttyname(self.slave)
        self.proc = subprocess.Popen([*cmd, "--port", self.port, *args], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE)
        Rx.live.append(self)
        assert self.proc.stderr is not None
        # the line with 8N1 is printed once the port is configured (raw, no echo); warnings
        # about the configuration may come before it
        # about the configuration may come before it (read unbuffered: the rest is for finish())
        banner = b""
        while b"8N1" not in banner or not banner.endswith(b"\n"):
            r, _, _ = select.select([self.proc.stderr], [], [], 20)
            assert r, f"attitude-rx did not start: {banner!r}"
            chunk = os.read(self.proc.stderr.fileno(), 4096)
            assert chunk, f"attitude-rx ended: {banner!r}"
            banner += chunk
        self.banner = banner.decode()

    def finish(self, sig: int | None = signal.SIGINT, timeout: float = 20) -> tuple[int, str, str]:
        if sig is not None and self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            out, err = self.proc.communicate(timeout=timeout)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()
            os.close(self.master)
            os.close(self.slave)
        return self.proc.returncode, out.decode(), self.banner + err.decode()


def _stats(err: str) -> dict[str, int]:
    out: dict[str, int] = {}
    for line in err.splitlines():
        if line.startswith(("attitude-rx: link:", "attitude-rx: samples:", "attitude-rx: reports:")):
            for kv in line.split(":", 2)[2].split():
                if "=" in kv:  # key=value pairs only
                    k, v = kv.split("=")
                    out[k] = int(v)
    return out


def _gyro_codes(n: int, seed: int = 3) -> np.ndarray:
    """Simulated gyro: smooth ~0.5 rad/s motion on three axes, as 12-bit codes."""
    t = np.arange(n) * PERIOD
    w = np.column_stack([0.6 * np.sin(2.1 * t), 0.4 * np.cos(1.3 * t + 0.5), 0.3 + 0.2 * np.sin(0.7 * t)])
    rng = np.random.default_rng(seed)
    return np.clip(np.round(2048 + w / SCALE + rng.normal(0, 2, size=w.shape)), 0, 4095).astype(int)


@pytest.mark.qemu
def test_rx_armv4t_matches_host_integrator(rx_builds) -> None:
    """Codes -> increments -> rv3 on the emulated ARMv4T equals attitude_c.integrate on the host;
    the sample period is the one the stream's BOOT report announces (36 ticks = 0.01 s)."""
    import attitude_c
    from attitude_c.link import block

    n = 60
    codes = _gyro_codes(n)
    rx = Rx(rx_builds["armv4t"], "--method", "rv3", "--count", str(n // 3), "--gap-ms", "2000")
    feeder = Feeder(rx.master)
    feeder.send(block.encode_boot(round(PERIOD * 3600), 9600))
    for c in codes:
        feeder.send(_block(c))
    rc, out, err = rx.finish(sig=None)
    assert rc == 0, err
    lines = out.strip().splitlines()
    assert lines[0].startswith("t,n,code_x,code_y,code_z,q0,q1,q2,q3,yaw_deg")
    rows = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    assert rows.shape == (n // 3, 13)
    # each line carries the raw codes of the newest sample of its update
    np.testing.assert_array_equal(rows[:, 2:5], codes[2::3])
    np.testing.assert_allclose(rows[:, 0], np.arange(1, n // 3 + 1) * 3 * PERIOD, rtol=1e-12)
    dtheta = (codes - 2048.0) * SCALE * PERIOD
    q_ref = attitude_c.integrate(dtheta, method="rv3")
    # same f64 algorithm; the ARM build uses soft-float glibc libm (sin/cos within
    # 1 ulp of the host's), printed with 17 digits: 20 updates stay far below 1e-12
    np.testing.assert_allclose(rows[:, 5:9], q_ref, atol=1e-12)
    e_ref = np.degrees(attitude_c.quat_to_euler(q_ref))
    np.testing.assert_allclose(rows[:, 9:12], e_ref, atol=1e-9)
    st = _stats(err)
    assert st["blocks_accepted"] == n + 1 and st["received"] == n and st["updates"] == n // 3
    assert st["naks"] == 0 and st["boot"] == 1 and st["held"] == 0
    assert feeder.sender.stats.blocks_accepted == n + 1
    assert "period 36 ticks = 0.01 s" in err


@pytest.mark.qemu
def test_rx_jsonl_axes_and_calibration(rx_builds, tmp_path: Path) -> None:
    """--format jsonl, a config file for calibration and axes, rv3-reuse (one line per sample)."""
    import json

    import attitude_c

    n = 12
    codes = _gyro_codes(n, seed=5)
    zero, scale = (2040.0, 2050.0, 2047.5), (7e-4, 8e-4, 7.5e-4)
    cfg = tmp_path / "rx.conf"
    cfg.write_text("# mini2440 gyro calibration\nperiod = 0.02\n"
                   f"gyro-zero = {','.join(map(str, zero))}\n"
                   f"gyro-scale = {','.join(map(str, scale))}\naxes = -y, x, z\nmethod = rv1\n")
    rx = Rx(rx_builds["armv4t"], "--config", str(cfg), "--method", "rv3-reuse", "--format", "jsonl",
            "--count", str(n), "--gap-ms", "2000")  # the command line overrides the file's method
    feeder = Feeder(rx.master)
    for c in codes:
        feeder.send(_block(c))
    rc, out, err = rx.finish(sig=None)
    assert rc == 0, err
    lines = [json.loads(ln) for ln in out.strip().splitlines()]
    recs = [r for r in lines if "q" in r]
    links = [r["link"] for r in lines if "link" in r]
    assert len(recs) == n and "rv3-reuse" in err
    assert [r["codes"] for r in recs] == codes.tolist()
    rates = (codes - np.array(zero)) * np.array(scale)
    body = np.column_stack([-rates[:, 1], rates[:, 0], rates[:, 2]])
    # each line carries the body rate it integrated (what attitude view's rate charts draw)
    np.testing.assert_allclose([r["rate_dps"] for r in recs], np.degrees(body), rtol=1e-15, atol=1e-12)
    # the link's counters as JSON: the last record is the final count, the same as stderr's statistics
    st = _stats(err)
    assert links and lines[-1] == {"t": lines[-1]["t"], "link": links[-1]}
    assert links[-1]["blocks"] == st["blocks_accepted"] == n
    assert links[-1]["naks"] == st["naks"] and links[-1]["timeouts"] == st["timeouts"]
    q_ref = attitude_c.integrate(body * 0.02, method="rv3-reuse")
    np.testing.assert_allclose([r["q"] for r in recs], q_ref, atol=1e-12)  # as above
    np.testing.assert_allclose([r["heading_deg"] for r in recs],
                               np.degrees(attitude_c.heading(q_ref)), atol=1e-9)
    assert recs[-1]["t"] == pytest.approx(n * 0.02)


@pytest.mark.qemu
def test_rx_lossy_channel_keeps_running_and_counts_match(rx_builds) -> None:
    """Bit errors, drops and garbage both ways: the app keeps running, its link
    statistics equal what was seen on the wire, every output comes from a sent block."""
    from attitude_c.link import Channel, ChannelConfig

    # gap and answer timeouts short enough to keep the run short, long enough for a loaded machine
    rx = Rx(rx_builds["armv4t"], "--method", "rv1", "--no-header", "--gap-ms", "300")
    chan = Channel(ChannelConfig(ber=2e-3, drop=0.01, insert=0.01, duplicate=0.005, seed=11))
    feeder = Feeder(rx.master, channel=chan, timeout_ms=600)
    n = 100
    sent = [(1024 + i, 2048 + (i * 7) % 100, 3000 - i) for i in range(n)]  # unique per block
    for c in sent:
        feeder.send(_block(c))
    feeder.channel = None  # then a clean line: it must still be working
    for i in range(5):
        feeder.send(_block((100 + i, 200, 300)))
    feeder.drain(300)
    rc, out, err = rx.finish(signal.SIGTERM)
    assert rc == 0, err
    assert "stopped by signal 15" in err
    st = _stats(err)
    a = feeder.sender.stats
    seen = f"app: {st}; on the wire from B: {feeder.b_bytes}, other {feeder.other}; A: {a}"
    # B's counters = what B put on the wire (seen before the channel)
    assert st["syns"] == feeder.b_bytes[0xBB], seen
    assert st["blocks_accepted"] == feeder.b_bytes[0x00], seen
    assert st["naks"] == feeder.b_bytes[0xFF], seen
    assert feeder.other == 0, seen
    # A saw at most what B answered (answers get lost or corrupted on the way back)
    assert a.blocks_accepted <= st["blocks_accepted"]
    assert a.naks <= st["naks"] + feeder.b_bytes[0x00] + feeder.b_bytes[0xBB] + chan.stats()["b_to_a"]["inserted"]
    assert st["received"] == st["blocks_accepted"] == st["updates"] == st["integrated"]
    codes = [tuple(int(v) for v in ln.split(",")[2:5]) for ln in out.strip().splitlines()]
    assert len(codes) == st["updates"]
    assert codes[-5:] == [(100 + i, 200, 300) for i in range(5)]
    sent_set = set(sent)
    foreign = [c for c in codes[:-5] if c not in sent_set]
    # an 8-bit sum misses some multi-bit errors (docs/link.md): allow a few, and say how many
    print(f"lossy: A accepted {a.blocks_accepted}, B accepted {st['blocks_accepted']}, "
          f"naks {st['naks']}, timeouts {st['timeouts']}, undetected corrupt {len(foreign)}")
    assert len(foreign) <= 2
    assert chan.stats()["a_to_b"]["corrupted"] > 0  # the channel really was lossy
    assert st["naks"] > 0


def _rows(out: str) -> list[tuple[int, int, int]]:
    """The codes of each CSV output line."""
    return [tuple(int(v) for v in ln.split(",")[2:5]) for ln in out.strip().splitlines()]


def _unique_codes(n: int) -> list[tuple[int, int, int]]:
    """n sample codes, each block different (so the output says which block it came from)."""
    return [(1000 + i % 2000, 2048 + i % 7, 3000 - i % 2000) for i in range(n)]


def _send_while_alive(feeder: Feeder, rx: Rx, codes) -> list[tuple[int, int, int]]:
    """Send the blocks in order while attitude-rx runs; the codes of those A saw accepted."""
    acked = []
    for c in codes:
        if rx.proc.poll() is not None:
            break
        if feeder.send(_block(c)):
            acked.append(tuple(c))
    return acked


def _delivered(st: dict[str, int], feeder: Feeder, acked: list, rows: list) -> str:
    """Acknowledged == integrated == printed, sample by sample (returns a summary for the log)."""
    seen = f"app {st}; B on the wire {feeder.b_bytes}; A {feeder.sender.stats}"
    assert feeder.b_bytes[0x00] == len(acked) == st["blocks_accepted"], seen  # every 0x00 reached A
    assert st["received"] == st["integrated"] == len(acked), seen
    assert rows == acked, seen  # each acknowledged sample printed once, in order, nothing else
    assert st.get("queue_overflows", 0) == 0 and st["held"] == 0, seen
    return (f"acknowledged {feeder.b_bytes[0x00]}, integrated {st['integrated']}, printed {len(rows)}, "
            f"A gave up {feeder.sender.stats.gave_up}, busy NAKs {st.get('busy_naks')}")


def test_rx_slow_consumer_backpressure_acknowledged_is_printed(rx_builds) -> None:
    """A slow attitude thread (--consumer-delay) and a small queue, fed by the C sender at
    the line's pace: a block is acknowledged only once its sample is in the queue (the
    answer is held, then 0xFF), so every acknowledged sample is integrated and printed."""
    rx = Rx(rx_builds["host"], "--method", "rv1", "--no-header", "--queue", "4",
            "--consumer-delay", "0.03", "--gap-ms", "2000")
    feeder = Feeder(rx.master, impl="c", timeout_ms=300)
    acked = _send_while_alive(feeder, rx, _unique_codes(80))
    feeder.drain(100)
    rc, out, err = rx.finish(signal.SIGINT)
    assert rc == 0, err
    st = _stats(err)
    print("consumer-delay:", _delivered(st, feeder, acked, _rows(out)))
    assert st["busy_naks"] > 0 and st["queue_high_water"] == 4  # the queue really was full


def test_rx_count_acknowledges_only_what_it_prints(rx_builds) -> None:
    """--count 100 with a slow consumer: 100 samples acknowledged, integrated, printed (issue 17:
    main acknowledged 204 of which 100 were printed)."""
    rx = Rx(rx_builds["host"], "--method", "rv1", "--no-header", "--count", "100",
            "--consumer-delay", "0.02", "--gap-ms", "2000")
    feeder = Feeder(rx.master, impl="c", timeout_ms=300)
    acked = _send_while_alive(feeder, rx, _unique_codes(400))
    rc, out, err = rx.finish(sig=None)
    assert rc == 0, err
    st = _stats(err)
    print("count:", _delivered(st, feeder, acked, _rows(out)))
    assert len(acked) == 100


def _wire_block(block: bytes) -> bytes:
    """What A sends for one block after 0xBB: the data and its checksum (the C sender's)."""
    from attitude_c.link import Result, make_sender

    a = make_sender("c", block_size=len(block))
    a.start(block, 0)
    assert a.poll(0) == (Result.SEND, 0xAA)
    a.sink(0xBB, 0)
    out = bytearray()
    while (r := a.poll(0))[0] == Result.SEND:
        out.append(r[1])
    return bytes(out)


def test_rx_stop_keeps_its_last_answers_on_the_line(rx_builds) -> None:
    """--count 1 and a sender that reads nothing until attitude-rx has ended (a slow reader,
    as on a loaded machine): every answer it wrote is still there, the 0x00 of the block it
    printed last. On main it closed the port with TCOFLUSH, which drops what the other end
    has not taken in yet: A timed out on a block B had delivered (issue 27). The NAKed
    blocks before it fill the pty's 4 KB line buffer, so the last answers wait in the
    kernel's buffer, where a flush finds them whatever the machine's load."""
    rx = Rx(rx_builds["host"], "--method", "rv1", "--no-header", "--count", "1", "--gap-ms", "2000")
    codes = _unique_codes(1)
    good = _wire_block(_block(codes[0]))
    bad = good[:-1] + bytes([good[-1] ^ 0x01])  # a wrong checksum: B answers 0xFF
    naks = 2100  # 2 answer bytes each (0xBB, 0xFF): more than the 4096 bytes of the line buffer
    os.write(rx.master, (b"\xaa" + bad) * naks + b"\xaa" + good)
    rx.proc.wait(timeout=60)  # it ends by itself (--count 1)
    want = b"\xbb\xff" * naks + b"\xbb\x00"
    got = _read_upto(rx.master, len(want))
    rc, out, err = rx.finish(sig=None)
    assert rc == 0 and _rows(out) == codes, err
    assert got == want, f"{len(got)} of {len(want)} answer bytes, ending {got[-4:].hex()}"


def _read_upto(fd: int, n: int, quiet: float = 20.0) -> bytes:
    """n bytes from fd, or fewer if none comes for `quiet` s (never hang)."""
    got = bytearray()
    while len(got) < n and select.select([fd], [], [], quiet)[0]:
        got += os.read(fd, n - len(got))
    return bytes(got)


@pytest.mark.parametrize(("method", "count", "samples", "every", "first"),
                         [("rv3", 20, 60, 3, 2),   # an update per 3 samples
                          ("rk4", 20, 41, 2, 2)])  # start sample, then (midpoint, end) pairs
def test_rx_count_multi_sample_methods_acknowledge_whole_updates(rx_builds, method: str, count: int,
                                                                  samples: int, every: int, first: int) -> None:
    """--count with methods that need several samples per update: exactly the samples of the
    N updates are acknowledged (att_integ_outputs), integrated, and end in a printed line."""
    rx = Rx(rx_builds["host"], "--method", method, "--no-header", "--count", str(count),
            "--consumer-delay", "0.01", "--gap-ms", "2000")
    feeder = Feeder(rx.master, impl="c", timeout_ms=300)
    acked = _send_while_alive(feeder, rx, _unique_codes(samples + 60))
    rc, out, err = rx.finish(sig=None)
    assert rc == 0, err
    st = _stats(err)
    assert feeder.b_bytes[0x00] == len(acked) == st["integrated"] == samples, st
    assert st["pending"] == 0 and st["updates"] == count, st
    assert _rows(out) == acked[first::every]  # each line carries the codes of its newest sample


class SlowReader:
    """Reads a child's stdout pipe (shrunk to one page) slowly until told to hurry."""

    def __init__(self, proc: subprocess.Popen, chunk: int, every: float) -> None:
        import fcntl
        import threading

        assert proc.stdout is not None
        self.fd = proc.stdout.fileno()
        fcntl.fcntl(self.fd, fcntl.F_SETPIPE_SZ, 4096)  # ~20 CSV lines
        self.chunk, self.every = chunk, every
        self.hurry = threading.Event()
        self.data = bytearray()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while True:
            if not self.hurry.is_set():
                self.hurry.wait(self.every)
            r, _, _ = select.select([self.fd], [], [], 30)
            b = os.read(self.fd, self.chunk if not self.hurry.is_set() else 65536) if r else b""
            if not b:
                return
            self.data += b

    def finish(self) -> str:
        self.hurry.set()
        self.thread.join(30)
        return self.data.decode()


def test_rx_slow_stdout_backpressure_acknowledged_is_printed(rx_builds) -> None:
    """stdout read slowly (a one-page pipe, 512 bytes every 0.1 s: ~27 lines/s against ~100
    blocks/s on the pty): the printing thread blocks, the queue fills, answers are held;
    every acknowledged sample is printed (issue 17: main printed 350 of 2,000 acknowledged)."""
    rx = Rx(rx_builds["host"], "--method", "rv1", "--no-header", "--queue", "4", "--gap-ms", "2000")
    reader = SlowReader(rx.proc, 512, 0.1)
    feeder = Feeder(rx.master, impl="c", timeout_ms=300)
    acked = _send_while_alive(feeder, rx, _unique_codes(80))
    feeder.drain(100)
    rx.proc.send_signal(signal.SIGINT)
    out = reader.finish()
    rc, _, err = rx.finish(sig=None)
    assert rc == 0, err
    st = _stats(err)
    print("slow stdout:", _delivered(st, feeder, acked, _rows(out)))
    assert st["busy_naks"] > 0


def _wait_exit(proc: subprocess.Popen, sig: int) -> tuple[float, int]:
    """Send sig; seconds until the process ended (killed after 10 s), its exit code."""
    t0 = time.monotonic()
    proc.send_signal(sig)
    try:
        rc = proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        raise AssertionError(f"signal {sig} did not stop attitude-rx within 10 s") from None
    return time.monotonic() - t0, rc


#: attitude-rx ends within 1 s of SIGINT/SIGTERM (docs/attitude-rx.md); the rest is the test
#: machine's latency to deliver the signal and report the exit (2 shared cores under load)
STOP_BOUND_S = 1.0 + 0.5


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_rx_signal_stops_it_while_the_port_write_blocks(rx_builds, sig: int) -> None:
    """The port's output is stopped (tcflow TCOOFF, as an XOFF or a peer that stopped reading
    does): attitude-rx's answer to 0xAA cannot leave. A signal still ends it within the bound,
    with its statistics and exit code 0 (nothing was acknowledged, nothing is lost)."""
    import termios

    rx = Rx(rx_builds["host"], "--gap-ms", "2000")
    termios.tcflow(rx.slave, termios.TCOOFF)
    os.write(rx.master, bytes([0xAA]))  # B answers 0xBB: the write blocks
    time.sleep(0.5)
    dt, rc = _wait_exit(rx.proc, sig)
    _, _, err = rx.finish(sig=None)
    print(f"port write blocked: signal {sig} -> exit {rc} after {dt:.3f} s")
    assert dt < STOP_BOUND_S, f"{dt:.2f} s"
    assert rc == 0, err
    assert f"stopped by signal {sig}" in err
    assert _stats(err)["syns"] == 1


def test_rx_signal_stops_it_while_stdout_blocks(rx_builds) -> None:
    """stdout is a one-page pipe nobody reads: the printing thread blocks with acknowledged
    samples queued. SIGTERM ends the program within the bound; the samples it could not print
    are counted (undelivered=) and the exit code says so (75); printed + undelivered =
    acknowledged."""
    import fcntl

    rx = Rx(rx_builds["host"], "--method", "rv1", "--no-header", "--queue", "8", "--gap-ms", "2000")
    assert rx.proc.stdout is not None
    fcntl.fcntl(rx.proc.stdout.fileno(), fcntl.F_SETPIPE_SZ, 4096)
    feeder = Feeder(rx.master, impl="c", timeout_ms=300, max_attempts=1)
    acked = _send_while_alive(feeder, rx, _unique_codes(60))
    assert feeder.sender.stats.gave_up > 0  # back-pressure reached the sender
    dt, rc = _wait_exit(rx.proc, signal.SIGTERM)
    out, err = rx.proc.communicate(timeout=10)
    rx.finish(sig=None)
    err = err.decode()
    print(f"stdout blocked: SIGTERM -> exit {rc} after {dt:.3f} s")
    assert dt < STOP_BOUND_S, f"{dt:.2f} s"
    assert rc == 75, err
    st = _stats(err)
    rows = _rows(out.decode())
    # the line being written when the grace time ended is lost; the samples still queued
    # were never integrated
    assert feeder.b_bytes[0x00] == len(acked) == st["integrated"] + st["undelivered"], st
    assert st["lines_lost"] == 1 and st["undelivered"] > 0, st
    assert len(rows) + st["lines_lost"] + st["undelivered"] == len(acked), (len(rows), st)
    assert rows == acked[:len(rows)]
    assert f"{st['undelivered']} acknowledged samples not integrated and 1 attitude line not printed" in err


def test_rx_random_bytes_never_integrate_impossible_codes(rx_builds) -> None:
    """1 MiB of random bytes on the line: the blocks whose 8-bit sum happens to match are
    acknowledged, but no code outside 0..4095 is integrated; every one is counted."""
    rng = np.random.default_rng(17)
    noise = rng.integers(0, 256, size=1 << 20, dtype=np.uint8).tobytes()
    rx = Rx(rx_builds["host"], "--method", "rv1", "--no-header", "--gap-ms", "2000")
    for k in range(0, len(noise), 4096):
        os.write(rx.master, noise[k:k + 4096])
        while select.select([rx.master], [], [], 0)[0]:  # B's answers: keep its output moving
            os.read(rx.master, 4096)
    end = time.monotonic() + 1.0
    while time.monotonic() < end:
        if select.select([rx.master], [], [], 0.05)[0]:
            os.read(rx.master, 4096)
    rc, out, err = rx.finish(signal.SIGINT)
    assert rc == 0, err
    st = _stats(err)
    rows = _rows(out)
    assert all(0 <= v <= 4095 for r in rows for v in r)
    # every sample record of an accepted block is integrated or rejected for its code
    assert st["received"] == st["integrated"] + st["code_errors"]
    # no good sample before it: held periods before the first one print nothing
    assert len(rows) == st["integrated"] + st["held"]
    print(f"1 MiB of noise: {st['blocks_accepted']} blocks accepted, {st['received']} sample records, "
          f"{st['code_errors']} rejected codes, {st['integrated']} integrated, "
          f"{st['block_errors']} bad reports, {sum(st[k] for k in ('boot', 'selftest', 'gave_up', 'overrun', 'adc_error'))} reports")
    assert st["blocks_accepted"] > 0 and st["code_errors"] > 0  # the noise did get through the sum


def _jsonl(out: str) -> list[dict]:
    import json

    return [json.loads(ln) for ln in out.strip().splitlines()]


def test_rx_reports_are_logged_and_losses_held_not_integrated(rx_builds) -> None:
    """The firmware's report blocks are decoded (stderr and JSONL records), never integrated;
    the sample period comes from BOOT; every missing sample (loss reports, a code above 4095,
    a numbering slip) is filled by holding the last rate (docs/cross-build.md)."""
    import attitude_c
    from attitude_c.link import block

    rx = Rx(rx_builds["host"], "--method", "rv1", "--format", "jsonl", "--gap-ms", "2000")
    feeder = Feeder(rx.master)
    codes = _gyro_codes(24, seed=7)
    bad = bytes([0x10, 0x00, 0x08, 0x00, 0x08, 0x00])  # X = 4096: no sample, and no report
    # (what is sent, sample number it stands for or None); numbers 0..23
    stream: list[tuple[bytes, str]] = [
        (block.encode_boot(72, 9600), "boot"),
        *[(_block(codes[k]), "s") for k in range(6)],
        (block.encode_loss("gave_up", 6, 1), "loss"),
        *[(_block(codes[k]), "s") for k in (7, 8)],
        (block.encode_loss("overrun", 9, 3), "loss"),            # 9, 10, 11
        (_block(codes[12]), "s"),
        (block.encode_adc_error(13, -40), "loss"),
        (_block(codes[14]), "s"),
        (bad, "bad"),                                           # 15
        (_block(codes[16]), "s"),
        (block.encode_selftest(-41, 4095, 1), "selftest"),
        (bytes([0xFE, 0x09, 0, 0, 0, 0]), "unknown"),           # no such kind: ignored, no number
        (block.encode_loss("gave_up", 19, 1), "loss"),          # 17, 18 vanished unreported: slip 2
        *[(_block(codes[k]), "s") for k in range(20, 24)],
    ]
    for raw, _ in stream:
        feeder.send(raw)
    feeder.drain(300)
    rc, out, err = rx.finish(signal.SIGINT)
    assert rc == 0, err
    recs = [r for r in _jsonl(out) if "link" not in r]  # the link counters: checked elsewhere
    updates = [r for r in recs if "q" in r]
    reports = [r for r in recs if "report" in r]
    errors = [r for r in recs if "error" in r]
    # one rv1 update per sample period, numbers 0..23 without a hole, t from BOOT's 20 ms
    assert [u["n"] for u in updates] == list(range(24))
    np.testing.assert_allclose([u["t"] for u in updates], 0.02 * np.arange(1, 25), rtol=1e-12)
    # the policy, written out: a missing sample gets the rate of the last good one
    held = {6: 5, 9: 8, 10: 8, 11: 8, 13: 12, 15: 14, 17: 16, 18: 16, 19: 16}
    src = [held.get(k, k) for k in range(24)]
    assert [u["codes"] for u in updates] == codes[src].tolist()
    dtheta = (codes[src] - 2048.0) * SCALE * 0.02
    np.testing.assert_allclose([u["q"] for u in updates], attitude_c.integrate(dtheta, method="rv1"),
                               atol=1e-12)  # same f64 arithmetic as the host library: rounding only
    assert updates[-1]["held"] == len(held)
    assert [r["report"] for r in reports] == ["BOOT", "GAVE_UP", "OVERRUN", "ADC_ERROR", "SELFTEST", "GAVE_UP"]
    boot = reports[0]
    assert (boot["period_ticks"], boot["period_s"], boot["baud"], boot["version"]) == (72, 0.02, 9600, 1)
    assert [(r["first"], r["count"], r["slip"]) for r in reports if "first" in r] == [
        (6, 1, 0), (9, 3, 0), (13, 1, 0), (17, 3, 2)]
    assert reports[3]["status"] == -40 and reports[4]["bad_code"] == 4095
    assert [e["error"] for e in errors] == ["code", "kind"]
    assert errors[0]["n"] == 15 and errors[0]["codes"] == [4096, 2048, 2048]
    # each record sits in the stream where it arrived
    order = [("q" if "q" in r else r.get("report") or r["error"]) for r in recs]
    assert order.index("BOOT") == 0 and order[7] == "GAVE_UP" and order[11] == "OVERRUN"
    st = _stats(err)
    assert st["received"] == 16 and st["integrated"] == 15 and st["code_errors"] == 1
    assert st["held"] == st["missing"] == len(held)
    assert (st["boot"], st["gave_up"], st["overrun"], st["adc_error"], st["selftest"]) == (1, 2, 1, 1, 1)
    assert st["block_errors"] == 1 and st["seq_errors"] == 1 and st["updates"] == 24
    assert "BOOT: block format 1, sample period 72 ticks = 0.02 s, 9600 baud" in err
    assert "OVERRUN: 3 samples lost at sample 9" in err and "samples 9..11 missing (OVERRUN): holding the last rate over 3 sample periods" in err
    assert "sample 15 rejected: code out of 0..4095" in err
    assert "vanished unreported" in err


def test_rx_period_option_wins_over_boot_with_a_warning(rx_builds) -> None:
    rx = Rx(rx_builds["host"], "--method", "rv3", "--period", "0.01", "--no-header", "--gap-ms", "2000")
    from attitude_c.link import block

    feeder = Feeder(rx.master)
    feeder.send(block.encode_boot(72, 9600))
    for k in range(3):
        feeder.send(_block((2048 + 100 * k, 2048, 2048)))
    feeder.drain(200)
    rc, out, err = rx.finish(signal.SIGINT)
    assert rc == 0, err
    rows = out.strip().splitlines()
    assert len(rows) == 1 and float(rows[0].split(",")[0]) == pytest.approx(0.03)
    assert "warning: the board samples every 0.02 s (BOOT) but --period 0.01 s was given" in err


def test_rx_command_line_getopt(rx_builds, tmp_path: Path) -> None:
    """-h/--help, --version, unknown options name themselves, --name=value, config file kept."""

    exe = rx_builds["host"]

    def run(*args: str) -> tuple[int, str, str]:
        p = subprocess.run([*exe, *args], capture_output=True, timeout=20, check=False)
        return p.returncode, p.stdout.decode(), p.stderr.decode()

    for h in ("-h", "--help"):
        rc, out, err = run(h)
        assert rc == 0 and out.startswith("usage:") and "--period" in out and err == ""
        assert "--link P                 auto (default:" in out  # link v2 or legacy, as the board speaks
    rc, out, _ = run("--version")
    import attitude_c

    version = attitude_c.__version__  # from the library's version.h
    assert rc == 0 and out.startswith(f"attitude-rx {version} ")
    assert run("--port", "/dev/null", "--help")[0] == 0  # help wins over the rest
    for args, want in [(("--foo",), "unknown option --foo"),
                       (("--port", "/dev/null", "--bogus=3"), "unknown option --bogus"),
                       (("-x", "--port", "/dev/null"), "unknown option -x"),
                       (("--port",), "option --port needs a value"),
                       (("--port", "/dev/null", "--period"), "option --period needs a value"),
                       (("--port", "/dev/null", "stray"), "unexpected argument 'stray'")]:
        rc, out, err = run(*args)
        assert rc == 64 and want in err and err.count("\n") == 1, (args, err)
    cfg = tmp_path / "rx.conf"
    cfg.write_text(f"port = {tmp_path / 'nope'}\n")
    rc, _, err = run("--config", str(cfg))  # the file is read ...
    assert rc == 66 and "nope" in err
    rc, _, err = run(f"--config={cfg}", "--port=/dev/null")  # ... and the command line wins
    assert rc == 74 and "not a serial port" in err


def test_rx_builds_say_whether_gpsd_is_built_in(rx_builds) -> None:
    """Host and ARMv4T (qemu-arm) builds: --help lists --gnss, --version says whether gpsd support
    (libgps, probed at build time: toolchain/app/optional.toml) is built in, and --gnss gpsd
    agrees: without it one line and exit 69; with it, a gpsd that refuses the connection is
    one line and exit 69 as well (docs/gnss.md)."""
    import socket

    def run(exe: list[str], *args: str) -> tuple[int, str, str]:
        p = subprocess.run([*exe, *args], capture_output=True, timeout=60, check=False)
        return p.returncode, p.stdout.decode(), p.stderr.decode()

    for name, exe in rx_builds.items():
        rc, out, _ = run(exe, "--help")
        assert rc == 0 and "--gnss SOURCE" in out and "69 gpsd unreachable" in out, name
        rc, out, _ = run(exe, "--version")
        built = "gpsd support: yes (libgps)" in out
        assert rc == 0 and (built or "gpsd support: no" in out), (name, out)
        refused = socket.socket()  # bound, not listening: a connection to it is refused
        refused.bind(("127.0.0.1", 0))
        master, slave = os.openpty()
        try:
            rc, _, err = run(exe, "--port", os.ttyname(slave), "--gnss",
                             f"gpsd:127.0.0.1:{refused.getsockname()[1]}")
        finally:
            refused.close()
            os.close(master)
            os.close(slave)
        want = "is unreachable" if built else "was built without gpsd support"
        assert rc == 69 and want in err and err.count("\n") == 1, (name, err)


def test_rx_port_vanishes_is_reported_and_retried(rx_builds, tmp_path: Path) -> None:
    """The port goes away (EIO): reported once, reopened when it comes back, no spinning."""
    require_tools("socat", apt="socat")
    port, peer = tmp_path / "ttyRX", tmp_path / "ttyPEER"

    def start_socat() -> subprocess.Popen:
        p = subprocess.Popen(["socat", f"PTY,link={port},raw,echo=0", f"PTY,link={peer},raw,echo=0"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        end = time.monotonic() + 10
        while not (port.exists() and peer.exists()):
            assert time.monotonic() < end, "socat did not create the pty pair"
            time.sleep(0.02)
        return p

    s1 = start_socat()
    proc = subprocess.Popen([*rx_builds["host"], "--port", str(port), "--method", "rv1", "--no-header",
                             "--reopen-delay", "0.1", "--gap-ms", "2000"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    s2 = None
    try:
        assert proc.stderr is not None
        assert "8N1" in _readline(proc.stderr)
        s1.terminate()
        s1.wait(timeout=10)
        line = _readline(proc.stderr)
        assert "reopening" in line, line
        s2 = start_socat()
        line = _readline(proc.stderr)
        assert "reopened" in line, line
        fd = os.open(peer, os.O_RDWR | os.O_NOCTTY)
        try:
            Feeder(fd).send(_block((2100, 2048, 2048)))
        finally:
            os.close(fd)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=20)
    finally:
        for p in (proc, s1, s2):
            if p is not None and p.poll() is None:
                p.kill()
                p.wait()
    assert proc.returncode == 0, err
    assert out.decode().count("\n") == 1
    st = _stats(err.decode())
    assert st["port_errors"] == 1 and st["reopens"] == 1  # reported once, not spun on
    assert st["blocks_accepted"] == 1


def test_rx_errors_and_exit_codes(rx_builds, tmp_path: Path) -> None:
    exe = rx_builds["host"]

    def run(*args: str, user: list[str] | None = None) -> tuple[int, str]:
        p = subprocess.run([*(user or []), *exe, *args], capture_output=True, timeout=20,
                           check=False)
        return p.returncode, p.stderr.decode()

    rc, err = run("--port", str(tmp_path / "nope"))
    assert rc == 66 and "No such file" in err
    rc, err = run()
    assert rc == 64 and "--port" in err
    rc, err = run("--port", "/dev/null", "--bogus", "1")
    assert rc == 64 and "--bogus" in err
    rc, err = run("--port", "/dev/null", "--method", "rv9")
    assert rc == 78 and "method" in err and "rv9" in err
    rc, err = run("--port", "/dev/null", "--baud", "12345")
    assert rc == 78 and "baud" in err
    rc, err = run("--port", "/dev/null", "--gyro-zero", "1,2")
    assert rc == 78 and "gyro-zero" in err
    rc, err = run("--port", "/dev/null", "--axes", "x,x,z")
    assert rc == 78 and "axes" in err
    bad = tmp_path / "bad.conf"
    bad.write_text("baud = 9600\nperiod = -1\n")
    rc, err = run("--port", "/dev/null", "--config", str(bad))
    assert rc == 78 and "bad.conf:2" in err and "period" in err
    rc, err = run("--port", "/dev/null")  # not a tty
    assert rc == 74 and "not a serial port" in err
    rc, err = run("--help")
    assert rc == 0
    # no permission: a file with mode 000, opened as an ordinary user (as nobody when root)
    node = tmp_path / "locked"
    node.write_text("")
    node.chmod(0o000)
    tmp_path.chmod(0o755)
    if os.geteuid() == 0:
        require_tools("setpriv", apt="util-linux")
        user = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups"]
        exe_dir = Path(exe[0]).parent
        for p in (exe_dir, *exe_dir.parents):
            if p == Path("/"):
                break
            p.chmod(p.stat().st_mode | 0o005)
        rc, err = run("--port", str(node), user=user)
    else:
        rc, err = run("--port", str(node))
    assert rc == 77 and "Permission denied" in err


def test_rx_accepts_every_method_name(rx_builds, tmp_path: Path) -> None:
    """Every integrator method of the library (attitude_c.METHODS, rv3-reuse-poly
    included) is a valid --method: the run gets past its configuration to the
    port (exit 66, no such port), and the error for an unknown name lists them."""
    import attitude_c

    for m in attitude_c.METHODS:
        p = subprocess.run([*rx_builds["host"], "--port", str(tmp_path / "nope"), "--method", m],
                           capture_output=True, timeout=20, check=False)
        assert p.returncode == 66, (m, p.stderr)
    p = subprocess.run([*rx_builds["host"], "--port", str(tmp_path / "nope"), "--method", "rv9"],
                       capture_output=True, timeout=20, check=False)
    assert p.returncode == 78
    assert all(m in p.stderr.decode() for m in attitude_c.METHODS)


BAUDS = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400)


def _line_capacity(baud: int, block_size: int) -> float:
    """Blocks per second the handshake protocol carries at most: one exchange is 0xAA, 0xBB,
    N data bytes, the checksum and the answer, N + 4 bytes of 10 bits (8N1) one after the
    other (each side waits for the other's byte: the line is used half-duplex)."""
    return baud / (10.0 * (block_size + 4))


def test_rx_warns_when_the_rate_cannot_fit_the_line(rx_builds) -> None:
    """For every baud rate and block size, with the default period (0.02 s) and 0.01 s: a
    warning with the numbers exactly when the samples need more blocks per second than the
    line carries (9600 baud, 6-byte blocks: 96.0 blocks/s)."""
    import re

    exe = rx_builds["host"]
    checked = warned = 0
    for baud in BAUDS:
        for n in range(6, 61, 6):
            for period in (None, 0.01):
                args = ["--port", "/dev/null", "--baud", str(baud), "--block-size", str(n)]
                if period is not None:
                    args += ["--period", str(period)]
                p = subprocess.run([*exe, *args], capture_output=True, timeout=20, check=False)
                err = p.stderr.decode()
                assert p.returncode == 74, err  # /dev/null is no tty: the check comes first
                need = (1.0 / (period or 0.02)) / (n // 6)
                cap = _line_capacity(baud, n)
                m = re.search(r"needs ([0-9.]+) blocks/s .* carries at most ([0-9.]+)", err)
                if need > cap:
                    assert m, (baud, n, period, err)
                    assert (m.group(1), m.group(2)) == (f"{need:.1f}", f"{cap:.1f}"), err
                    # --link auto (the default) has heard nothing yet: the figures are the legacy link's
                    assert "(if it speaks the legacy protocol; link v2 carries about twice as much)" in err
                    warned += 1
                else:
                    assert "warning" not in err, (baud, n, period, err)
                checked += 1
    assert checked == 180 and 0 < warned < checked


def test_rx_warns_when_the_boot_period_cannot_fit_the_line(rx_builds) -> None:
    """The period BOOT announces is checked against the port's baud rate too."""
    from attitude_c.link import block

    for ticks, warns in ((36, True), (72, False)):  # 100 and 50 samples/s against 96.0 blocks/s
        rx = Rx(rx_builds["host"], "--no-header", "--gap-ms", "2000")
        assert "warning" not in rx.banner
        Feeder(rx.master).send(block.encode_boot(ticks, 9600))
        time.sleep(0.2)
        rc, _, err = rx.finish(signal.SIGINT)
        assert rc == 0, err
        assert ("needs 100.0 blocks/s" in err and "carries at most 96.0" in err) == warns, err
        assert "if it speaks" not in err  # the BOOT came over the legacy link: auto knows it


class _PtyMaster:
    """The master side of attitude-rx's pty as a port for run_sender2. Writes wait for room
    only while attitude-rx runs: once it has ended (--count), nobody reads the pty, and a
    blocking write into its full buffer would hang the sender."""

    timeout = 0.01
    baudrate = None
    in_waiting = 0

    def __init__(self, fd: int, rx: Rx) -> None:
        self.fd, self.rx = fd, rx
        os.set_blocking(fd, False)

    def read(self, n: int) -> bytes:
        r, _, _ = select.select([self.fd], [], [], self.timeout)
        return os.read(self.fd, 4096) if r else b""

    def write(self, data: bytes) -> None:
        view = memoryview(data)
        while view and self.rx.proc.poll() is None:
            _, w, _ = select.select([], [self.fd], [], self.timeout)
            try:
                view = view[os.write(self.fd, view):] if w else view
            except BlockingIOError:  # room for less than the pty's write chunk: wait again
                pass

    def flush(self) -> None:
        pass


class _RxEnded:
    """run_sender2's stop: set once attitude-rx has ended."""

    def __init__(self, rx: Rx) -> None:
        self.rx = rx

    def is_set(self) -> bool:
        return self.rx.proc.poll() is not None


@pytest.mark.parametrize("link", ["v2", "auto"])
def test_rx_link_v2(rx_builds, link: str) -> None:
    """--link v2 (and auto, which detects it): a board speaking link v2 (the Python sender
    A from attitude_c.link.transport2): BOOT + samples, every line printed, no loss."""
    from attitude_c.link import block
    from attitude_c.link.transport2 import run_sender2

    codes = _gyro_codes(300)
    recs = [block.encode_boot(36, 9600)] + [_block(c) for c in codes]
    rx = Rx(rx_builds["host"], "--link", link, "--method", "rv1", "--count", "200", "--no-header")
    rep = run_sender2(_PtyMaster(rx.master, rx), recs, impl="python", timeout=15,
                      stop=_RxEnded(rx))  # type: ignore[arg-type]
    rc, out, err = rx.finish(sig=None)
    assert rc == 0, err
    assert len(out.splitlines()) == 200
    assert rep.acknowledged >= 201  # BOOT + the 200 samples the count needs (a frame may carry more)
    line = next(x for x in err.splitlines() if x.startswith("attitude-rx: link2:"))
    stats = dict(kv.split("=") for kv in line.split(":", 2)[2].split())
    assert int(stats["records"]) == rep.acknowledged and int(stats["syns"]) == 1
    assert ("the board speaks link v2" in err) == (link == "auto")
    assert "warning" not in err  # 100 samples/s (BOOT) is beyond the legacy link's 96.0, not v2's


@pytest.mark.parametrize("link", [None, "auto"])
def test_rx_link_auto_hears_legacy(rx_builds, link: str | None) -> None:
    """auto (the default) and a legacy board: the block that names the protocol is the
    first one printed (delivered, not just detected); every acknowledged sample printed."""
    args = () if link is None else ("--link", link)
    rx = Rx(rx_builds["host"], *args, "--method", "rv1", "--count", "20", "--no-header", "--gap-ms", "2000")
    # 1 s answer timeout: a stall of the loaded machine must not make A resend a block B took
    # (the legacy protocol would deliver it twice), and A gives up within 5 s once rx is gone
    feeder = Feeder(rx.master, impl="c", timeout_ms=1000)
    codes = [tuple(int(v) for v in c) for c in _gyro_codes(40)]
    acked = _send_while_alive(feeder, rx, codes)
    rc, out, err = rx.finish(sig=None)
    assert rc == 0, err
    assert acked == codes[:20] and _rows(out) == acked, f"{err}\nA: {feeder.sender.stats} B sent {feeder.b_bytes}"
    assert "the board speaks the legacy protocol" in err and "link2:" not in err


def _pump2(a, rx: Rx, seconds: float) -> None:
    """Sender A (attitude_c.link.v2.Sender2) on the pty's master side in real time (1 ms
    ticks) until attitude-rx ends or `seconds` pass."""
    from attitude_c.link.v2 import Result2

    end = time.monotonic() + seconds
    while time.monotonic() < end and rx.proc.poll() is None:
        out = bytearray()
        while len(out) < 64:
            res, byte = a.poll(_tick())
            if res == Result2.SEND:
                out.append(byte)
            elif res != Result2.TIMEOUT:
                break
        if out:
            os.write(rx.master, bytes(out))
        r, _, _ = select.select([rx.master], [], [], 0.005)
        if r:
            for b in os.read(rx.master, 4096):
                a.sink(b, _tick())


def test_rx_link_auto_v2_board_mid_stream_loses_nothing(rx_builds) -> None:
    """The default (auto) started while a v2 board streams to a receiver that went away: the
    first frame it hears is a DATA frame of a session it never saw. That frame is answered
    F_NOSESSION (not just used for detection), the board starts a session at its first
    unacknowledged record, and from that record on every sample is printed, in order."""
    from attitude_c.link import block, v2

    codes = [tuple(int(v) for v in c) for c in _gyro_codes(60)]
    recs = [block.encode_boot(72, 9600)] + [_block(c) for c in codes]
    a = v2.Sender2(ring_size=64, max_samples=4, rto=300)
    old = v2.Receiver2(room=100)  # the receiver before: BOOT and a few samples acknowledged
    for r in recs:
        a.push(r)
    t = 0
    while a.base < 5:
        t += 1
        assert t < 10_000, "the first receiver took nothing"
        _, byte = a.poll(t)
        if byte is not None:
            old.sink(byte)
        _, byte = old.poll()
        if byte is not None:
            a.sink(byte, t)
    base = a.base  # A's first record not acknowledged: a frame after it may be on its way
    assert a.session == "run" and a.next > base
    rx = Rx(rx_builds["host"], "--method", "rv1", "--count", "40", "--no-header")
    _pump2(a, rx, 20)
    rc, out, err = rx.finish(sig=None)
    assert rc == 0, err
    assert _rows(out) == codes[base - 1:base - 1 + 40], err  # record k is sample k - 1 (BOOT first)
    line = next(x for x in err.splitlines() if x.startswith("attitude-rx: link2:"))
    stats = {k: int(v) for k, v in (kv.split("=") for kv in line.split(":", 2)[2].split())}
    # each DATA frame already on its way is answered F_NOSESSION too, and makes A SYN again (at
    # its base: the rows above show nothing lost or repeated)
    assert stats["no_session"] >= 1 and stats["syns"] >= 1, err
    assert "the board speaks link v2" in err and "attitude-rx: link: syns=" not in err


def test_rx_link_auto_undecodable_legacy_block_decides_nothing(rx_builds) -> None:
    """auto: a block the legacy checksum accepts but whose record does not decode (as a v2
    frame's bytes may by chance) is delivered as on the legacy link but does not name the
    protocol: a v2 board heard afterwards is still detected and every sample printed."""
    from attitude_c.link import block
    from attitude_c.link.transport2 import run_sender2

    rx = Rx(rx_builds["host"], "--method", "rv1", "--no-header", "--gap-ms", "2000")
    assert Feeder(rx.master, impl="c", timeout_ms=300).send(_block((0xF123, 0x4567, 0x89AB)))
    codes = [tuple(int(v) for v in c) for c in _gyro_codes(30)]
    rep = run_sender2(_PtyMaster(rx.master, rx), [block.encode_boot(72, 9600)] + [_block(c) for c in codes],
                      impl="python", timeout=15)
    assert rep.acknowledged == 31
    time.sleep(0.3)
    rc, out, err = rx.finish(signal.SIGINT)
    assert rc == 0, err
    assert "the board speaks link v2" in err and "legacy protocol" not in err
    assert [r for r in _rows(out) if max(r) < 4096][-30:] == codes, err


class _ProbeWatch(_PtyMaster):
    """_PtyMaster that sets ``probed`` when A writes a probe (an empty DATA frame): A's sign
    that B's limit has blocked it for rto ticks."""

    def __init__(self, fd: int, rx: Rx) -> None:
        import threading

        super().__init__(fd, rx)
        self.probed = threading.Event()

    def write(self, data: bytes) -> None:
        from attitude_c.link import v2

        for part in bytes(data).split(b"\0"):
            f = v2.rcobs_decode(part) if part else None
            if f is not None and len(f) == 6 and f[0] & 0xDF == v2.T_DATA:  # n = 0, either epoch
                self.probed.set()
        super().write(data)


@pytest.mark.parametrize("impl", ["c", "python"])
def test_rx_link_v2_full_queue_resumes(rx_builds, impl: str) -> None:
    """Link v2 under back-pressure: attitude-rx's stdout is a pipe nobody reads at first, so its
    attitude thread blocks, the queue fills and B's limit stops A (which probes). Once stdout is
    read, the room grows and A must resume: every one of the 800 samples acknowledged, received
    once and printed, and the run ends by --count. (A colleague's "v2 stall" at a full queue was
    this state with a harness that never read stdout: correct back-pressure, not a stuck link.)"""
    import fcntl
    import threading

    from attitude_c.link.transport2 import run_sender2

    n, queue = 800, 256
    rx = Rx(rx_builds["host"], "--link", "v2", "--method", "rv1", "--count", str(n), "--no-header",
            "--consumer-delay", "0.003")
    assert rx.proc.stdout is not None
    # one page of pipe (Linux' minimum): ~38 lines of ~107 bytes, far below the 800 - 256 queued
    # and 64 in A's ring that must be printed before the last sample can be acknowledged
    fcntl.fcntl(rx.proc.stdout.fileno(), fcntl.F_SETPIPE_SZ, 4096)
    port = _ProbeWatch(rx.master, rx)
    out: list[bytes] = []

    def drain() -> None:
        port.probed.wait(60)  # bound only: the probe comes once the pipe and the queue are full
        out.append(rx.proc.stdout.read())  # type: ignore[union-attr]

    th = threading.Thread(target=drain, daemon=True)
    th.start()
    recs = [_block(c) for c in _gyro_codes(n)]
    rep = run_sender2(port, recs, impl=impl, timeout=60, stop=_RxEnded(rx))  # type: ignore[arg-type]
    if rep.ended_by != "done":  # a stuck link leaves attitude-rx waiting: stop it for its statistics
        rx.proc.send_signal(signal.SIGINT)
    th.join(90)  # bound only: the drain ends at attitude-rx's exit
    rc, _, err = rx.finish(sig=None)
    st = _stats(err)
    assert port.probed.is_set() and rep.stats["timeouts"] >= 1, err  # B's limit did block A
    assert rc == 0 and rep.ended_by == "done" and rep.acknowledged == n, f"{rep}\n{err}"
    assert st["queue_high_water"] == queue, err  # the default queue did fill
    line = next(x for x in err.splitlines() if x.startswith("attitude-rx: link2:"))
    l2 = dict(kv.split("=") for kv in line.split(":", 2)[2].split())
    assert int(l2["records"]) == n and st["received"] == n and st["integrated"] == n, err  # each once
    assert len(b"".join(out).splitlines()) == n
