"""TLC2543: C driver vs Python reference driver vs device models (Python and C twin).

The device model checks every pin operation against the datasheet timing and
protocol (attitude_c/tlc2543/model.py); the traces it records are compared
event by event between the C driver (through CFFI callbacks), the pure-Python
reference driver, and the C driver against the C twin of the model.
"""

from __future__ import annotations

import functools
import itertools
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from attitude_c import tlc2543 as T
from attitude_c.errors import DeviceTimeout, InvalidArgument, InvalidType, NonFiniteError

VREF = 5.0
MODES = list(itertools.product((8, 12, 16), (False, True), (False, True)))
MODE_IDS = [f"{n}bit-{'lsb' if l else 'msb'}-{'bip' if b else 'uni'}" for n, l, b in MODES]


def expected_word(code12: int, length: int, bipolar: bool) -> int:
    """The word the datasheet's output format gives for a 12-bit code."""
    c = code12 ^ 0x800 if bipolar else code12
    w = c >> 4 if length == 8 else c << 4 if length == 16 else c
    if bipolar and w >> (length - 1):
        w -= 1 << length
    return w


def run_all_three(volts: list[float], channels: list[int], length: int, lsb: bool, bip: bool,
                  scans: int = 2) -> tuple[list[Any], list[Any], list[Any]]:
    """Self-test + `scans` scans with each implementation; returns
    (codes, trace) pairs for C+Python model, reference+Python model, C+twin."""
    out = []
    m1 = T.Tlc2543Model(volts, vref_plus=VREF)
    c_drv = T.Tlc2543(m1, length=length, lsb_first=lsb, bipolar=bip)
    codes = [c_drv.self_test().tolist()] + [c_drv.scan(channels).tolist() for _ in range(scans)]
    out.append((codes, m1.trace))

    m2 = T.Tlc2543Model(volts, vref_plus=VREF)
    ref = T.ReferenceDriver(m2, length=length, lsb_first=lsb, bipolar=bip)
    codes = [ref.self_test()] + [ref.scan(channels) for _ in range(scans)]
    out.append((codes, m2.trace))

    twin = T.CTwin(volts, vref_plus=VREF)
    c2 = T.Tlc2543(twin, length=length, lsb_first=lsb, bipolar=bip)
    codes = [c2.self_test().tolist()] + [c2.scan(channels).tolist() for _ in range(scans)]
    out.append((codes, twin.trace))
    return out[0], out[1], out[2]


@pytest.mark.parametrize(("length", "lsb", "bip"), MODES, ids=MODE_IDS)
def test_every_mode_same_trace_and_codes(length: int, lsb: bool, bip: bool) -> None:
    # AIN0..AIN5: both rails, beyond both rails (the chip clips), mid-scale, 1 LSB
    volts = [0.0, VREF, -0.7, VREF + 1.3, VREF / 2, VREF / 4096]
    chans = [0, 1, 2, 3, 4, 5]
    (c_codes, c_trace), (r_codes, r_trace), (t_codes, t_trace) = run_all_three(volts, chans, length, lsb, bip)
    assert c_trace == r_trace
    assert c_trace == t_trace
    assert c_codes == r_codes == t_codes
    want = [expected_word(T.quantize(v, VREF), length, bip) for v in volts]
    assert c_codes[1] == want and c_codes[2] == want
    assert c_codes[0] == [0x800, 0x000, 0xFFF]
    assert want[0] == expected_word(0, length, bip) and want[2] == want[0]  # clipped low
    assert want[1] == expected_word(4095, length, bip) and want[3] == want[1]  # clipped high


@settings(max_examples=25, deadline=None)
@given(volts=st.lists(st.floats(-1.0, 6.0, allow_nan=False), min_size=3, max_size=3),
       mode=st.sampled_from(MODES), order=st.permutations([0, 1, 2]))
