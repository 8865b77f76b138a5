"""Link v2 (attitude/link2.h, attitude_c.link.v2): the spec-written Python
ends against the C machines (byte for byte, all four pairings, through a
faulty channel), the framing pieces against their definitions, delivery
exactly once and in order under every channel fault, back-pressure, reboots,
and "never gets stuck" properties (hypothesis). The legacy protocol's own
tests are in test_link.py, untouched."""

from __future__ import annotations

import itertools

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from attitude_c.errors import InvalidArgument, LinkBusy
from attitude_c.link import (
    ChannelConfig,
    CReceiver2,
    CSender2,
    Receiver2,
    Result2,
    Sender2,
    simulate_link2,
)
from attitude_c.link.sim2 import record
from attitude_c.link.v2 import (
    crc32c,
    make_frame,
    pack_samples,
    rcobs_decode,
    rcobs_encode,
    unpack_samples,
)

PAIRS = list(itertools.product(("c", "python"), ("c", "python")))
PAIR_IDS = [f"{a}-to-{b}" for a, b in PAIRS]


def test_crc32c_check_value() -> None:
    # the catalogued check value of CRC-32C (iSCSI, RFC 3720): reveng's CRC-32/ISCSI entry
    assert crc32c(b"123456789") == 0xE3069283


@given(st.binary(max_size=600))
def test_rcobs_round_trip_and_no_zero(data: bytes) -> None:
    enc = rcobs_encode(data)
    assert 0 not in enc
    assert rcobs_decode(enc) == data
    # overhead: one code, plus one per 254 bytes without a zero
    assert len(enc) <= len(data) + 1 + len(data) // 254


def test_rcobs_by_hand() -> None:
    # each zero becomes 1 + the bytes since the previous code; the final code closes
    assert rcobs_encode(b"\x11\x00\x00\x22\x33") == b"\x11\x02\x01\x22\x33\x03"
    assert rcobs_encode(b"") == b"\x01"
    assert rcobs_decode(b"\x11\x02\x01\x22\x33\x03") == b"\x11\x00\x00\x22\x33"
    assert rcobs_decode(b"\x05") is None  # a code pointing before the frame
    assert rcobs_decode(b"\x11\xff") is None  # a final code cannot be 0xFF


@given(st.lists(st.tuples(*[st.integers(0, 4095)] * 3), min_size=1, max_size=24))
def test_packing_round_trip(samples: list[tuple[int, int, int]]) -> None:
    recs = [b"".join(c.to_bytes(2, "big") for c in s) for s in samples]
    packed = pack_samples(recs)
    assert len(packed) == (9 * len(recs) + 1) // 2  # three 12-bit codes in 4.5 bytes
    assert unpack_samples(packed, len(recs)) == recs


def test_packing_by_hand() -> None:
    # codes 0xABC, 0x123, 0x456 -> AB C1 23 45 60
    assert pack_samples([bytes([0x0A, 0xBC, 0x01, 0x23, 0x04, 0x56])]) == bytes([0xAB, 0xC1, 0x23, 0x45, 0x60])


def _lockstep(a, b, records: list[bytes], steps: int, room: int = 1000):
    """One byte per direction per step, delivered at once; returns the delivered records
    and the bytes each end handed out."""
    b.set_room(room)
    got: list[bytes] = []
    wire: list[tuple[int, int]] = []
    queue = list(records)
    for t in range(steps):
        while queue and a.room > 0:
            a.push(queue.pop(0))
        r, byte = a.poll(t)
        while r == Result2.TIMEOUT:
            r, byte = a.poll(t)
        if r == Result2.SEND:
            wire.append((0, byte))
            if b.sink(byte) == Result2.DELIVERED:
                got.extend(b.delivered)
        r, byte = b.poll(t)
        if r == Result2.SEND:
            wire.append((1, byte))
            a.sink(byte, t)
    return got, wire


def test_first_frames_by_hand() -> None:
    """The wire from the spec alone: 0x00, SYN(0), 0x00; B: 0x00, ACK(SYNACK, 0, limit), 0x00;
    then one DATA frame of 2 packed samples."""
    a, b = Sender2(ring_size=8), Receiver2()
    recs = [bytes([0x0A, 0xBC, 0x01, 0x23, 0x04, 0x56]), bytes([0x00, 0x01, 0x0F, 0xFF, 0x08, 0x00])]
    got, wire = _lockstep(a, b, recs, 60, room=5)
    a_bytes = bytes(x for d, x in wire if d == 0)
    b_bytes = bytes(x for d, x in wire if d == 1)
    syn = b"\x00" + rcobs_encode(make_frame(0x80, 0)) + b"\x00"
    data = rcobs_encode(make_frame(0x02, 0, pack_samples(recs))) + b"\x00"
    assert a_bytes == syn + b"\x00" + data  # the line was idle before the data frame: a leading 0x00
    synack = b"\x00" + rcobs_encode(make_frame(0xC2, 0, bytes([5]))) + b"\x00"
    ack = b"\x00" + rcobs_encode(make_frame(0xC0, 2, bytes([5]))) + b"\x00"
    assert b_bytes == synack + ack
    assert got == recs
    assert a.pending == 0


