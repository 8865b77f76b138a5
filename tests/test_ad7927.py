"""AD7927: C driver vs Python reference driver vs device models (Python and C twin),
through both HALs (bit-banged pins, frame transfer).

The device model checks every pin operation against the datasheet's
serial-interface timing and protocol (attitude_c/ad7927/model.py); its pin
traces and frame logs are compared event by event between the C driver
(through CFFI callbacks), the pure-Python reference driver, and the C driver
against the C twin. Expected words come from the datasheet's bit tables
(hand-assembled hex below) or from the reference's field builder, never from
the C driver.
"""

from __future__ import annotations

import functools
import itertools
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from attitude_c import ad7927 as A
from attitude_c.errors import AttitudeError, InvalidArgument, InvalidType, NonFiniteError

REFIN = 2.5
RAMP = [0.3 + 0.6 * i for i in range(8)]  # 0.3 .. 4.5 V, inside 0..5 V
MODES = list(itertools.product((True, False), (False, True)))
MODE_IDS = [f"{'0-2ref' if r else '0-ref'}-{'twos' if t else 'binary'}" for r, t in MODES]


def expected_code(v: float, range_double: bool, twos: bool) -> int:
    """The datasheet transfer: transitions at whole LSBs, LSB = span / 4096, clipped;
    two's complement = straight binary - 2048."""
    span = 2 * REFIN if range_double else REFIN
    c = min(max(int(np.floor(v / span * 4096)), 0), 4095)
    return c - 2048 if twos else c


def session(drv: Any, twos: bool) -> list[Any]:
    """Every call of the driver API once or more; returns what it read."""
    out: list[Any] = []

    def scan(ch: list[int], nxt: int | None = None) -> None:
        out.append(list(drv.scan(ch, nxt)))

    def seq(n: int) -> None:
        codes, chans = drv.seq_read(n)
        out.append((list(codes), list(chans)))

    drv.power_up()
    scan([0, 1, 2, 3, 4, 5, 6])
    scan([0, 1, 2, 3, 4, 5, 6])          # steady state: 7 frames
    scan([6, 2, 7, 0, 3], 3)
    drv.seq_start(6)
    seq(9)                                # wraps 0..6, 0, 1
    drv.shadow_start([1, 4, 6], [0, 7])
    seq(7)                                # 1 4 6 0 7 1 4
    drv.configure(range_double=True, twos_complement=not twos)
    seq(4)                                # (1,0) write inside the sequence
    scan([5, 2])
    drv.power_down()
    scan([3])                             # wakes the part
    return out


def run(kind: str, hal: str, range_double: bool, twos: bool) -> tuple[list[Any], Any]:
    """A session with one driver/model pair; returns (what it read, the model)."""
    if kind == "c-python":
        m: Any = A.Ad7927Model(RAMP, refin=REFIN)
        drv: Any = A.Ad7927(m, hal=hal, range_double=range_double, twos_complement=twos)
    elif kind == "c-twin":
        m = A.CTwin(RAMP, refin=REFIN)
        drv = A.Ad7927(m, hal=hal, range_double=range_double, twos_complement=twos)
    else:
        m = A.Ad7927Model(RAMP, refin=REFIN)
        drv = A.ReferenceDriver(m, frames=hal == "frames", range_double=range_double,
                                twos_complement=twos)
    out = session(drv, twos)
    return [[int(x) for x in o] if not isinstance(o, tuple) else ([int(x) for x in o[0]], [int(x) for x in o[1]])
            for o in out], m


