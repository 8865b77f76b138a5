"""The link over real ttys (a pseudo-terminal pair) and over pyserial's
``socket://``, all four pairings of C and Python ends, a lossy channel in
the bridge, a dead port, and the ``attitude link-*`` commands. Every wait
is bounded; bridges and ports are closed in ``finally`` blocks."""

from __future__ import annotations

import itertools
import os
import select
import subprocess
import sys
import threading
import time
from typing import Any

import pytest
from conftest import ROOT

from attitude_c.cli import main as cli_main
from attitude_c.errors import LinkError
from attitude_c.link import ChannelConfig
from attitude_c.link.transport import PtyPair, SocketRelay, open_port, run_receiver, run_sender

pytestmark = pytest.mark.system  # runs link ends over pty pairs in processes

PAIRS = list(itertools.product(("c", "python"), ("c", "python")))
PAIR_IDS = [f"{a}-to-{b}" for a, b in PAIRS]
BLOCKS = [bytes([i, 0xAA, i ^ 0x55, 0xBB, 0xFF - i, 0x00]) for i in range(25)]
# Real-time ticks are milliseconds of a loaded 2-core machine: timeouts far
# above thread-scheduling jitter, so a clean line never sees a spurious one.
SLOW = {"syn_timeout_ms": 1000, "answer_timeout_ms": 1000}
GAP_MS = 400


def _exchange(url_a: str, url_b: str, s_impl: str, r_impl: str, blocks, count=None, gap_ms=GAP_MS, **kw):
    box: dict = {}
    stop = threading.Event()
    pb = open_port(url_b)
    try:
        th = threading.Thread(target=lambda: box.setdefault("rx", run_receiver(
            pb, impl=r_impl, count=count if count is not None else len(blocks), duration=30,
            gap_timeout_ms=gap_ms, stop=stop)), daemon=True)
        th.start()
        pa = open_port(url_a)
        try:
            reports, stats = run_sender(pa, blocks, impl=s_impl, **{**SLOW, **kw})
        finally:
            pa.close()
            time.sleep(0.1)  # B's last answer has gone out
            stop.set()
        th.join(timeout=35)
        assert not th.is_alive(), "receiver did not stop"
    finally:
        pb.close()
    return reports, stats, box["rx"]


@pytest.mark.parametrize("s_impl,r_impl", PAIRS, ids=PAIR_IDS)
def test_pty_pair_interop(s_impl, r_impl):
    with PtyPair() as (p0, p1):
        assert p0.startswith("/dev/pts/") and p1.startswith("/dev/pts/")
        reports, stats, rx = _exchange(p0, p1, s_impl, r_impl, BLOCKS)
    assert rx.blocks == BLOCKS
    assert [r.outcome for r in reports] == ["accepted"] * len(BLOCKS)
    assert stats["blocks_accepted"] == len(BLOCKS) and stats["retries"] == 0
    assert rx.stats["syns"] == len(BLOCKS) and rx.stats["bytes_discarded"] == 0


@pytest.mark.parametrize("s_impl,r_impl", PAIRS, ids=PAIR_IDS)
def test_socket_interop(s_impl, r_impl):
    with SocketRelay() as url:
        assert url.startswith("socket://127.0.0.1:")
        reports, _stats, rx = _exchange(url, url, s_impl, r_impl, BLOCKS)
    assert rx.blocks == BLOCKS
    assert all(r.outcome == "accepted" and r.attempts == 1 for r in reports)


def test_pty_lossy_bridge_paced_at_9600():
    """Bit errors injected between two real ttys paced at 9600 baud: every
    block B accepts is one A sent (or counted as an undetected error)."""
    blocks = [bytes([i, 2 * i % 256, 3, 4, 5, 6]) for i in range(40)]
    pair = PtyPair(baud=9600, channel=ChannelConfig(ber=5e-3, seed=7))
    try:
        # shorter timeouts so lost handshakes cost less; gap < A's timeouts (docs/link.md)
        reports, stats, rx = _exchange(pair.paths[0], pair.paths[1], "c", "c", blocks,
                                       count=10_000, max_attempts=10, gap_ms=80,
                                       syn_timeout_ms=200, answer_timeout_ms=200)
    finally:
        pair.close()
    undetected = sum(b not in blocks for b in rx.blocks)
    accepted = [r for r in reports if r.outcome == "accepted"]
    # ~7 bytes x 8 bits x 5e-3 = 0.3 corrupted frames per exchange: NAKs must occur
    assert stats["naks"] + stats["timeouts"] > 0
    assert len(accepted) >= 35  # 10 attempts per block: giving up needs 10 failures in a row
    assert len(rx.blocks) >= len(accepted) - undetected
    assert undetected <= 2  # an 8-bit sum misses ~1/30 of 2-bit errors; few frames have 2