@pytest.mark.parametrize(("sender", "receiver"), PAIRS, ids=PAIR_IDS)
def test_lockstep_pairs_match(sender: str, receiver: str) -> None:
    recs = [record(i, 7) for i in range(200)]
    a = (CSender2 if sender == "c" else Sender2)(ring_size=16, max_samples=5, rto=40)
    b = (CReceiver2 if receiver == "c" else Receiver2)()
    got, wire = _lockstep(a, b, recs, 3000)
    _ref_got, ref_wire = _lockstep(CSender2(16, 5, 40), CReceiver2(), recs, 3000)
    assert got == recs
    assert wire == ref_wire


CHANNELS = {
    "ber1e-3": ChannelConfig(ber=1e-3, seed=11),
    "bytes": ChannelConfig(ber=1e-4, drop=2e-3, insert=2e-3, duplicate=1e-3, seed=12),
    "dead": ChannelConfig(ber=1e-4, dead=[(2.0, 3.0)], seed=13),
}


@pytest.mark.parametrize("chan", list(CHANNELS), ids=list(CHANNELS))
def test_python_engine_all_pairs_equal_c_engine(chan: str) -> None:
    """Every pairing, byte for byte, equals the all-C run of the same seed."""
    kw = {"report_every": 37, "queue": 64, "consume_period_s": 0.004, "ring_size": 32}
    ref = simulate_link2(1500, CHANNELS[chan], **kw)
    assert ref.delivered == ref.in_order == ref.offered == 1500
    logs = []
    for sender, receiver in PAIRS:
        log: list[tuple[int, int, int]] = []
        run = simulate_link2(1500, CHANNELS[chan], engine="python", sender=sender, receiver=receiver,
                             log=log, **kw)
        assert run.summary() == ref.summary(), (sender, receiver)
        logs.append(log)
    assert all(log == logs[0] for log in logs)


@pytest.mark.parametrize("ber,n", [(1e-4, 30000), (1e-3, 20000), (1e-2, 1000)])
def test_exactly_once_in_order(ber: float, n: int) -> None:
    ch = ChannelConfig(ber=ber, drop=ber / 10, insert=ber / 10, seed=5)
    run = simulate_link2(n, ch, report_every=50)
    print(f"BER {ber}: {run.summary()}")
    assert (run.corrupt, run.duplicates, run.lost) == (0, 0, 0)
    assert run.delivered == run.in_order == run.acked == n


def test_dead_line_and_reboots() -> None:
    # a line dead for 4 s, then B reboots (its session forgotten), then A reboots (a new session)
    ch = ChannelConfig(ber=1e-4, dead=[(1.0, 4.0)], seed=3)
    run = simulate_link2(3000, ch, period_s=0.006, ring_size=64, max_time_s=40.0)
    assert (run.corrupt, run.duplicates, run.lost, run.delivered) == (0, 0, 0, run.offered)
    run = simulate_link2(3000, ChannelConfig(seed=4), reboot_receiver_s=3.0)
    assert (run.corrupt, run.lost) == (0, 0)
    assert run.receiver["no_session"] >= 1 and run.sender["syns"] >= 2
    assert run.delivered == run.offered  # acknowledged => delivered; the new B may get re-sent records
    run = simulate_link2(3000, ChannelConfig(seed=4), reboot_sender_s=3.0)
    assert run.corrupt == 0 and run.sender["syns"] == 2


def test_back_pressure_acknowledged_is_delivered() -> None:
    """A consumer much slower than the line: B never takes more than its room, A waits
    (window closed, probes), nothing acknowledged is ever dropped."""
    run = simulate_link2(600, ChannelConfig(ber=1e-4, seed=9), queue=8, consume_period_s=0.02)
    assert run.delivered == run.in_order == run.acked == 600
    assert run.receiver["refused"] >= 0 and run.duration >= 600 * 0.02 * 0.9  # paced by the consumer
    b = Receiver2(room=2)
    cb = CReceiver2(room=2)
    frame = make_frame(0x80, 0)
    data = make_frame(0x04, 0, pack_samples([record(i) for i in range(4)]))
    for end in (b, cb):
        for byte in b"\x00" + rcobs_encode(frame) + b"\x00" + rcobs_encode(data) + b"\x00":
            end.sink(byte)
        assert end.stats.records == 2 and end.stats.refused == 2