@pytest.mark.parametrize(("range_double", "twos"), MODES, ids=MODE_IDS)
@pytest.mark.parametrize("hal", ["pins", "frames"])
def test_same_transcript_and_codes_everywhere(hal: str, range_double: bool, twos: bool) -> None:
    (c_out, c_m), (r_out, r_m), (t_out, t_m) = (run(k, hal, range_double, twos)
                                                for k in ("c-python", "reference", "c-twin"))
    assert c_out == r_out == t_out
    assert c_m.frames == r_m.frames == t_m.frames  # byte-exact: DIN, DOUT, channel, validity, time
    if hal == "pins":
        assert c_m.trace == r_m.trace == t_m.trace  # pin-exact
        assert len(c_m.trace) > 2000  # ~40 frames of ~80 pin events
    want = [expected_code(v, range_double, twos) for v in RAMP]
    assert c_out[0] == want[:7] and c_out[1] == want[:7]
    assert c_out[2] == [want[c] for c in (6, 2, 7, 0, 3)]
    assert c_out[3] == ([want[c] for c in [0, 1, 2, 3, 4, 5, 6, 0, 1]], [0, 1, 2, 3, 4, 5, 6, 0, 1])
    assert c_out[4] == ([want[c] for c in [1, 4, 6, 0, 7, 1, 4]], [1, 4, 6, 0, 7, 1, 4])
    # the coding changes from the second conversion of that read on
    other = [expected_code(v, True, not twos) for v in RAMP]
    assert c_out[5] == ([want[6], other[0], other[7], other[1]], [6, 0, 7, 1])
    assert c_out[6] == [other[5], other[2]] and c_out[7] == [other[3]]


def test_pins_and_frames_carry_the_same_words() -> None:
    (_, m_pins), (_, m_frames) = run("c-python", "pins", True, False), run("c-python", "frames", True, False)
    strip = [(f.din, f.dout, f.channel, f.valid) for f in m_pins.frames]
    assert strip == [(f.din, f.dout, f.channel, f.valid) for f in m_frames.frames]
    # and the pin trace says the same: the DOUT? reads of each frame are its DOUT word
    words, cur, n = [], 0, 0
    for _, sig, val in m_pins.trace:
        if sig == "DOUT?":
            cur, n = (cur << 1) | val, n + 1
            if n == 16:
                words.append(cur)
                cur, n = 0, 0
    assert words == [f.dout for f in m_pins.frames]


# -- datasheet transcripts -------------------------------------------------------

# Control words assembled by hand from Table 5 (WRITE SEQ x ADD2 ADD1 ADD0 PM1 PM0
# SHADOW x RANGE CODING, MSB first, then 4 don't-care zeros): 0..2 REFIN
# (RANGE 0), straight binary (CODING 1), normal power (PM 11).
W_VIN0 = 0x8310     # 1 0 0 000 11 0 0 0 1
W_VIN5 = 0x9710     # 1 0 0 101 11 0 0 0 1
W_SEQ6 = 0xDB90     # 1 1 0 110 11 1 0 0 1: consecutive VIN0..VIN6
W_SHADOW = 0x8390   # 1 0 0 000 11 1 0 0 1: the next frame loads the shadow register
W_DOWN = 0x8210     # 1 0 0 000 10 0 0 0 1: full shutdown
SHADOW_146_07 = 0x4A81  # 0100 1010 | 1000 0001: VIN1, VIN4, VIN6 | VIN0, VIN7


def test_control_word_builder_matches_the_hand_assembled_words() -> None:
    assert A.control_word(add=0) == W_VIN0
    assert A.control_word(add=5) == W_VIN5
    assert A.control_word(seq=1, shadow=1, add=6) == W_SEQ6
    assert A.control_word(shadow=1) == W_SHADOW
    assert A.control_word(pm=0b10) == W_DOWN
    assert A.shadow_word([1, 4, 6], [0, 7]) == SHADOW_146_07
    assert A.shadow_channels(SHADOW_146_07) == [1, 4, 6, 0, 7]


