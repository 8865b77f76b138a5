"""The serial link (attitude_c.link): byte-exact transcripts in all four
pairings of C and Python ends, the channel simulator and the fast C path,
the lossy-channel figures, property tests of the receiver and argument
checks. Real ttys and sockets are in test_link_serial.py."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from attitude_c.errors import InvalidArgument, InvalidType
from attitude_c.link import (
    OUTCOME_ACKED,
    ChannelConfig,
    CReceiver,
    CSender,
    LinkBusy,
    Receiver,
    Result,
    Sender,
    checksum,
    make_receiver,
    make_sender,
    simulate_link,
)

PAIRS = list(itertools.product(("c", "python"), ("c", "python")))
PAIR_IDS = [f"{a}-to-{b}" for a, b in PAIRS]
BLK = bytes([0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC])
CK = 0x6A  # 0x12+0x34+0x56+0x78+0x9A+0xBC = 0x26A


class Rig:
    """Lock-step wire: one tick per byte time, each end hands out at most one
    byte per tick, a byte handed out at tick t arrives at t+1. ``faults``
    maps (direction, k) -> "drop" or an XOR mask for the k-th byte handed
    out in that direction (0 = A->B, 1 = B->A)."""

    def __init__(self, s_impl: str, r_impl: str, n: int = 6, faults=None,
                 syn=20, answer=20, gap=5, attempts=3) -> None:
        self.a = make_sender(s_impl, block_size=n, syn_timeout=syn, answer_timeout=answer,
                             max_attempts=attempts)
        self.b = make_receiver(r_impl, block_size=n, gap_timeout=gap)
        self.faults = faults or {}
        self.logs: list[list[int]] = [[], []]
        self.q: list[list[int]] = [[], []]
        self.events: list[tuple[str, object]] = []
        self.t = 0

    def _hand(self, d: int, byte: int) -> None:
        k = len(self.logs[d])
        self.logs[d].append(byte)
        f = self.faults.get((d, k))
        if f == "drop":
            return
        self.q[d].append(byte ^ (f or 0))

    def tick(self) -> None:
        t = self.t
        qa, qb = self.q
        self.q = [[], []]
        for x in qa:
            r = self.b.sink(x, t)
            if r in (Result.ACCEPTED, Result.REJECTED):
                self.events.append(("B", r.name, self.b.block if r is Result.ACCEPTED else None))
        for x in qb:
            r = self.a.sink(x, t)
            if r in (Result.ACCEPTED, Result.REJECTED):
                self.events.append(("A", r.name))
        while True:
            r, o = self.a.poll(t)
            if r is Result.SEND:
                self._hand(0, o)
                break
            if r in (Result.NONE, Result.IDLE):
                break
            self.events.append(("A", r.name))
        while True:
            r, o = self.b.poll(t)
            if r is Result.SEND:
                self._hand(1, o)
                break
            if r in (Result.NONE, Result.IDLE):
                break
            self.events.append(("B", r.name))
        self.t += 1

    def run(self, limit: int = 400) -> None:
        for _ in range(limit):
            self.tick()
            if self.a.idle and not self.q[0] and not self.q[1]:
                return
        raise AssertionError("sender did not finish")

    def send(self, block: bytes, limit: int = 400) -> None:
        self.a.start(block, self.t)
        self.run(limit)


def frame(block: bytes) -> list[int]:
    return [0xAA, *block, checksum(block)]


@pytest.mark.parametrize("s_impl,r_impl", PAIRS, ids=PAIR_IDS)
class TestTranscripts:
    def test_normal(self, s_impl, r_impl):
        rig = Rig(s_impl, r_impl)
        rig.send(BLK)
        assert rig.logs[0] == [0xAA, 0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, CK]
        assert rig.logs[1] == [0xBB, 0x00]
        assert rig.events == [("B", "ACCEPTED", BLK), ("A", "ACCEPTED")]
        assert rig.a.stats.as_dict() == {"blocks_sent": 1, "blocks_accepted": 1, "naks": 0, "timeouts": 0,
                                             "gave_up": 0, "bytes_discarded": 0, "retries": 0}
        assert rig.b.stats.as_dict() == {"syns": 1, "blocks_accepted": 1, "naks": 0, "timeouts": 0, "resyncs": 0,
                                             "bytes_discarded": 0}

    def test_corrupted_block_is_resent_from_syn(self, s_impl, r_impl):
        rig = Rig(s_impl, r_impl, faults={(0, 3): 0x01})
        rig.send(BLK)
        assert rig.logs[0] == frame(BLK) * 2
        assert rig.logs[1] == [0xBB, 0xFF, 0xBB, 0x00]
        assert [e[:2] for e in rig.events] == [("B", "REJECTED"), ("A", "REJECTED"),
                                               ("B", "ACCEPTED"), ("A", "ACCEPTED")]
        assert rig.a.stats.naks == 1 and rig.b.stats.naks == 1

    def test_two_bit_error_accepted_undetected(self, s_impl, r_impl):
        # bit 1 of 0x12 (-2) and of 0x34 (+2): same sum, B accepts a wrong block
        rig = Rig(s_impl, r_impl, faults={(0, 1): 0x02, (0, 2): 0x02})
        rig.send(BLK)
        assert rig.events[0] == ("B", "ACCEPTED", bytes([0x10, 0x36]) + BLK[2:])

    def test_lost_syn_ack(self, s_impl, r_impl):
        rig = Rig(s_impl, r_impl, faults={(1, 0): "drop"})
        rig.send(BLK)
        assert rig.logs[0] == [0xAA] + frame(BLK)
        assert rig.logs[1] == [0xBB, 0xBB, 0x00]
        # A timed out waiting for 0xBB; B had already dropped the block it opened
        assert ("A", "TIMEOUT") in rig.events and ("B", "TIMEOUT") in rig.events
        assert rig.a.stats.timeouts == 1 and rig.b.stats.timeouts == 1

    def test_lost_answer_gives_duplicate(self, s_impl, r_impl):
        rig = Rig(s_impl, r_impl, faults={(1, 1): "drop"})
        rig.send(BLK)
        assert rig.logs[0] == frame(BLK) * 2
        assert rig.logs[1] == [0xBB, 0x00, 0xBB, 0x00]
        accepted = [e for e in rig.events if e[:2] == ("B", "ACCEPTED")]
        assert len(accepted) == 2  # the duplicate the protocol cannot see

    def test_garbage_before_syn(self, s_impl, r_impl):
        rig = Rig(s_impl, r_impl)
        rig.q[0] = [0x00, 0xBB, 0x55]  # noise reaches B at tick 0
        rig.tick()
        rig.send(BLK)
        assert rig.logs[1] == [0xBB, 0x00]
        assert rig.b.stats.bytes_discarded == 3 and rig.b.stats.resyncs == 1
        assert rig.events[0] == ("B", "ACCEPTED", BLK)

    def test_syn_inside_data_is_data(self, s_impl, r_impl):
        blk = bytes([0xAA, 0xAA, 0x00, 0xAA, 0xFF, 0xBB])
        rig = Rig(s_impl, r_impl)
        rig.send(blk)
        assert rig.logs[0] == [0xAA, *blk, 0xB8]  # 3*0xAA + 0xFF + 0xBB = 0x3B8
        assert rig.events[0] == ("B", "ACCEPTED", blk)
        assert rig.b.stats.syns == 1

    def test_truncated_block_then_recovery(self, s_impl, r_impl):
        # A (re)boots after 3 data bytes: B drops the partial block after
        # its gap timeout and answers the next 0xAA at once
        rig = Rig(s_impl, r_impl)
        rig.a.start(BLK, rig.t)
        for _ in range(5):
            rig.tick()
        assert rig.logs[0] == [0xAA, 0x12, 0x34, 0x56]
        rig.a.reset()
        rig.q[0] = []  # the byte in flight dies with the reboot
        for _ in range(10):
            rig.tick()
        other = bytes(range(1, 7))
        rig.send(other)
        assert rig.logs[0] == [0xAA, 0x12, 0x34, 0x56] + frame(other)
        assert rig.logs[1] == [0xBB, 0xBB, 0x00]
        assert rig.b.stats.timeouts == 1 and rig.b.stats.bytes_discarded == 2
        assert [e for e in rig.events if e[0] == "B"] == [("B", "TIMEOUT"), ("B", "ACCEPTED", other)]

    def test_receiver_reboot_mid_block(self, s_impl, r_impl):
        rig = Rig(s_impl, r_impl)
        rig.a.start(BLK, rig.t)
        for _ in range(4):
            rig.tick()
        rig.b.reset()  # B loses the data byte it had (d1); d2 is on the wire
        rig.run()
        # A finishes the frame into an idle B (discarded), waits for the answer
        # timeout (20 ticks), starts again from 0xAA
        assert rig.logs[0] == frame(BLK) * 2
        assert rig.logs[1] == [0xBB, 0xBB, 0x00]
        assert rig.a.stats.timeouts == 1
        assert rig.b.stats.bytes_discarded == 6  # d2..d6 + checksum of the cut frame
        assert rig.b.stats.resyncs == 1  # the next 0xAA came after discarded bytes
        assert rig.events[-1] == ("A", "ACCEPTED")

    def test_give_up_after_max_attempts(self, s_impl, r_impl):
        rig = Rig(s_impl, r_impl, faults={(0, k): "drop" for k in range(50)}, attempts=3)
        rig.send(BLK)
        assert rig.logs[0] == [0xAA] * 3
        assert [e for e in rig.events if e[0] == "A"] == [("A", "TIMEOUT")] * 3 + [("A", "GAVE_UP")]
        assert rig.a.stats.gave_up == 1 and rig.a.stats.retries == 2


def test_tick_wraparound_same_in_c_and_python():
    for impl in ("c", "python"):
        s = make_sender(impl, syn_timeout=10)
        s.start(BLK, 65530)
        assert s.poll(65530) == (Result.SEND, 0xAA)
        assert s.ticks_left(65530) == 11
        assert s.poll(65536 + 4) == (Result.NONE, None)  # 10 ticks elapsed across the wrap
        assert s.sink(0xBB, 65536 + 5) is Result.DISCARDED  # 11 elapsed: too late
        assert s.poll(65536 + 5) == (Result.TIMEOUT, None)


# -- simulator ---------------------------------------------------------------

FAULTY = ChannelConfig(ber=3e-3, drop=0.01, insert=0.01, duplicate=0.01, dead=[(0.5, 0.2)], seed=5)
REBOOTS = [(1.0, "sender"), (1.5, "receiver")]


def _blocks(n: int, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (n, 6), dtype=np.uint8)


def test_clean_line_reaches_theoretical_rate():
    run = simulate_link(_blocks(500))
    # one exchange = 0xAA, 0xBB, 6 data, checksum, answer = 10 bytes x 10 bits
    assert run.duration == pytest.approx(500 * 100 / 9600, abs=1e-12)
    assert np.array_equal(run.accepted, run.blocks)
    assert np.array_equal(run.accepted_index, np.arange(500))
    assert (run.outcome == OUTCOME_ACKED).all()


@pytest.mark.parametrize("s_impl,r_impl", PAIRS, ids=PAIR_IDS)
def test_all_pairings_identical_to_fast_path_on_faulty_line(s_impl, r_impl):
    blocks = _blocks(150)
    fast = simulate_link(blocks, channel=FAULTY, reboots=REBOOTS)
    slow = simulate_link(blocks, channel=FAULTY, reboots=REBOOTS, sender=s_impl, receiver=r_impl,
                         engine="python")
    # same channel faults (same seed), same event order: every end must behave identically
    assert np.array_equal(slow.accepted, fast.accepted)
    assert np.array_equal(slow.accepted_index, fast.accepted_index)
    assert np.array_equal(slow.outcome, fast.outcome)
    assert slow.sender_stats == fast.sender_stats
    assert slow.receiver_stats == fast.receiver_stats
    assert slow.channel_stats == fast.channel_stats
    assert slow.duration == fast.duration
    # and the faults really happened
    assert fast.sender_stats["naks"] > 0 and fast.sender_stats["timeouts"] > 0
    assert fast.receiver_stats["resyncs"] > 0
    assert len(fast.lost_to_reboot) == 1
    assert fast.channel_stats["a_to_b"]["dead"] > 0


def test_dead_line_gives_up_then_recovers():
    blocks = _blocks(200)
    run = simulate_link(blocks, channel=ChannelConfig(dead=[(0.5, 1.0)]))
    gave_up = run.gave_up
    # 5 attempts x ~52 ms fit in the 1 s outage ~4 times
    assert 1 <= len(gave_up) <= 6
    assert (run.outcome[gave_up[-1] + 1:] == OUTCOME_ACKED).all()
    assert run.correct.all()


def test_lossy_channel_10000_blocks_ber_1e3(capsys):
    """Every block B accepted matches what A sent, or is counted as an
    undetected error; duplicates (lost 0x00) are counted too."""
    blocks = _blocks(10_000, seed=42)
    run = simulate_link(blocks, channel=ChannelConfig(ber=1e-3, seed=2027))
    s = run.summary()
    with capsys.disabled():
        print(f"\n10,000 blocks at BER 1e-3: {s['undetected_errors']} undetected errors, "
              f"{s['duplicates']} duplicates, {s['gave_up']} gave up, "
              f"{s['blocks_per_s']:.1f} blocks/s")
    correct = run.correct
    dup = run.duplicate
    # bookkeeping: accepted = correct first copies + duplicates + undetected errors
    assert len(run.accepted) == s["delivered_unique"] + s["duplicates"] + s["undetected_errors"]
    # exact counts for this seed (deterministic: splitmix64 channel, IEEE arithmetic)
    assert s["undetected_errors"] == int(np.count_nonzero(~correct)) == 2
    assert s["duplicates"] == int(np.count_nonzero(dup)) == 82
    assert s["gave_up"] == 0
    assert s["acked"] == 10_000
    # A got 0x00 for the two wrong blocks, so their true content never arrived
    assert s["delivered_unique"] == 10_000 - 2
    # the accepted-but-wrong blocks are really different from what A sent
    bad = ~correct
    assert (run.accepted[bad] != blocks[run.accepted_index[bad]]).any(axis=1).all()
    assert (run.accepted[bad].sum(axis=1) % 256 == blocks[run.accepted_index[bad]].sum(axis=1) % 256).all()


def test_simulate_link_arguments():
    with pytest.raises(InvalidArgument, match="blocks must be 2-D"):
        simulate_link(np.zeros(6, dtype=np.uint8))
    with pytest.raises(InvalidType, match="blocks must hold integers"):
        simulate_link(np.zeros((2, 6)))
    with pytest.raises(InvalidArgument, match="byte values"):
        simulate_link(np.full((2, 6), 300))
    with pytest.raises(InvalidArgument, match="block size must be 1..64"):
        simulate_link(np.zeros((2, 65), dtype=np.uint8))
    with pytest.raises(InvalidArgument, match="ber"):
        simulate_link(_blocks(2), channel=ChannelConfig(ber=float("nan")))
    with pytest.raises(InvalidArgument, match="drop"):
        simulate_link(_blocks(2), channel=ChannelConfig(drop=1.5))
    with pytest.raises(InvalidArgument, match="syn_timeout_ms"):
        simulate_link(_blocks(2), syn_timeout_ms=10_000)
    with pytest.raises(InvalidArgument, match="engine='c'"):
        simulate_link(_blocks(2), sender="python", engine="c")
    with pytest.raises(InvalidArgument, match="reboot side"):
        simulate_link(_blocks(2), reboots=[(0.1, "both")])
    # lists of bytes work too
    run = simulate_link([BLK, BLK[::-1]])
    assert run.accepted.tobytes() == BLK + BLK[::-1]


def test_ends_argument_errors():
    for cls in (Sender, CSender):
        with pytest.raises(InvalidArgument, match="block_size"):
            cls(block_size=0)
        with pytest.raises(InvalidArgument, match="syn_timeout"):
            cls(syn_timeout=40000)
        with pytest.raises(InvalidType, match="max_attempts"):
            cls(max_attempts=2.5)
        s = cls()
        with pytest.raises(InvalidArgument, match="block must have 6 bytes"):
            s.start(b"abc", 0)
        s.start(BLK, 0)
        with pytest.raises(LinkBusy):
            s.start(BLK, 0)
        with pytest.raises(InvalidArgument, match="byte"):
            s.sink(256, 0)
    for cls in (Receiver, CReceiver):
        with pytest.raises(InvalidArgument, match="gap_timeout"):
            cls(gap_timeout=0)
        with pytest.raises(InvalidArgument, match="byte"):
            cls().sink(-1, 0)


# -- properties of the receiver ----------------------------------------------

stream = st.lists(st.tuples(st.integers(0, 300), st.sampled_from([0xAA, 0xBB, 0x00, 0xFF]) | st.integers(0, 255),
                            st.booleans()), max_size=200)


@settings(max_examples=150, deadline=None)
@given(n=st.integers(1, 64), gap=st.integers(1, 400), events=stream)
def test_receiver_c_and_python_agree_and_never_stick(n, gap, events):
    c, p = CReceiver(block_size=n, gap_timeout=gap), Receiver(block_size=n, gap_timeout=gap)
    t = 0
    for dt, byte, poll in events:
        t += dt
        assert c.sink(byte, t) == p.sink(byte, t)
        assert c._r.index <= n  # never writes past the caller's buffer
        if poll:
            for _ in range(4):
                rc, rp = c.poll(t), p.poll(t)
                assert rc == rp
                if rc[0] in (Result.NONE, Result.IDLE):
                    break
            else:
                raise AssertionError("poll did not settle within 4 calls")
        assert c.ticks_left(t) == p.ticks_left(t)
    assert c.stats == p.stats
    assert c.block == p.block
    # bounded return to idle: n + 1 bytes end any block (a 0xAA inside is data)
    for _ in range(n + 1):
        c.sink(0x00, t)
        while c.poll(t)[0] not in (Result.NONE, Result.IDLE):
            pass
    assert c.poll(t) == (Result.IDLE, None)
    # and so does silence longer than the gap timeout
    c.sink(0xAA, t)
    c.poll(t)
    assert c.poll(t + gap + 1) == (Result.TIMEOUT, None)
    assert c.poll(t + gap + 1) == (Result.IDLE, None)


@settings(max_examples=100, deadline=None)
@given(n=st.integers(1, 8), events=stream)
def test_sender_c_and_python_agree(n, events):
    c = CSender(block_size=n, syn_timeout=50, answer_timeout=30, max_attempts=3)
    p = Sender(block_size=n, syn_timeout=50, answer_timeout=30, max_attempts=3)
    blk = bytes(range(7, 7 + n))
    t = 0
    for dt, byte, poll in events:
        t += dt
        assert c.sink(byte, t) == p.sink(byte, t)
        if poll:
            for _ in range(80):
                rc, rp = c.poll(t), p.poll(t)
                assert rc == rp
                if rc[0] is Result.IDLE:
                    c.start(blk, t)
                    p.start(blk, t)
                elif rc[0] is Result.NONE:
                    break
        assert c.ticks_left(t) == p.ticks_left(t)
    assert c.stats == p.stats
