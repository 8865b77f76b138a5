"""Link v2 over real byte streams: all four pairings of C and Python ends over
a pty pair and over ``socket://`` (attitude_c.link.transport2), a lossy
paced bridge, and back-pressure from a slow consumer."""

from __future__ import annotations

import itertools
import json
import subprocess
import sys
import threading

import pytest

from attitude_c.link import ChannelConfig
from attitude_c.link.sim2 import record
from attitude_c.link.transport import PtyPair, SocketRelay, open_port
from attitude_c.link.transport2 import run_receiver2, run_sender2

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