@pytest.mark.parametrize("hal", ["pins", "frames"])
def test_byte_exact_frames(hal: str) -> None:
    m = A.CTwin(RAMP)
    d = A.Ad7927(m, hal=hal)
    d.power_up()
    d.scan([5])
    d.seq_start(6)
    d.seq_read(2)
    d.shadow_start([1, 4, 6], [0, 7])
    d.power_down()
    din = [f.din for f in m.frames]
    assert din == [0xFFFF, 0xFFFF, W_VIN0,       # power-up: two frames with DIN high, first write
                   W_VIN5, W_VIN5,               # VIN5 not pending: prime, then read (next = VIN5)
                   W_SEQ6, 0x0000, 0x0000,       # sequence start, two WRITE = 0 frames
                   W_SHADOW, SHADOW_146_07,      # shadow program
                   W_DOWN]
    dout = [f.dout for f in m.frames]
    code5 = A.quantize(RAMP[5], REFIN)
    # frame 3: VIN0 of the all-ones sequence (RANGE = 1: 0..REFIN, straight binary)
    assert dout[2] == (0 << 12) | A.quantize(RAMP[0], REFIN, range_double=False)
    assert dout[4] == (5 << 12) | code5                      # leading 0, ADD = 101, 12 data bits
    assert dout[6] == (0 << 12) | A.quantize(RAMP[0], REFIN)
    assert dout[7] == (1 << 12) | A.quantize(RAMP[1], REFIN)
    assert all(w >> 15 == 0 for w in dout)


def test_pin_exact_first_frame() -> None:
    """The first frame's pins, from the documented engine timing (docs/ad7927.md):
    CS low, 35 ns, then per bit DIN, 10 ns, read DOUT, SCLK low, 40 ns, SCLK high, 20 ns."""
    m = A.Ad7927Model(RAMP)
    A.Ad7927(m).power_up()
    want: list[tuple[int, str, int]] = [(0, "SCLK", 1), (0, "CS", 0), (0, "DOUT", 0)]
    t, dout, din = 35, 0, 0
    garbage = A.model.GARBAGE  # the default power-on state converts nothing valid
    for k in range(16):
        if din != 1:
            want.append((t, "DIN", 1))
            din = 1
        t += 10
        want.append((t, "DOUT?", dout))
        want.append((t, "SCLK", 0))
        nxt = (garbage >> (14 - k)) & 1 if k < 15 else A.HIGH_Z
        if nxt != dout:
            want.append((t, "DOUT", nxt))
            dout = nxt
        t += 40
        want.append((t, "SCLK", 1))
        t += 20
    want += [(t, "CS", 1)]
    assert m.trace[:len(want)] == want
    assert m.trace[len(want)] == (t + 1000, "CS", 0)  # t_POWER-UP, then the second DIN-high frame


# -- pipeline, power-up, sequencer -----------------------------------------------------

def test_pipeline_offset_on_random_scans() -> None:
    rng = np.random.default_rng(3)
    m = A.Ad7927Model(RAMP)
    d = A.Ad7927(m, hal="frames")
    d.power_up()
    for _ in range(20):
        ch = rng.integers(0, 8, rng.integers(1, 9)).tolist()
        assert d.scan(ch, int(rng.integers(0, 8))).tolist() == [A.quantize(RAMP[c], REFIN) for c in ch]
    f = m.frames
    for prev, cur in zip(f[2:], f[3:]):   # every frame after power-up's DIN-high ones
        assert cur.channel == (prev.din >> 10) & 7  # the channel written one frame earlier
        assert cur.dout >> 12 == cur.channel


def test_steady_scan_takes_n_frames_and_samples_in_its_own_frames() -> None:
    m = A.Ad7927Model(RAMP)
    d = A.Ad7927(m)
    d.power_up()
    d.scan([2, 3, 4])                  # VIN0 pending: primes (4 frames)
    n0 = len(m.frames)
    m.set_inputs([4.0] * 8)            # new voltages between scans
    assert d.scan([2, 3, 4]).tolist() == [A.quantize(4.0, REFIN)] * 3
    assert len(m.frames) - n0 == 3


POWERUP_STATES = [
    (0x020, True),   # full shutdown, shadow load pending (the default worst case)
    (0x030, False),  # normal, VIN0
    (0x010, True),   # auto shutdown, shadow load pending
    (0x5F9, False),  # normal, consecutive sequence VIN0..VIN7 running
    (0x4E8, False),  # full shutdown, consecutive sequence VIN0..VIN3, two's complement
]