def test_dead_port_errors_and_keeps_accepted_blocks():
    with pytest.raises(LinkError, match="cannot open port"):
        open_port("/dev/does-not-exist-tty")
    pair = PtyPair()
    got: list[bytes] = []
    try:
        pb = open_port(pair.paths[1])
        box: dict = {}
        th = threading.Thread(target=lambda: box.setdefault("rx", run_receiver(
            pb, count=1000, duration=20, on_block=got.append, gap_timeout_ms=GAP_MS)), daemon=True)
        th.start()
        pa = open_port(pair.paths[0])
        run_sender(pa, BLOCKS[:5], **SLOW)
        pa.close()
        time.sleep(0.2)
        # the line dies: the pseudo-terminal of B goes away under it
        pair.close()
        th.join(timeout=25)
        assert not th.is_alive()
    finally:
        pair.close()
        pb.close()
    rx = box["rx"]
    assert got == BLOCKS[:5] == rx.blocks  # nothing accepted was lost
    assert rx.ended_by in ("error", "duration")


def test_socket_peer_gone_sender_gives_up():
    """B never answers (nobody on the other side of the relay): A gives up
    on each block after max_attempts and says so."""
    with SocketRelay() as url:
        silent = open_port(url)  # a peer that reads nothing and says nothing
        pa = open_port(url)
        try:
            reports, stats = run_sender(pa, BLOCKS[:2], syn_timeout_ms=30, answer_timeout_ms=30,
                                        max_attempts=2)
        finally:
            pa.close()
            silent.close()
    assert [r.outcome for r in reports] == ["gave up", "gave up"]
    assert stats["gave_up"] == 2 and stats["timeouts"] == 4


def test_cli_link_test_sim(capsys):
    rc = cli_main(["link-test", "--blocks", "300", "--ber", "1e-3", "--seed", "3", "--json"])
    assert rc == 0
    import json

    out = json.loads(capsys.readouterr().out)
    assert out["blocks"] == 300 and out["engine"] == "c"
    assert out["delivered_unique"] + out["undetected_errors"] + out["duplicates"] == out["accepted_by_B"]
    rc = cli_main(["link-test", "--blocks", "20", "--sender", "python", "--reboot", "0.05:receiver"])
    assert rc == 0
    assert cli_main(["link-test", "--blocks", "5", "--dead", "oops"]) == 2