def test_random_voltages_same_trace_and_codes(volts: list[float], mode: tuple[int, bool, bool],
                                              order: list[int]) -> None:
    length, lsb, bip = mode
    (c_codes, c_trace), (r_codes, r_trace), (t_codes, t_trace) = run_all_three(volts, order, length, lsb, bip,
                                                                               scans=1)
    assert c_trace == r_trace == t_trace
    assert c_codes == r_codes == t_codes
    assert c_codes[1] == [expected_word(T.quantize(volts[c], VREF), length, bip) for c in order]


def test_quantizer_transfer() -> None:
    # first transition at 0.5 LSB, clipped at both rails; LSB = 5 V / 4096
    lsb = VREF / 4096
    assert T.quantize(0.49 * lsb, VREF) == 0
    assert T.quantize(0.51 * lsb, VREF) == 1
    assert T.quantize(VREF / 2, VREF) == 0x800
    assert T.quantize(VREF, VREF) == 0xFFF
    assert T.quantize(-3.0, VREF) == 0 and T.quantize(99.0, VREF) == 0xFFF
    assert T.quantize(1.0, 2.0, vref_minus=1.0) == 0


# -- pipeline -----------------------------------------------------------------

def input_bytes(trace: list[tuple[int, str, int]]) -> list[int]:
    """Decode the input bytes the driver sent: DATA INPUT at rising edges 1..8."""
    out, din, n, byte = [], 0, 0, 0
    for _, sig, val in trace:
        if sig == "DIN":
            din = val
        elif sig == "CS" and val == 0:
            n, byte = 0, 0
        elif sig == "CLOCK" and val == 1:
            n += 1
            if n <= 8:
                byte = (byte << 1) | din
            if n == 8:
                out.append(byte)
    return out


def test_first_result_after_power_up_is_discarded() -> None:
    m = T.Tlc2543Model([1.0, 2.0, 3.0], powerup_word=0x123)
    d = T.Tlc2543(m)
    assert d.pending is None
    assert d.cycle(T.CH_Y) == 0x123  # what a raw first cycle clocks out: garbage
    m2 = T.Tlc2543Model([1.0, 2.0, 3.0], powerup_word=0x123)
    d2 = T.Tlc2543(m2)
    codes = d2.scan([T.CH_X, T.CH_Y, T.CH_Z])
    assert codes.tolist() == [T.quantize(v, VREF) for v in (1.0, 2.0, 3.0)]
    assert 0x123 not in codes.tolist()
    # the scan took 4 cycles: X (discarded output), Y, Z, then X again for next time
    assert [b >> 4 for b in input_bytes(m2.trace)] == [0, 1, 2, 0]
    assert m2.conversions == 4


def test_scan_order_and_labels() -> None:
    # every channel a distinct voltage, scanned in a scrambled order, twice
    volts = [0.3 * (i + 1) for i in range(11)]
    order = [7, 2, 10, 0, 5]
    m = T.Tlc2543Model(volts)
    d = T.Tlc2543(m)
    first = d.scan(order)
    n0 = len(input_bytes(m.trace))
    second = d.scan(order)
    want = [T.quantize(volts[c], VREF) for c in order]
    assert first.tolist() == want and second.tolist() == want
    sent = [b >> 4 for b in input_bytes(m.trace)]
    # first scan: n + 1 cycles; second: n (channel 7 was requested at the end of the first)
    assert sent == [7, 2, 10, 0, 5, 7] + [2, 10, 0, 5, 7]
    assert len(sent) - n0 == len(order)


def test_next_address_other_than_first_costs_a_cycle() -> None:
    m = T.Tlc2543Model([1.0, 2.0, 3.0])
    d = T.Tlc2543(m)
    d.scan([0, 1, 2], next_address=T.TEST_MID)
    d.scan([0, 1, 2], next_address=T.TEST_MID)
    assert [b >> 4 for b in input_bytes(m.trace)] == [0, 1, 2, 11] * 2


def test_power_down_then_wake() -> None:
    m = T.Tlc2543Model([1.0, 2.0, 3.0])
    d = T.Tlc2543(m)
    d.scan([0, 1])
    d.power_down()
    assert d.pending is None
    assert d.scan([2, 1]).tolist() == [T.quantize(3.0, VREF), T.quantize(2.0, VREF)]