@pytest.mark.parametrize(("control", "shadow"), POWERUP_STATES)
@pytest.mark.parametrize("backend", ["python", "twin"])
def test_power_up_from_any_state(control: int, shadow: bool, backend: str) -> None:
    cls: Any = A.Ad7927Model if backend == "python" else A.CTwin
    m = cls(RAMP, powerup_control=control, powerup_shadow=shadow)
    d = A.Ad7927(m)
    d.power_up()
    assert d.scan([7, 1]).tolist() == [A.quantize(RAMP[7], REFIN), A.quantize(RAMP[1], REFIN)]
    if backend == "twin":
        assert m.violation() is None


@settings(max_examples=30, deadline=None)
@given(control=st.integers(0, 0xFFF).filter(lambda c: (c >> 4) & 3 != 0), shadow=st.booleans())
def test_power_up_from_random_states(control: int, shadow: bool) -> None:
    for cls in (A.Ad7927Model, A.CTwin):
        m: Any = cls(RAMP, powerup_control=control, powerup_shadow=shadow)
        d = A.Ad7927(m, hal="frames")
        d.power_up()
        assert d.scan([0, 5]).tolist() == [A.quantize(RAMP[0], REFIN), A.quantize(RAMP[5], REFIN)]


def test_without_the_dummy_frames_the_first_write_is_lost() -> None:
    # a scan is refused before power_up ...
    d = A.Ad7927(A.Ad7927Model(RAMP))
    with pytest.raises(AttitudeError, match="not valid in current state"):
        d.scan([0])
    # ... because in the worst power-on state the first word goes to the pending
    # shadow load and the part stays in full shutdown: nothing converts
    m = A.Ad7927Model(RAMP)
    m.transfer([W_VIN5], 1000)               # "select VIN5" ...
    assert m.seq == A.shadow_channels(W_VIN5) and m.pm == 2  # ... became a shadow load
    out = m.transfer([W_VIN0], 1000)         # the read of "VIN5"
    assert [f.valid for f in m.frames] == [False, False]
    assert out == [A.model.GARBAGE]


def test_power_up_waits_t_power_up_after_each_dummy() -> None:
    m = A.Ad7927Model(RAMP)
    A.Ad7927(m, hal="frames").power_up()
    for a, b in zip(m.frames, m.frames[1:]):
        assert b.t - (a.t + 16 * 108) >= 1000


def test_sequencer_wraps_and_needs_no_writes() -> None:
    m = A.Ad7927Model(RAMP)
    d = A.Ad7927(m)
    d.power_up()
    d.seq_start(6)
    n0 = len(m.frames)
    codes, chans = d.seq_read(16)
    assert chans.tolist() == [i % 7 for i in range(16)]
    assert codes.tolist() == [A.quantize(RAMP[i % 7], REFIN) for i in range(16)]
    assert all(f.din == 0 for f in m.frames[n0:])
    codes, chans = d.seq_read(3)       # and on from where it stopped
    assert chans.tolist() == [2, 3, 4]
    with pytest.raises(InvalidArgument, match="last"):
        d.seq_start(8)


def test_shadow_sequence_two_only_after_one() -> None:
    m = A.CTwin(RAMP)
    d = A.Ad7927(m)
    d.power_up()
    d.shadow_start([5], [5, 2])
    assert d.seq_read(6)[1].tolist() == [5, 2, 5, 5, 2, 5]
    with pytest.raises(InvalidArgument, match="sequence_one"):
        d.shadow_start([], [1])


def test_power_down_and_wake() -> None:
    m = A.Ad7927Model(RAMP)
    d = A.Ad7927(m)
    d.power_up()
    d.power_down()
    assert d.pending is None and m.pm == 2
    assert d.scan([4]).tolist() == [A.quantize(RAMP[4], REFIN)]
    wake = m.frames[-2]
    assert not wake.valid and m.frames[-1].t - wake.t >= 1000 + 16 * 70


