"""``attitude view`` as a command: its URL line, one-line errors with the
documented exit statuses, Ctrl-C and SIGTERM ending cleanly with the
recording complete, the warning for a non-loopback address, and the whole
recipe ``attitude-rx --format jsonl | attitude view --stdin`` with the real
receiver app on a pseudo-terminal fed by the link sender. Every process has
a timeout and is killed in a ``finally``."""

from __future__ import annotations

import csv
import io
import json
import os
import re
import select
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, _missing, require_target
from test_view_sources import CODES, K, _constant_rate_trial, send_boot_and_samples

import attitude_c

pytestmark = pytest.mark.system  # starts attitude view servers


def _aiohttp() -> None:
    try:
        import aiohttp  # noqa: F401
    except ImportError:
        _missing("needs aiohttp: pip install -e '.[test]'")


def _cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "attitude_c", "view", *args]


class View:
    """``attitude view`` in a subprocess; ``url`` from its first stdout line."""

    def __init__(self, *args: str, stdin: int | None = subprocess.DEVNULL, port: int = 0,
                 cwd: Path | None = None) -> None:
        self.proc = subprocess.Popen(_cmd("--port", str(port), *args), stdin=stdin, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, cwd=cwd or ROOT, start_new_session=True)
        assert self.proc.stdout is not None
        r, _, _ = select.select([self.proc.stdout], [], [], 60)
        line = self.proc.stdout.readline().decode() if r else ""
        m = re.search(r"(http://\S+/)", line)
        if not m:
            self.kill()
            raise AssertionError(f"no URL line: {line!r}; stderr: {self.proc.stderr.read().decode()}")
        self.url = m.group(1)
        self.line = line

    def get(self, path: str) -> bytes:
        with urllib.request.urlopen(self.url + path.lstrip("/"), timeout=10) as r:
            return r.read()

    def counters(self, timeout: float = 10) -> dict:
        """The source's counters, as the page receives them (the first status frame on /ws)."""
        import asyncio

        import aiohttp

        async def first() -> dict:
            async with aiohttp.ClientSession() as s, s.ws_connect(self.url + "ws") as ws:
                while True:
                    msg = json.loads((await ws.receive(timeout=timeout)).data)
                    if "counters" in msg:
                        return msg["counters"]

        return asyncio.run(first())

    def stop(self, sig: int = signal.SIGINT, timeout: float = 10) -> tuple[int, str]:
        self.proc.send_signal(sig)
        try:
            _, err = self.proc.communicate(timeout=timeout)
        finally:
            self.kill()
        return self.proc.returncode, err.decode()

    def kill(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()


def _run(*args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    return subprocess.run(_cmd(*args), capture_output=True, text=True, timeout=timeout, cwd=ROOT,
                          stdin=subprocess.DEVNULL, check=False)


def _one_line_error(proc: subprocess.CompletedProcess, rc: int, text: str) -> None:
    assert proc.returncode == rc, (proc.returncode, proc.stderr)
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert "Traceback" not in proc.stderr
    assert text in lines[-1], proc.stderr
    assert len(lines) == 1 or lines[0].startswith("usage:"), proc.stderr


def test_usage_and_source_errors_are_one_line_with_their_exit_status(tmp_path: Path) -> None:
    _aiohttp()
    _one_line_error(_run("--replay", str(tmp_path / "missing.jsonl")), 1, "no such file")
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"t": 0, "q": [1, 0, 0, 0]}\nnot a line\n')
    _one_line_error(_run("--replay", str(bad)), 1, "line 2")
    _one_line_error(_run("--serial", "/dev/nonexistent-attitude-port"), 1, "/dev/nonexistent-attitude-port")
    _one_line_error(_run("--stdin", "--baud", "1200"), 2, "--baud is an option of --serial")
    _one_line_error(_run("--serial", "loop://", "--block-size", "8"), 2, "--block-size: must be a multiple of 6")
    _one_line_error(_run("--stdin", "--speed", "3"), 2, "--speed is for --replay and --simulate")
    _one_line_error(_run("--simulate", "--budget"), 2, "--budget: not for the display")
    _one_line_error(_run("--simulate", "--period", "-1"), 2, "--period: must be a finite number > 0")
    _one_line_error(_run("--stdin", "--port", "70000"), 2, "--port: must be in 0..65535")
    _one_line_error(_run("--stdin", "--display-rate", "500"), 2, "--display-rate: must be a finite number >= 1 and <= 100")
    _one_line_error(_run(), 2, "one of the arguments --stdin --serial --replay --simulate is required")
    _one_line_error(_run("--stdin", "--record", str(tmp_path / "no" / "dir" / "r.csv")), 1,
                    "cannot write the recording")


def test_a_nine_axis_replay_says_it_runs_the_filter(tmp_path: Path) -> None:
    """attitude view --replay TRIAL.mat with no --estimator: the attitude filter, named on
    the URL line (the page shows the same description); --method asks for the integrator."""
    _aiohttp()
    f = tmp_path / "01_nine_axis.mat"
    _constant_rate_trial(f, np.array([0.1, 0.0, 0.2]), np.array([1.0, 0, 0, 0]), 100, 100.0)
    cases = [((), "BROAD trial, ahrs (rv3-reuse); auto: the source has accelerometer and magnetometer"),
             (("--method", "rv1"), "BROAD trial, integrator rv1; auto: an integrator method was given")]
    for args, says in cases:
        v = View("--replay", str(f), *args)
        try:
            assert says in v.line, v.line
        finally:
            v.kill()
    _one_line_error(_run("--stdin", "--estimator", "ahrs"), 2, "--estimator and --method are for --serial")
    _one_line_error(_run("--serial", "loop://", "--estimator", "ahrs"), 2, "needs accelerometer samples")


def test_address_in_use_is_exit_3() -> None:
    _aiohttp()
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(1)
    try:
        port = s.getsockname()[1]
        _one_line_error(_run("--stdin", "--port", str(port)), 3, f"cannot listen on 127.0.0.1 port {port}")
    finally:
        s.close()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_ends_cleanly_with_the_recording_complete(tmp_path: Path, sig: int) -> None:
    _aiohttp()
    rec = tmp_path / "kept.csv"
    v = View("--stdin", "--record", str(rec), stdin=subprocess.PIPE)
    try:
        assert v.line.startswith(f"attitude view: {v.url}  (stdin (attitude-rx JSON Lines or CSV); Ctrl-C to stop)")
        assert v.get("/").startswith(b"<!doctype html>")
        q = attitude_c.euler_to_quat([0.1, 0.2, 0.3]).tolist()
        assert v.proc.stdin is not None
        for k in range(50):
            v.proc.stdin.write((json.dumps({"t": k * 0.01, "n": k, "q": q}) + "\n").encode())
        v.proc.stdin.write(b'{"t":0.5,"report":"BOOT","period_s":0.01}\n')
        v.proc.stdin.flush()
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and v.get("/recording.csv").count(b"\n") < 52:
            time.sleep(0.05)
        assert (tmp_path / "kept.csv.part").exists()
        t0 = time.monotonic()
        rc, err = v.stop(sig)
        assert time.monotonic() - t0 < 5  # bounded, whatever the source is doing (stdin still open)
    finally:
        v.kill()
    assert rc == 0, err
    assert "Traceback" not in err
    assert f"stopped: 50 samples and 1 events recorded in {rec}" in err
    rows = list(csv.DictReader(rec.read_text(encoding="utf-8").splitlines()))
    assert [r["n"] for r in rows[:50]] == [str(k) for k in range(50)] and rows[50]["event"] == "BOOT"
    assert not (tmp_path / "kept.csv.part").exists()


def test_non_loopback_address_needs_the_option_and_warns() -> None:
    _aiohttp()
    v = View("--stdin", "--bind", "0.0.0.0", stdin=subprocess.PIPE)
    try:
        assert v.url.startswith("http://127.0.0.1:")
        assert v.get("/").startswith(b"<!doctype html>")
        rc, err = v.stop()
    finally:
        v.kill()
    assert rc == 0
    assert "warning: listening on 0.0.0.0, not the loopback address" in err


def test_default_bind_is_loopback_only() -> None:
    _aiohttp()
    v = View("--stdin", stdin=subprocess.PIPE)
    try:
        assert v.url.startswith("http://127.0.0.1:")
        port = int(v.url.rsplit(":", 1)[1].strip("/"))
        # the listening socket's local address, from the kernel's table: 127.0.0.1 only
        listening = [ln.split()[1] for ln in Path("/proc/net/tcp").read_text().splitlines()[1:]
                     if ln.split()[3] == "0A" and int(ln.split()[1].split(":")[1], 16) == port]
        assert listening == [f"0100007F:{port:04X}"], listening
        rc, err = v.stop()
    finally:
        v.kill()
    assert rc == 0 and "warning" not in err


def test_attitude_rx_jsonl_piped_into_view(tmp_path: Path) -> None:
    """The real receiver app on a pty fed by the link sender (BOOT + 90 samples of
    a constant rate), its JSON Lines piped into ``attitude view --stdin``: the
    recording served by the view holds BOOT and every rv3 update, at the
    closed-form attitude of the constant rate."""
    _aiohttp()
    require_target("host")
    from attitude_c.link.transport import PtyPair
    from toolchain.tasks.cross import cross_build_target

    exe = str(cross_build_target("host", out=tmp_path / "rx")["app"])
    with PtyPair() as (p0, p1):
        rx = subprocess.Popen([exe, "--port", p1, "--format", "jsonl", "--gap-ms", "2000"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
        v = None
        try:
            v = View("--stdin", stdin=rx.stdout)
            assert rx.stderr is not None
            banner = rx.stderr.readline().decode()  # the port is configured
            assert "until a BOOT report announces it" in banner, banner
            send_boot_and_samples(p0, 90)
            deadline = time.monotonic() + 30
            body = b""
            while time.monotonic() < deadline:
                body = v.get("/recording.csv")
                if body.count(b"\n") >= 1 + 1 + 30:
                    break
                time.sleep(0.1)
            rx.send_signal(signal.SIGINT)
            rx.wait(timeout=10)
            rx_err = rx.stderr.read().decode()
            time.sleep(0.5)  # the view reads attitude-rx's last line (its final link counters)
            counters = v.counters()
            rc, err = v.stop()
        finally:
            for p in (rx, v.proc if v else None):
                if p is not None and p.poll() is None:
                    os.killpg(p.pid, signal.SIGKILL)
                    p.wait()
    assert rc == 0, err
    # attitude-rx's link counters reach the page (its {"link": ...} JSON Lines record), equal to
    # the statistics it prints on stderr: BOOT and 90 samples, one record per block, no NAK
    stats = dict(kv.split("=") for kv in re.search(r"link: (.*)", rx_err).group(1).split())
    assert counters["blocks"] == int(stats["blocks_accepted"]) == 91, (counters, rx_err)
    assert counters["naks"] == int(stats["naks"]) == 0 and counters["timeouts"] == int(stats["timeouts"])
    rows = list(csv.DictReader(io.StringIO(body.decode())))
    assert rows[0]["event"] == "BOOT" and json.loads(rows[0]["detail"])["period_s"] == 0.02
    smp = [r for r in rows if not r["event"]]
    assert [int(r["n"]) for r in smp] == list(range(2, 90, 3))
    t = np.array([float(r["t"]) for r in smp])
    np.testing.assert_allclose(t, (np.arange(2, 90, 3) + 1) * 0.02, rtol=1e-9)
    w = (np.array(CODES) - 2048.0) * K
    closed = attitude_c.rotvec_to_quat(t[:, None] * w)
    q = np.array([[float(r[f"q{i}"]) for i in range(4)] for r in smp])
    # attitude-rx integrates in double (17 digits printed); the recording keeps 9 significant digits
    np.testing.assert_allclose(q * np.sign(np.sum(q * closed, axis=1))[:, None], closed, atol=5e-9)
    # rates taken from successive attitudes: the constant rate (deg/s in the recording)
    rates = np.array([[float(r[f"rate_{a}_dps"]) for a in "xyz"] for r in smp[1:]])
    np.testing.assert_allclose(rates, np.tile(np.degrees(w), (len(rates), 1)), rtol=1e-5)