# -- faults -------------------------------------------------------------------

@pytest.mark.parametrize("backend", ["python", "twin"])
def test_eoc_stuck_low_times_out(backend: str) -> None:
    m: Any = T.Tlc2543Model([1.0], stuck_eoc=0) if backend == "python" else T.CTwin([1.0], stuck_eoc=0)
    d = T.Tlc2543(m, eoc_polls=10)
    with pytest.raises(DeviceTimeout, match="EOC"):
        d.scan([0])
    assert d.pending is None
    eoc_reads = [e for e in m.trace if e[1] == "EOC?"]
    assert len(eoc_reads) == 10  # bounded: exactly eoc_polls samples, then the error


def test_eoc_stuck_high_is_seen_by_the_model() -> None:
    # a driver cannot tell EOC stuck high from "done": it re-asserts CS while
    # the chip is still converting, which the model reports
    with pytest.raises(T.ProtocolViolation) as info:
        T.Tlc2543(T.Tlc2543Model([1.0], stuck_eoc=1)).scan([0])
    assert info.value.rule == "cs-too-early"
    with pytest.raises(T.ProtocolViolation):
        T.convert(np.ones((3, 3)), VREF, stuck_eoc=1)


def test_reference_driver_eoc_stuck_low_times_out() -> None:
    r = T.ReferenceDriver(T.Tlc2543Model([1.0], stuck_eoc=0), eoc_polls=5)
    with pytest.raises(DeviceTimeout):
        r.scan([0])


@pytest.mark.parametrize("level", [0, 1])
@pytest.mark.parametrize("backend", ["python", "twin"])
def test_dout_stuck_fails_self_test(level: int, backend: str) -> None:
    m: Any = T.Tlc2543Model(stuck_dout=level) if backend == "python" else T.CTwin(stuck_dout=level)
    d = T.Tlc2543(m)
    with pytest.raises(T.SelfTestError, match=r"0x800") as info:
        d.self_test()
    assert info.value.codes is not None
    assert info.value.codes.tolist() == [0xFFF * level] * 3


def test_slow_conversion_beyond_the_eoc_bound() -> None:
    # a conversion slower than the driver's 40-sample bound (40 us) is a timeout;
    # within the bound the driver just waits longer
    slow = T.Timing(t_conv=30_000)
    assert T.Tlc2543(T.Tlc2543Model([1.0], timing=slow)).scan([0]).tolist() == [T.quantize(1.0, VREF)]
    too_slow = T.Timing(t_conv=60_000)
    with pytest.raises(DeviceTimeout):
        T.Tlc2543(T.Tlc2543Model([1.0], timing=too_slow)).scan([0])


def test_wrong_edge_driver_is_caught() -> None:
    # the reference driver with DATA OUT sampled right after the falling edge
    m = T.Tlc2543Model([1.0, 2.0])
    broken = T.ReferenceDriver(m, sample_after_fall=True)
    with pytest.raises(T.ProtocolViolation) as info:
        broken.scan([0, 1])
    assert info.value.rule == "dout-early"


def test_driver_sits_on_the_datasheet_limits() -> None:
    # a model whose clock-high limit is doubled rejects the driver: the
    # model really measures the driver's timing (nothing is checked loosely)
    strict = T.Timing(t_clk_high=244)
    with pytest.raises(T.ProtocolViolation) as info:
        T.Tlc2543(T.Tlc2543Model([1.0], timing=strict)).scan([0])
    assert info.value.rule == "clock-too-fast"


# -- the model's rules, one hand-made violation each, on both models -------------------

class TwinPins:
    """The C twin's pin functions with the Python model's method names."""

    def __init__(self, **kw: Any) -> None:
        self.twin = T.CTwin(**kw)
        lib, m = self.twin._lib, self.twin._m
        # the C model's tlc2543m_<pin>(m, ...) as self.<pin>(...)
        for pin in ("set_cs", "set_clock", "set_din", "get_dout", "get_eoc", "delay_ns"):
            setattr(self, pin, functools.partial(getattr(lib, "tlc2543m_" + pin), m))

    def rule(self) -> str | None:
        v = self.twin.violation()
        return None if v is None else v.rule