# -- faults ------------------------------------------------------------------------------

@pytest.mark.parametrize("hal", ["pins", "frames"])
@pytest.mark.parametrize("backend", ["python", "twin", "reference"])
def test_stuck_dout_high_is_a_frame_error(backend: str, hal: str) -> None:
    m: Any = A.CTwin(stuck_dout=1) if backend == "twin" else A.Ad7927Model(stuck_dout=1)
    d: Any = (A.ReferenceDriver(m, frames=hal == "frames") if backend == "reference"
              else A.Ad7927(m, hal=hal))
    with pytest.raises(A.FrameError) as info:
        d.power_up()
    assert info.value.word == 0xFFFF


@pytest.mark.parametrize("backend", ["python", "twin", "reference"])
def test_stuck_dout_low_is_caught_at_the_first_nonzero_channel(backend: str) -> None:
    m: Any = A.CTwin(RAMP, stuck_dout=0) if backend == "twin" else A.Ad7927Model(RAMP, stuck_dout=0)
    d: Any = A.ReferenceDriver(m) if backend == "reference" else A.Ad7927(m)
    d.power_up()  # 0x0000 names VIN0: power-up cannot tell
    with pytest.raises(A.AddressMismatch, match="expected VIN1") as info:
        d.scan([0, 1, 2])
    assert info.value.word == 0 and info.value.expected == 1
    if backend != "reference":
        assert d.pending is None


@pytest.mark.parametrize("backend", ["python", "twin", "reference"])
def test_wrong_channel_address(backend: str) -> None:
    m: Any = A.CTwin(RAMP) if backend == "twin" else A.Ad7927Model(RAMP)
    d: Any = A.ReferenceDriver(m) if backend == "reference" else A.Ad7927(m)
    d.power_up()
    d.scan([3])
    if backend == "twin":
        m._m.address_xor = 4
    else:
        m.address_xor = 4
    with pytest.raises(A.AddressMismatch, match="names VIN7, expected VIN3"):
        d.scan([3])
    if backend == "twin":
        m._m.address_xor = 0
    else:
        m.address_xor = 0
    assert list(d.scan([3])) == [A.quantize(RAMP[3], REFIN)]  # re-primes and recovers


@pytest.mark.parametrize("backend", ["python", "twin"])
def test_stuck_din_means_no_write_lands(backend: str) -> None:
    m: Any = A.CTwin(RAMP, stuck_din=0) if backend == "twin" else A.Ad7927Model(RAMP, stuck_din=0)
    with pytest.raises(A.AddressMismatch):
        A.Ad7927(m).power_up()
    # from a normal power-on state the part converts VIN0 over and over
    m2 = A.Ad7927Model(RAMP, stuck_din=0, powerup_control=0x030, powerup_shadow=False)
    d = A.Ad7927(m2)
    d.power_up()
    with pytest.raises(A.AddressMismatch, match="names VIN0, expected VIN1"):
        d.scan([1])


def test_convert_faults_keep_partial_results() -> None:
    v = np.full((10, 7), 2.0)
    with pytest.raises(A.FrameError) as info:
        A.convert(v, stuck_dout=1)
    assert info.value.rows_done == 0  # type: ignore[attr-defined]
    with pytest.raises(A.AddressMismatch):
        A.convert(v, address_xor=1, hal="pins")
    with pytest.raises(A.AddressMismatch):
        A.convert(v, stuck_din=1, mode="sequence")


def test_wrong_edge_reference_is_caught() -> None:
    m = A.Ad7927Model(RAMP)
    with pytest.raises(A.ProtocolViolation) as info:
        A.ReferenceDriver(m, sample_after_fall=True).power_up()
    assert info.value.rule == "dout-early"


