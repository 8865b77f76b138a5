"""Link v2 over real byte streams: all four pairings of C and Python ends over
a pty pair and over ``socket://`` (attitude_c.link.transport2), a lossy
paced bridge, and back-pressure from a slow consumer."""

from __future__ import annotations

import itertools
import json
import subprocess
import sys
import threading
from typing import Any

import pytest

from attitude_c.link import ChannelConfig
from attitude_c.link.sim2 import record
from attitude_c.link.transport import PtyPair, SocketRelay, open_port
from attitude_c.link.transport2 import run_receiver2, run_sender2

pytestmark = pytest.mark.system  # runs link v2 ends over pty pairs in processes

PAIRS = list(itertools.product(("c", "python"), ("c", "python")))
PAIR_IDS = [f"{a}-to-{b}" for a, b in PAIRS]


def _exchange(url_a: str, url_b: str, impl_a: str, impl_b: str, n: int, **rx_kw):
    recs = [record(i, 40) for i in range(n)]
    box: dict = {}
    stop = threading.Event()
    pb = open_port(url_b)
    th = threading.Thread(target=lambda: box.setdefault("rx", run_receiver2(pb, impl=impl_b, stop=stop, **rx_kw)),
                          daemon=True)
    th.start()
    pa = open_port(url_a)
    try:
        rep = run_sender2(pa, recs, impl=impl_a, timeout=60)
    finally:
        stop.set()
        th.join(timeout=5)
        pa.close()
        pb.close()
    return recs, rep, box["rx"]


@pytest.mark.parametrize(("impl_a", "impl_b"), PAIRS, ids=PAIR_IDS)
def test_pty_all_pairings(impl_a: str, impl_b: str) -> None:
    with PtyPair() as (pa, pb):
        recs, rep, rx = _exchange(pa, pb, impl_a, impl_b, 400)
    assert rep.ended_by == "done" and rep.acknowledged == 400
    assert rx.records == recs


@pytest.mark.parametrize(("impl_a", "impl_b"), PAIRS, ids=PAIR_IDS)
def test_socket_all_pairings(impl_a: str, impl_b: str) -> None:
    with SocketRelay() as url:
        recs, rep, rx = _exchange(url, url, impl_a, impl_b, 300)
    assert rep.ended_by == "done" and rep.acknowledged == 300
    assert rx.records == recs


def test_lossy_paced_bridge_exactly_once() -> None:
    # 9600 baud, BER 1e-3 and dropped/inserted bytes both ways: every record once, in order
    ch = ChannelConfig(ber=1e-3, drop=1e-3, insert=1e-3, seed=2)
    with PtyPair(baud=9600, channel=ch) as (pa, pb):
        recs, rep, rx = _exchange(pa, pb, "c", "c", 120)
    assert rep.ended_by == "done", rep.error
    assert rx.records == recs


def test_slow_consumer_back_pressure() -> None:
    """The caller takes a record every 5 ms and has room for 4: B acknowledges only
    what it hands over, A waits, nothing is lost or doubled."""
    taken: list[bytes] = []
    backlog: list[bytes] = []
    lock = threading.Lock()
    done = threading.Event()

    def consume() -> None:
        while not done.is_set():
            with lock:
                if backlog:
                    taken.append(backlog.pop(0))
            done.wait(0.005)

    def on_record(rec: bytes) -> None:
        with lock:
            backlog.append(rec)

    def room() -> int:
        with lock:
            return 4 - len(backlog)

    th = threading.Thread(target=consume, daemon=True)
    th.start()
    with PtyPair() as (pa, pb):
        recs, rep, rx = _exchange(pa, pb, "c", "c", 150, on_record=on_record, room=room, keep_records=False)
    done.wait(0.2)
    done.set()
    th.join(timeout=2)
    assert rep.ended_by == "done"
    assert taken + backlog == recs
    assert rx.stats["refused"] >= 0


def _cli(*args: str, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "attitude_c", *args], capture_output=True, text=True, check=False,
                          timeout=120, **kw)