@settings(max_examples=120, deadline=None)
@given(st.binary(max_size=400), st.integers(0, 300))
def test_receivers_agree_and_never_stick(noise: bytes, room: int) -> None:
    """Any bytes: C and Python receivers give the same result for every byte and the
    same answers; after a delimiter a valid SYN and DATA frame are always taken."""
    ends = (CReceiver2(room=room), Receiver2(room=room))
    for byte in noise:
        results = [e.sink(byte) for e in ends]
        assert results[0] == results[1]
        assert ends[0].delivered == ends[1].delivered
        assert len(ends[0].delivered) <= room
        polls = [e.poll() for e in ends]
        assert polls[0] == polls[1]
    assert ends[0].stats == ends[1].stats
    tail = (b"\x00" + rcobs_encode(make_frame(0x80, 9)) + b"\x00"
            + rcobs_encode(make_frame(0x01, 9, pack_samples([record(1)]))) + b"\x00")
    for e in ends:
        e.set_room(5)
        out = [e.sink(byte) for byte in tail]
        assert out[-1] == Result2.DELIVERED and e.delivered == [record(1)]


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 255), st.integers(0, 400)), max_size=300),
       st.integers(1, 500), st.integers(0, 65535))
def test_senders_agree_and_never_stick(events: list[tuple[int, int]], rto: int, t0: int) -> None:
    """Random bytes from 'B' at random times (the 16-bit tick wraps): the C and Python
    senders answer alike; afterwards a real receiver still gets every record."""
    ends = (CSender2(16, 6, rto), Sender2(16, 6, rto))
    t = t0
    for i in range(10):
        for e in ends:
            e.push(record(i))
    for byte, dt in events:
        t += dt
        assert ends[0].sink(byte, t) == ends[1].sink(byte, t)
        p = [e.poll(t) for e in ends]
        assert p[0] == p[1]
        assert ends[0].ticks_left(t) == ends[1].ticks_left(t)
    assert ends[0].stats == ends[1].stats
    for e in ends:
        b = Receiver2()
        got, _ = _lockstep(_Shift(e, t), b, [], 3000 + 4 * rto)
        # random bytes never make a valid ACK (CRC-32C): all 10 records arrive, once, in order
        assert got == [record(i) for i in range(10)]
        assert e.pending == 0


class _Shift:
    """An end whose ticks continue from t (so lock-step time 0 is t)."""

    def __init__(self, end, t: int) -> None:
        self.end, self.t = end, t

    def __getattr__(self, name: str):
        return getattr(self.end, name)

    def poll(self, tick: int):
        return self.end.poll(self.t + tick)

    def sink(self, byte: int, tick: int = 0):
        return self.end.sink(byte, self.t + tick)


def test_arguments() -> None:
    for cls in (Sender2, CSender2):
        with pytest.raises(InvalidArgument, match="ring_size"):
            cls(ring_size=6)
        with pytest.raises(InvalidArgument, match="max_samples"):
            cls(max_samples=25)
        with pytest.raises(InvalidArgument, match="rto"):
            cls(rto=0)
        s = cls(ring_size=2)
        s.push(bytes(6))
        s.push(bytes(6))
        with pytest.raises(LinkBusy):
            s.push(bytes(6))
        with pytest.raises(InvalidArgument, match="record"):
            s.push(b"abc")
    with pytest.raises(InvalidArgument, match="engine"):
        simulate_link2(10, engine="fast")  # type: ignore[arg-type]


def _ends(kind: str, rto: int):
    return (CSender2 if kind[0] == "c" else Sender2)(16, 6, rto), (CReceiver2 if kind[1] == "c" else Receiver2)()


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(PAIRS), st.integers(1, 8), st.integers(0, 400), st.integers(0, 300), st.integers(1, 40))
def test_room_to_zero_and_back_a_always_resumes(pair: tuple[str, str], cap: int, stall: int, deaf: int,
                                                rto: int) -> None:
    """Never stuck: B's consumer stops for `stall` steps (its room goes to 0), then frees one
    record a step; B's bytes (its window update among them) are lost for `deaf` steps after the
    stall. Once the room is back A resumes (probing if it heard nothing): all 40 records
    delivered, once, in order. B's room is set before every byte, as attitude-rx does."""
    a, b = _ends(pair, rto)
    recs = [record(i) for i in range(40)]
    queue, got, held = list(recs), [], 0
    # bound: stall and deafness, then per record a few frames and, at worst, a probe's rto
    for t in range(stall + deaf + 40 * (4 * rto + 200)):
        if t >= stall and held:
            held -= 1  # the consumer frees one record
        while queue and a.room > 0:
            a.push(queue.pop(0))
        r, byte = a.poll(t)
        while r == Result2.TIMEOUT:
            r, byte = a.poll(t)
        b.set_room(cap - held)
        if r == Result2.SEND and b.sink(byte) == Result2.DELIVERED:
            got.extend(b.delivered)
            held += len(b.delivered)
            assert held <= cap  # B never takes more than its room
        b.set_room(cap - held)
        r, byte = b.poll(t)
        if r == Result2.SEND and not stall <= t < stall + deaf:
            a.sink(byte, t)
        if len(got) == len(recs) and a.pending == 0:
            break
    assert got == recs and a.pending == 0