@pytest.mark.parametrize("backend", ["python", "twin"])
def test_driver_sits_on_the_datasheet_limits(backend: str) -> None:
    # a model whose DIN setup limit is 1 ns longer rejects the driver: the model
    # really measures the engine's timing (the twin's violation is latched and
    # raised by the driver after the call)
    if backend == "python":
        m: Any = A.Ad7927Model(RAMP, timing=A.Timing(t_din_setup=11))
    else:
        m = A.CTwin(RAMP)
        m._m.timing.t_din_setup = 11
    with pytest.raises(A.ProtocolViolation) as info:
        A.Ad7927(m).power_up()
    assert info.value.rule == "din-setup"


# -- the model's rules, one hand-made violation each, on both models -------------------------

class TwinPins:
    """The C twin's pin functions with the Python model's method names."""

    def __init__(self, **kw: Any) -> None:
        self.twin = A.CTwin(**kw)
        lib, m = self.twin._lib, self.twin._m
        # the C model's ad7927m_<pin>(m, ...) as self.<pin>(...)
        for pin in ("set_cs", "set_sclk", "set_din", "get_dout", "delay_ns"):
            setattr(self, pin, functools.partial(getattr(lib, "ad7927m_" + pin), m))
        tx = self.twin._ffi.new("uint16_t[]", 8)
        rx = self.twin._ffi.new("uint16_t[]", 8)

        def transfer(words: list[int], hold: int) -> list[int]:
            for i, w in enumerate(words):
                tx[i] = w
            lib.ad7927m_transfer(m, tx, rx, len(words), hold)
            return [rx[i] for i in range(len(words))]
        self.transfer = transfer

    def rule(self) -> str | None:
        v = self.twin.violation()
        return None if v is None else v.rule


def frame(p: Any, word: int = 0, falls: int = 16, low: int = 40, high: int = 20) -> None:
    """A frame with the engine's timing (and a selectable number of falling edges)."""
    p.set_sclk(1)
    p.set_cs(0)
    p.delay_ns(35)
    for k in range(falls):
        p.set_din((word >> (15 - k)) & 1 if k < 16 else 0)
        p.delay_ns(10)
        p.set_sclk(0)
        p.delay_ns(low)
        p.set_sclk(1)
        p.delay_ns(high)


def good_frame(p: Any, word: int = 0) -> None:
    frame(p, word)
    p.set_cs(1)
    p.delay_ns(50)


def v_clock_count(p: Any) -> None:
    frame(p, falls=17)


def v_cs_early(p: Any) -> None:
    frame(p, falls=9)
    p.set_cs(1)


def v_cs_hold(p: Any) -> None:
    frame(p, falls=15)
    p.set_din(0)
    p.delay_ns(10)
    p.set_sclk(0)
    p.delay_ns(10)
    p.set_cs(1)


def v_cs_setup(p: Any) -> None:
    p.set_sclk(1)
    p.set_cs(0)
    p.delay_ns(5)
    p.set_sclk(0)


def v_quiet_time(p: Any) -> None:
    frame(p)
    p.set_cs(1)
    p.delay_ns(20)
    p.set_cs(0)


def v_clock_too_fast(p: Any) -> None:
    frame(p, falls=3, low=10, high=20)


def v_clock_too_slow(p: Any) -> None:
    frame(p, falls=3, low=60_000, high=60_000)


def v_din_setup(p: Any) -> None:
    p.set_sclk(1)
    p.set_cs(0)
    p.delay_ns(35)
    p.set_din(1)
    p.delay_ns(5)
    p.set_sclk(0)


def v_din_hold(p: Any) -> None:
    frame(p, falls=1, low=0, high=0)
    p.delay_ns(2)
    p.set_din(1)


def v_dout_early(p: Any) -> None:
    p.set_cs(0)
    p.delay_ns(10)
    p.get_dout()


def v_dout_three_state(p: Any) -> None:
    p.get_dout()


def v_power_up_time(p: Any) -> None:
    good_frame(p, 0xFFFF)  # default power-on: full shutdown, shadow pending
    good_frame(p, 0xFFFF)  # PM = 11: powers up on this CS rising edge
    frame(p)               # after t_QUIET only, not t_POWER-UP