def test_cli_link_test_v2() -> None:
    proc = _cli("link-test", "--protocol", "v2", "--blocks", "3000", "--ber", "1e-3", "--drop", "1e-3",
                "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert (out["corrupt"], out["duplicates"], out["lost"], out["delivered"]) == (0, 0, 0, 3000)
    proc = _cli("link-test", "--protocol", "v2", "--reboot", "1:sender", "--reboot", "2:sender")
    assert proc.returncode == 2 and "at most one --reboot" in proc.stderr


def test_cli_tx_rx_v2_over_pty() -> None:
    with PtyPair() as (pa, pb):
        rx = subprocess.Popen([sys.executable, "-m", "attitude_c", "link-rx", "--protocol", "v2", "--port", pb,
                               "--count", "50", "--decode", "--impl", "python"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        tx = _cli("link-tx", "--protocol", "v2", "--port", pa, "--generate", "--count", "50", "--wait", "60")
        out, err = rx.communicate(timeout=60)
    assert tx.returncode == 0, tx.stderr
    assert "50 of 50 record(s) acknowledged" in tx.stdout
    assert rx.returncode == 0, err
    lines = [json.loads(x) for x in out.splitlines()]
    assert len(lines) == 50 and all("codes" in x and "error" not in x for x in lines)


@pytest.mark.parametrize("protocol", ["v2", "legacy"])
def test_cli_rx_auto_hears_either_protocol(protocol: str) -> None:
    """`link-rx --protocol auto` and a sender of either protocol (hex lines on stdin): every
    record printed once, in order, from the first one (the frame or block that names the
    protocol is answered, not just recognised)."""
    import select

    recs = [record(i) for i in range(40)]
    lines = [r.hex(" ") for r in recs]
    with PtyPair() as (pa, pb):
        rx = subprocess.Popen([sys.executable, "-m", "attitude_c", "link-rx", "--protocol", "auto", "--port", pb,
                               "--count", "40", "--impl", "python", "--gap-timeout-ms", "1000", "--duration", "60"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            assert select.select([rx.stderr], [], [], 30)[0] and "legacy or link v2" in rx.stderr.readline()
            extra = ["--wait", "60"] if protocol == "v2" else ["--syn-timeout-ms", "1000", "--answer-timeout-ms", "1000"]
            tx = _cli("link-tx", "--protocol", protocol, "--port", pa, "--impl", "python", *extra,
                      input="\n".join(lines) + "\n")
            out, err = rx.communicate(timeout=60)
        finally:
            if rx.poll() is None:
                rx.kill()
                rx.communicate()
    assert tx.returncode == 0, tx.stderr
    assert rx.returncode == 0, err
    assert out.splitlines() == lines, err
    assert f"the sender speaks {'link v2' if protocol == 'v2' else 'the legacy protocol'}" in err


def test_listen_auto_undecodable_legacy_block_decides_nothing() -> None:
    """listen_auto: a legacy block whose record does not decode (as a v2 frame's bytes may pass
    the 8-bit sum) is handed on as the legacy link would, but names no protocol: the v2 SYN
    after it does, and run_receiver2 goes on with the same receiver: all records, in order."""
    import time

    from attitude_c.link import make_sender
    from attitude_c.link.protocol import Result
    from attitude_c.link.transport2 import listen_auto, run_receiver2, run_sender2

    recs = [record(i) for i in range(5)]
    bad = bytes([0xF1, 0x23, 0x45, 0x67, 0x89, 0xAB])  # codes above 4095: not a record
    box: dict[str, Any] = {}
    blocks: list[bytes] = []

    def receive(port: Any) -> None:
        heard = listen_auto(port, impl="python", on_block=blocks.append, duration=30)
        box["protocol"] = heard.protocol
        box["rep"] = run_receiver2(heard.port, impl="python", receiver=heard.v2, count=5, duration=30)

    with PtyPair() as (pa, pb):
        port_a, port_b = open_port(pa, 9600), open_port(pb, 9600)
        t = threading.Thread(target=receive, args=(port_b,))
        t.start()
        try:
            tx = make_sender("python", block_size=6, syn_timeout=1000, answer_timeout=1000)
            t0 = time.monotonic()

            def tick() -> int:
                return int((time.monotonic() - t0) * 1000) & 0xFFFF

            tx.start(bad, tick())
            port_a.timeout = 0.01
            while time.monotonic() - t0 < 20:
                res, byte = tx.poll(tick())
                if res == Result.SEND:
                    port_a.write(bytes([byte]))
                elif res == Result.IDLE:
                    break
                else:
                    for b in port_a.read(16):
                        tx.sink(b, tick())
            assert tx.stats.blocks_accepted == 1 and blocks == [bad]
            sent = run_sender2(port_a, recs, impl="python", timeout=20)
            t.join(30)
        finally:
            port_a.close()
            port_b.close()
    assert sent.acknowledged == 5
    assert box["protocol"] == "v2"
    assert box["rep"].records == recs