def clock(p: Any, n: int, din: int = 0) -> None:
    for _ in range(n):
        p.set_din(din)
        p.delay_ns(100)
        p.set_clock(1)
        p.delay_ns(122)
        p.set_clock(0)
        p.delay_ns(240)


def good_cycle(p: Any, address: int = 0) -> None:
    byte = address << 4
    p.set_cs(0)
    p.delay_ns(1425)
    for i in range(12):
        p.set_din((byte >> (7 - i)) & 1 if i < 8 else 0)
        p.delay_ns(100)
        p.get_dout()
        p.set_clock(1)
        p.delay_ns(122)
        p.set_clock(0)
        p.delay_ns(240)
    p.set_cs(1)


def v_clock_count(p: Any) -> None:
    p.set_cs(0)
    p.delay_ns(1425)
    clock(p, 13)


def v_cs_mid_cycle(p: Any) -> None:
    p.set_cs(0)
    p.delay_ns(1425)
    clock(p, 9)
    p.set_cs(1)


def v_dout_early(p: Any) -> None:
    p.set_cs(0)
    p.delay_ns(1425)
    clock(p, 1)
    p.set_clock(1)
    p.delay_ns(122)
    p.set_clock(0)
    p.delay_ns(100)
    p.get_dout()  # 100 ns after the fall: the next bit is not valid yet


def v_dout_cs_high(p: Any) -> None:
    p.get_dout()


def v_clock_too_fast(p: Any) -> None:
    p.set_cs(0)
    p.delay_ns(1425)
    p.set_clock(1)
    p.delay_ns(100)
    p.set_clock(0)


def v_cs_setup(p: Any) -> None:
    p.set_cs(0)
    p.delay_ns(1000)
    p.set_clock(1)


def v_cs_too_early(p: Any) -> None:
    good_cycle(p)
    p.delay_ns(4000)
    p.set_cs(0)


def v_cs_during_conversion(p: Any) -> None:
    good_cycle(p)
    p.delay_ns(7000)
    p.set_cs(0)


def v_eoc_early(p: Any) -> None:
    good_cycle(p)
    p.get_eoc()


def v_din_setup(p: Any) -> None:
    p.set_cs(0)
    p.delay_ns(1425)
    p.set_din(1)
    p.delay_ns(50)
    p.set_clock(1)


def v_din_hold(p: Any) -> None:
    p.set_cs(0)
    p.delay_ns(1425)
    p.set_clock(1)
    p.delay_ns(2)
    p.set_din(1)


def v_clock_cs_high(p: Any) -> None:
    p.set_clock(1)


def v_clock_high_at_cs(p: Any) -> None:
    p.set_cs(0)
    p.delay_ns(1425)
    p.set_clock(1)
    p.delay_ns(200)
    p.set_cs(1)


def v_reserved_address(p: Any) -> None:
    good_cycle(p, address=15)


VIOLATIONS = {name.replace("_", "-"): fn for name, fn in [
    ("clock_count", v_clock_count), ("cs_mid_cycle", v_cs_mid_cycle), ("dout_early", v_dout_early),
    ("dout_cs_high", v_dout_cs_high), ("clock_too_fast", v_clock_too_fast), ("cs_setup", v_cs_setup),
    ("cs_too_early", v_cs_too_early), ("cs_during_conversion", v_cs_during_conversion),
    ("eoc_early", v_eoc_early), ("din_setup", v_din_setup), ("din_hold", v_din_hold),
    ("clock_cs_high", v_clock_cs_high), ("clock_high_at_cs", v_clock_high_at_cs),
    ("reserved_address", v_reserved_address),
]}


def test_every_rule_has_a_violation_test() -> None:
    assert sorted(VIOLATIONS) == sorted(T.RULES)


