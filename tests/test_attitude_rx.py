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

    def __init__(self, master: int, channel=None, block_size: int = 6, timeout_ms: int = 2000) -> None:
        from attitude_c.link import Sender

        self.master = master
        self.channel = channel
        # qemu-arm answers within a few ms; the default 2 s leaves room for a loaded CI
        # machine (a timeout here would make A resend a block B already accepted)
        self.sender = Sender(block_size=block_size, syn_timeout=timeout_ms, answer_timeout=timeout_ms,
                             max_attempts=5)
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

    def send(self, block: bytes, deadline: float = 10.0) -> None:
        """Send one block (with the sender's retries) until the sender is idle again."""
        from attitude_c.link import Result

        end = time.monotonic() + deadline
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
                return
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
        # the first stderr line is printed once the port is configured (raw, no echo)
        r, _, _ = select.select([self.proc.stderr], [], [], 20)
        assert r, "attitude-rx did not start"
        self.banner = self.proc.stderr.readline().decode()
        assert "8N1" in self.banner, self.banner

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
    assert st["queue_overflows"] == 0 and st["naks"] == 0 and st["boot"] == 1 and st["held"] == 0
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
    recs = [json.loads(ln) for ln in out.strip().splitlines()]
    assert len(recs) == n and "rv3-reuse" in err
    assert [r["codes"] for r in recs] == codes.tolist()
    rates = (codes - np.array(zero)) * np.array(scale)
    body = np.column_stack([-rates[:, 1], rates[:, 0], rates[:, 2]])
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
    assert st["queue_overflows"] == 0
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


@pytest.mark.qemu
def test_rx_queue_overflow_is_counted_and_held(rx_builds) -> None:
    """A slow attitude thread and a tiny queue: samples are dropped and counted, not blocked;
    the next record that gets through brings the gap, and the rate is held over it."""
    rx = Rx(rx_builds["host"], "--method", "rv1", "--no-header", "--queue", "2",
            "--consumer-delay", "0.2", "--gap-ms", "2000")
    feeder = Feeder(rx.master)
    n = 12
    for i in range(n):
        feeder.send(_block((2048 + i, 2048, 2048)))
    time.sleep(1.0)  # the consumer (0.2 s per record) empties the 2-slot queue
    feeder.send(_block((2100, 2048, 2048)))
    time.sleep(0.5)
    rc, out, err = rx.finish(signal.SIGINT)
    assert rc == 0, err
    st = _stats(err)
    assert st["received"] == n + 1
    assert st["queue_overflows"] > 0
    assert st["queue_high_water"] == 2
    # nothing accepted is lost silently: every sample was integrated, or counted and its period held
    assert st["integrated"] + st["queue_overflows"] == n + 1
    assert st["held"] == st["missing"] == st["queue_overflows"]
    rows = [ln.split(",") for ln in out.strip().splitlines()]
    assert len(rows) == st["updates"] == n + 1  # one rv1 update per sample period
    assert [int(r[1]) for r in rows] == list(range(n + 1))  # the numbering has no hole
    assert "dropped on a full queue" in err


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
    recs = _jsonl(out)
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