def test_cli_rx_tx_processes_over_pty():
    """`attitude link-rx` and `attitude link-tx` as separate processes on a
    pty pair: tx reads hex lines from stdin, rx prints them back."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    lines = [b.hex(" ") for b in BLOCKS[:6]]
    with PtyPair() as (p0, p1):
        rx = subprocess.Popen([sys.executable, "-m", "attitude_c", "link-rx", "--port", p1, "--count", "6",
                               "--impl", "python", "--gap-timeout-ms", str(GAP_MS), "--duration", "30"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
        try:
            # wait (bounded) until rx has its tty open
            ready = select.select([rx.stderr], [], [], 30)[0]
            assert ready and b"listening" in rx.stderr.readline()
            tx = subprocess.run([sys.executable, "-m", "attitude_c", "link-tx", "--port", p0,
                                 "--syn-timeout-ms", "1000", "--answer-timeout-ms", "1000"],
                                input="\n".join(lines) + "\n", check=False, capture_output=True, text=True,
                                env=env, timeout=60)
            out, err = rx.communicate(timeout=60)
        finally:
            if rx.poll() is None:
                rx.kill()
                rx.communicate()
    assert tx.returncode == 0, tx.stderr
    assert tx.stdout.count(": accepted after 1 attempt(s)") == 6
    assert rx.returncode == 0, err
    assert out.decode().splitlines() == lines
    assert b'"blocks_accepted": 6' in err


def test_cli_tx_rejects_bad_hex():
    with PtyPair() as (p0, _p1):
        proc = subprocess.run([sys.executable, "-m", "attitude_c", "link-tx", "--port", p0],
                              input="zz zz\n", check=False, capture_output=True, text=True, timeout=60,
                              env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.returncode == 2
    assert "stdin line 1: not hex" in proc.stderr


def test_other_pyserial_urls_loop_and_spy(tmp_path):
    """loop:// opens at 9600 8N1 and echoes; spy:// wraps a real pty and logs
    the exchange (the transport takes any pyserial URL)."""
    port = open_port("loop://")
    try:
        assert (port.baudrate, port.bytesize, port.parity, port.stopbits) == (9600, 8, "N", 1)
        port.write(b"\xaa\x55")
        assert port.read(2) == b"\xaa\x55"
    finally:
        port.close()
    log = tmp_path / "spy.txt"
    with PtyPair() as (p0, p1):
        _reports, _stats, rx = _exchange(f"spy://{p0}?file={log}", p1, "c", "c", BLOCKS[:3])
    assert rx.blocks == BLOCKS[:3]
    text = log.read_text().upper()
    assert "AA" in text and "BB" in text  # the handshake bytes in the hexdump


# -- a sender whose receiver starts late (issue 11, section 3) -------------


def _tx_in_thread(argv: list[str]) -> tuple[threading.Thread, dict]:
    """`attitude link-tx ARGV` in a thread (no interpreter start-up to race
    against); the box gets its exit status."""
    box: dict = {}
    th = threading.Thread(target=lambda: box.setdefault("rc", cli_main(["link-tx", *argv])), daemon=True)
    th.start()
    return th, box


def _wait_for(cond, timeout: float, what: str) -> None:
    t_end = time.monotonic() + timeout
    while not cond():
        assert time.monotonic() < t_end, f"timed out waiting for {what}"
        time.sleep(0.01)


def test_cli_tx_waits_for_a_receiver_that_starts_late(capsys):
    """`link-tx --block-size 6 --count 5` started before its receiver: by
    default it keeps offering block 0 until B answers, then sends all five;
    nothing is given up (today's main gave up on every block)."""
    with PtyPair() as (p0, p1):
        th, box = _tx_in_thread(["--port", p0, "--block-size", "6", "--count", "5", "--generate"])
        try:
            # let A run through more than max_attempts (5) unanswered handshakes first
            time.sleep(0.6)
            pb = open_port(p1)
            try:
                rx = run_receiver(pb, count=5, duration=30, gap_timeout_ms=GAP_MS)
            finally:
                th.join(timeout=30)
                pb.close()
        finally:
            assert not th.is_alive(), "link-tx did not finish"
    cap = capsys.readouterr()
    assert box["rc"] == 0, cap.err
    assert cap.out.count(": accepted after") == 5
    assert '"gave_up": 0' in cap.err
    assert len(rx.blocks) == 5
    # more than 5 attempts of 50 ms went unanswered before B opened its port
    assert json_stats(cap.err)["timeouts"] >= 5


def json_stats(err: str) -> dict:
    import json

    line = next(ln for ln in err.splitlines() if ln.startswith("link-tx stats: "))
    return json.loads(line[len("link-tx stats: "):])


def test_run_sender_wait_runs_out_and_reports_no_receiver():
    """Nobody on the other side: with a bounded wait A offers block 0, says
    every `waiting_every` seconds that it waits, and stops with the block
    reported "no receiver" (not given up, nothing counted as gave_up)."""
    notes: list[float] = []
    with PtyPair() as (p0, _p1):
        pa = open_port(p0)
        try:
            t0 = time.monotonic()
            reports, stats = run_sender(pa, BLOCKS[:3], syn_timeout_ms=30, answer_timeout_ms=30, max_attempts=2,
                                        wait_first=0.8, waiting_every=0.25, on_waiting=notes.append)
            dt = time.monotonic() - t0
        finally:
            pa.close()
    assert [(r.index, r.outcome) for r in reports] == [(0, "no receiver")]
    assert stats["gave_up"] == 0 and stats["timeouts"] >= 5  # 0.8 s of 30 ms waits, far above 2 attempts
    assert 0.8 <= dt < 5.0
    assert len(notes) >= 2 and notes == sorted(notes)


def test_cli_tx_wait_limit_exit_status(capsys):
    with PtyPair() as (p0, _p1):
        rc = cli_main(["link-tx", "--port", p0, "--generate", "--count", "2", "--wait", "0.3"])
    err = capsys.readouterr().err
    assert rc == 4
    assert "no handshake from the receiver in 0.3 s: block 0" in err


def _answer_first_block_then_go_silent(url: str) -> tuple[threading.Thread, Any]:
    """A receiver B that accepts one block and then stays on the line, deaf."""
    pb = open_port(url)
    th = threading.Thread(target=lambda: run_receiver(pb, count=1, duration=30, gap_timeout_ms=GAP_MS),
                          daemon=True)
    th.start()
    return th, pb


@pytest.mark.parametrize("policy", ["fail", "skip"])
def test_cli_tx_give_up_after_the_handshake(policy, capsys):
    """After B has answered once, a give-up is a real loss: by default
    link-tx stops with exit status 3 naming the block; with
    `--on-give-up skip` it reports the block and goes on."""
    with PtyPair() as (p0, p1):
        peer, pb = _answer_first_block_then_go_silent(p1)
        try:
            rc = cli_main(["link-tx", "--port", p0, "--generate", "--count", "3", "--max-attempts", "2",
                           "--syn-timeout-ms", "1000", "--answer-timeout-ms", "1000", "--on-give-up", policy])
            peer.join(timeout=30)
        finally:
            pb.close()
    cap = capsys.readouterr()
    assert "block 0 " in cap.out and ": accepted after 1 attempt(s)" in cap.out
    if policy == "fail":
        assert rc == 3
        assert "gave up on block 1 " in cap.err
        assert "block 2 " not in cap.out  # nothing sent after the lost block
        assert json_stats(cap.err)["gave_up"] == 1
    else:
        assert rc == 0
        assert "block 1 " in cap.out and "block 2 " in cap.out
        assert cap.out.count(": gave up after 2 attempt(s)") == 2
        assert "skipped 2 block(s) given up: 1, 2" in cap.err