@pytest.mark.parametrize("rule", sorted(VIOLATIONS))
def test_model_raises_on_violation(rule: str) -> None:
    with pytest.raises(T.ProtocolViolation) as info:
        VIOLATIONS[rule](T.Tlc2543Model())
    assert info.value.rule == rule
    twin = TwinPins()
    VIOLATIONS[rule](twin)
    assert twin.rule() == rule


def test_good_cycle_is_accepted_by_both_models() -> None:
    for p in (T.Tlc2543Model([2.5]), TwinPins(inputs=[2.5])):
        good_cycle(p)
        p.delay_ns(10_000)
        assert p.get_eoc() == 1
        good_cycle(p)  # clocks out the AIN0 conversion
        if isinstance(p, TwinPins):
            assert p.rule() is None


# -- the Python API and the batch conversion ------------------------------------

def test_convert_matches_quantizer_and_modes() -> None:
    rng = np.random.default_rng(7)
    v = rng.uniform(-0.5, 5.5, (500, 3))
    q = np.vectorize(lambda x: T.quantize(float(x), VREF))(v)
    assert np.array_equal(T.convert(v, VREF), q)
    assert np.array_equal(T.convert(v, VREF, length=8), q >> 4)
    assert np.array_equal(T.convert(v, VREF, length=16, lsb_first=True), q << 4)
    bip = T.convert(v, VREF, bipolar=True)
    assert np.array_equal(bip, q - 2048)  # two's complement about mid-scale


def test_convert_channels_and_progress() -> None:
    v = np.array([[1.0, 4.0], [2.0, 3.0], [0.5, 0.25]])
    seen: list[int] = []
    codes = T.convert(v, VREF, channels=[9, 4], progress=seen.append, chunk=2)
    assert codes.tolist() == [[T.quantize(x, VREF) for x in row] for row in v.tolist()]
    assert seen == [2, 3]


def test_convert_faults_keep_partial_results() -> None:
    v = np.full((10, 3), 2.5)
    with pytest.raises(DeviceTimeout) as info:
        T.convert(v, VREF, stuck_eoc=0)
    assert info.value.rows_done == 0
    with pytest.raises(T.SelfTestError):
        T.convert(v, VREF, stuck_dout=0)
    # without the self-test a stuck DATA OUT just reads zeros
    assert T.convert(v, VREF, stuck_dout=0, self_test=False).max() == 0


def test_convert_rejects_bad_input() -> None:
    v = np.full((4, 3), 1.0)
    v[2, 1] = np.nan
    with pytest.raises(NonFiniteError) as info:
        T.convert(v, VREF)
    assert info.value.index == 2
    with pytest.raises(InvalidArgument, match="shape"):
        T.convert(np.ones(3), VREF)
    with pytest.raises(InvalidArgument, match="vref_plus"):
        T.convert(np.ones((2, 3)), 0.0)
    with pytest.raises(InvalidArgument, match="channels"):
        T.convert(np.ones((2, 2)), VREF, channels=[1, 1])
    with pytest.raises(InvalidArgument, match="length"):
        T.convert(np.ones((2, 2)), VREF, length=10)
    with pytest.raises(InvalidType):
        T.convert(np.array([["a", "b"]]), VREF)
    with pytest.raises(InvalidArgument, match="stuck_eoc"):
        T.convert(np.ones((2, 2)), VREF, stuck_eoc=2)


def test_api_argument_errors() -> None:
    d = T.Tlc2543()
    with pytest.raises(InvalidArgument, match="address"):
        d.cycle(15)
    with pytest.raises(InvalidArgument, match="channels"):
        d.scan([0, 14])
    with pytest.raises(InvalidArgument, match="next_address"):
        d.scan([0], next_address=99)
    with pytest.raises(NonFiniteError):
        T.Tlc2543Model([1.0, np.inf])
    with pytest.raises(InvalidType):
        T.Tlc2543(model="nope")  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument):
        T.Tlc2543(length=10)


def test_f32_build_drives_the_model_too() -> None:
    m = T.Tlc2543Model([1.0, 2.0, 3.0])
    assert T.Tlc2543(m, precision="f32").scan().tolist() == [T.quantize(v, VREF) for v in (1.0, 2.0, 3.0)]