def v_invalid_power_mode(p: Any) -> None:
    p.transfer([0x0000, 0x8000], 50)  # shadow load, then a write with PM = 00


VIOLATIONS = {name.replace("_", "-"): fn for name, fn in [
    ("clock_count", v_clock_count), ("cs_early", v_cs_early), ("cs_hold", v_cs_hold),
    ("cs_setup", v_cs_setup), ("quiet_time", v_quiet_time), ("clock_too_fast", v_clock_too_fast),
    ("clock_too_slow", v_clock_too_slow), ("din_setup", v_din_setup), ("din_hold", v_din_hold),
    ("dout_early", v_dout_early), ("dout_three_state", v_dout_three_state),
    ("power_up_time", v_power_up_time), ("invalid_power_mode", v_invalid_power_mode),
]}


def test_every_rule_has_a_violation_test() -> None:
    assert sorted(VIOLATIONS) == sorted(A.RULES)


@pytest.mark.parametrize("rule", sorted(VIOLATIONS))
def test_model_raises_on_violation(rule: str) -> None:
    with pytest.raises(A.ProtocolViolation) as info:
        VIOLATIONS[rule](A.Ad7927Model())
    assert info.value.rule == rule
    twin = TwinPins()
    VIOLATIONS[rule](twin)
    assert twin.rule() == rule


def test_good_frames_are_accepted_by_both_models() -> None:
    for p in (A.Ad7927Model(RAMP, powerup_control=0x030, powerup_shadow=False), TwinPins(inputs=RAMP,
              powerup_control=0x030, powerup_shadow=False)):
        good_frame(p, W_VIN5)
        good_frame(p, W_VIN0)  # converts VIN5
        if isinstance(p, TwinPins):
            assert p.rule() is None
            assert p.twin.frames[1].dout == (5 << 12) | A.quantize(RAMP[5], REFIN)
        else:
            assert p.frames[1].dout == (5 << 12) | A.quantize(RAMP[5], REFIN)


def test_auto_shutdown_needs_a_dummy_frame() -> None:
    # model behaviour the driver does not use: PM = 01 shuts down after each valid
    # conversion; the next CS falling edge wakes it (that conversion is a dummy)
    for p in (A.Ad7927Model(RAMP, powerup_control=0x030, powerup_shadow=False),
              TwinPins(inputs=RAMP, powerup_control=0x030, powerup_shadow=False)):
        auto5 = A.control_word(add=5, pm=0b01)
        out = p.transfer([auto5, 0, 0], 1000)   # VIN0 (valid), then dummy, then VIN5
        frames = p.twin.frames if isinstance(p, TwinPins) else p.frames
        assert [f.valid for f in frames] == [True, False, True]
        assert out[2] == (5 << 12) | A.quantize(RAMP[5], REFIN)


# -- the Python API and the batch conversion -----------------------------------------------

@pytest.mark.parametrize(("range_double", "twos"), MODES, ids=MODE_IDS)
@pytest.mark.parametrize("mode", ["scan", "sequence"])
@pytest.mark.parametrize("hal", ["frames", "pins"])
def test_convert_matches_the_transfer_function(hal: str, mode: str, range_double: bool, twos: bool) -> None:
    rng = np.random.default_rng(11)
    v = rng.uniform(-0.5, 5.5, (200, 7))
    codes = A.convert(v, REFIN, range_double=range_double, twos_complement=twos, mode=mode, hal=hal)  # type: ignore[arg-type]
    want = np.vectorize(lambda x: expected_code(float(x), range_double, twos))(v)
    assert np.array_equal(codes, want)


def test_convert_channels_chunks_and_progress() -> None:
    v = np.array([[1.0, 4.0], [2.0, 3.0], [0.5, 0.25]])
    seen: list[int] = []
    codes = A.convert(v, channels=[7, 2], progress=seen.append, chunk=2)
    assert codes.tolist() == [[A.quantize(x, REFIN) for x in row] for row in v.tolist()]
    assert seen == [2, 3]


def test_codes_to_volts_is_the_bin_centre() -> None:
    c = np.arange(4096)
    for range_double, twos in MODES:
        codes = c - 2048 if twos else c
        volts = A.codes_to_volts(codes, REFIN, range_double=range_double, twos_complement=twos)
        back = A.convert(volts[:, None], REFIN, range_double=range_double, twos_complement=twos)[:, 0]
        assert np.array_equal(back, codes)
        lsb = (2 * REFIN if range_double else REFIN) / 4096
        # the bin [c, c + 1) LSB: its centre, to rounding of a few ulps of 5 V
        assert np.allclose(volts, (c + 0.5) * lsb, rtol=0, atol=1e-12)
    with pytest.raises(InvalidArgument, match="element 1"):
        A.codes_to_volts(np.array([0, 4096]))
    with pytest.raises(InvalidType):
        A.codes_to_volts(np.array([0.5]))


def test_convert_rejects_bad_input() -> None:
    v = np.full((4, 3), 1.0)
    v[2, 1] = np.nan
    with pytest.raises(NonFiniteError) as info:
        A.convert(v)
    assert info.value.index == 2
    with pytest.raises(InvalidArgument, match="shape"):
        A.convert(np.ones(3))
    with pytest.raises(InvalidArgument, match="shape"):
        A.convert(np.ones((2, 9)))
    with pytest.raises(InvalidArgument, match="refin"):
        A.convert(np.ones((2, 3)), 0.0)
    with pytest.raises(InvalidArgument, match="channels"):
        A.convert(np.ones((2, 2)), channels=[1, 1])
    with pytest.raises(InvalidArgument, match="sequence"):
        A.convert(np.ones((2, 2)), channels=[0, 2], mode="sequence")
    with pytest.raises(InvalidArgument, match="hal"):
        A.convert(np.ones((2, 2)), hal="spi")  # type: ignore[arg-type]
    with pytest.raises(InvalidType):
        A.convert(np.array([["a", "b"]]))
    with pytest.raises(InvalidArgument, match="stuck_dout"):
        A.convert(np.ones((2, 2)), stuck_dout=2)


def test_api_argument_errors() -> None:
    d = A.Ad7927(A.Ad7927Model())
    d.power_up()
    with pytest.raises(InvalidArgument, match="channels"):
        d.scan([0, 8])
    with pytest.raises(InvalidArgument, match="next_channel"):
        d.scan([0], next_channel=9)
    with pytest.raises(InvalidType, match="last"):
        d.seq_start(1.5)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="n must"):
        d.seq_read(17)
    with pytest.raises(AttitudeError, match="not valid"):
        d.seq_read(1)  # no sequence running
    with pytest.raises(NonFiniteError):
        A.Ad7927Model([1.0, np.inf])
    with pytest.raises(InvalidType):
        A.Ad7927(model="nope")  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="hal"):
        A.Ad7927(hal="spi")  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="powerup_control"):
        A.Ad7927Model(powerup_control=0x000)


def test_codes_come_from_the_library() -> None:
    from attitude_c._lib import ffi_lib

    _, lib = ffi_lib()
    assert (lib.AD7927_E_CHANNEL, lib.AD7927_E_FRAME, lib.AD7927_E_TRANSFER) == (-180, -181, -182)
    assert lib.AD7927M_E_VIOLATION == -190  # inside the AD7927 range -180..-199 of common.h
    assert lib.AD7927_CHANNELS == 8 and lib.AD7927_T_POWER_UP_NS == 1000


def test_thesis_board() -> None:
    b = A.THESIS_BOARD
    assert (b.spi_hz, b.refin, b.range_double) == (9_260_000, 2.5, True)
    assert sorted(b.channels.values()) == list(range(8))


def test_f32_build_drives_the_model_too() -> None:
    m = A.Ad7927Model(RAMP)
    d = A.Ad7927(m, precision="f32")
    d.power_up()
    assert d.scan([1, 2]).tolist() == [A.quantize(RAMP[1], REFIN), A.quantize(RAMP[2], REFIN)]
