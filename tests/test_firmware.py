"""AT89S51 firmware (firmware/): SDCC build limits and whole-firmware runs in s51.

Every run is ``s51 -t C51 -R 1`` in lockstep with libattitude's C receiver B
(through CFFI) on its UART (:class:`toolchain.firmware.LinkHost`,
:func:`toolchain.firmware.run`: simulated time advances only while the host is
caught up); the firmware stops itself through the simulator interface after a
given number of accepted blocks, and every s51 process is killed in a
``finally`` (wall-clock timeouts on all).

Images (toolchain/firmware.py): ``production`` (what goes into the chip),
``bench`` (production pins and RAM layout, cycle counters in unused SFR
cells) and ``sim`` (the production driver and HAL with the pins pointed at
a TLC2543 + gyro model kept in unused SFR cells: same RAM layout again).
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from conftest import require_target, require_tools

from toolchain import firmware as tool

pytestmark = pytest.mark.system  # builds the firmware and runs it in s51

#: Stack margin we require in the production RAM layout: the highest SP
#: s51 sees running the bench image (production code, RAM layout and call
#: depth) must leave at least this many bytes below 0x80.
STACK_MARGIN = 4

#: Sampling period of the long runs: 216 ticks = 60 ms. One exchange is 10
#: byte times = 10.4 ms at 9600 baud, plus the host's latency: up to one
#: lockstep step per wait (two waits, each <= tool.LOCKSTEP_BOUND_S = 43 ms,
#: ~16 ms measured); 60 ms and the two-slot queue keep the samples.
PERIOD = 216
#: Link timeouts of the test images: 720 ticks = 200 ms of simulated time,
#: well above a lockstep step, so a host is never mistaken for a silent one
#: (the silence test counts timeouts exactly).
TIMEOUT = 720


def _need() -> None:
    require_target("mcs51")
    require_tools("socat", apt="socat")


@pytest.fixture(scope="module")
def out(build_root: Path) -> Path:
    return build_root / "firmware"


def _samples(stream: list) -> list[tool.Sample]:
    return [x for x in stream if isinstance(x, tool.Sample)]


def _assert_match_model(samples: list[tool.Sample]) -> None:
    """Each code within 1 LSB of its gyro's analog input at the sample's time.

    The model quantizes v >> 4 (floor of the input in LSB), and its sine
    table is rounded to 1/32767 (< 0.02 LSB at these amplitudes): the code
    is within 1 LSB of the exact analog value, never more.
    """
    for s in samples:
        for c, g in enumerate(tool.GYROS):
            exact = g.lsb(s.seq)
            assert abs(s.codes[c] - exact) <= 1.0, (s.seq, "XYZ"[c], s.codes[c], exact)


# -- build ---------------------------------------------------------------------

@pytest.mark.parametrize("baud", [9600, 57600])
def test_production_image_fits_the_at89s51(out: Path, baud: int) -> None:
    require_target("mcs51")
    img = tool.build(out, tool.Config(baud=baud), kind="production")
    print(img.size_report())
    assert img.flash <= tool.FLASH_SIZE
    assert img.stack_start + img.stack_free == tool.IRAM_SIZE
    # static RAM leaves room for the stack the bench run measures (15 bytes)
    assert img.stack_free >= 15 + STACK_MARGIN


def test_sim_image_that_never_stops_compiles(out: Path) -> None:
    """sim_blocks=0 is documented as "run until the simulator is stopped"."""
    require_target("mcs51")
    img = tool.build(out, kind="sim", sim_blocks=0, name="fw_forever")
    assert img.ihx.exists()
    with pytest.raises(ValueError, match="adc_error_at=K"):
        tool.build(out, kind="sim", faults=["adc_error_at=300"], name="fw_bad_fault")


def test_build_fails_when_the_image_does_not_fit(out: Path) -> None:
    require_target("mcs51")
    with pytest.raises(tool.FirmwareTooBig, match="does not fit"):
        tool.build(out, kind="production", code_size=2048, name="too_small")


def test_config_rejects_rates_the_crystal_cannot_make() -> None:
    with pytest.raises(ValueError, match="baud"):
        tool.Config(baud=38400)  # 11.0592 MHz / 384 / 38400 = 0.75: not an integer reload
    with pytest.raises(ValueError, match="period_ticks"):
        tool.Config(period_ticks=0)


# -- whole firmware in s51 ---------------------------------------------------------

def test_stack_in_the_production_layout(out: Path) -> None:
    """Bench image (production code and RAM layout): handshakes and the stack high-water mark."""
    _need()
    img = tool.build(out, tool.Config(period_ticks=PERIOD, syn_timeout=TIMEOUT, answer_timeout=TIMEOUT), kind="bench", sim_blocks=20)
    res = tool.run(img, tool.LinkHost(), timeout=60)
    print(img.size_report(), f"max SP 0x{res.max_sp:02X}")
    assert res.stats["accepted"] == 20 and res.host.stats()["blocks_accepted"] == 20
    assert res.bench["scans"] >= 15
    assert res.max_sp <= 0x7F - STACK_MARGIN


@pytest.mark.parametrize("impl,n", [("c", 200), ("python", 50)])
def test_200_samples_match_the_analog_inputs(out: Path, impl: str, n: int) -> None:
    """At least 200 samples, in order, every loss reported in place, each within 1 LSB of its input.

    The run stops after n + 20 accepted sample records (a count of samples, not of
    blocks: a loss report takes no sample's place in the count), normally with no
    loss. s51 runs in simulated time while the host answers over a pty in wall
    time: a host that stalls long enough lets the two-slot queue overflow; the
    firmware then reports the loss in place (OVERRUN), which decode_stream checks
    against the numbering (s51 runs niced under the host, toolchain/firmware.py,
    so that a loaded machine slows the simulation down instead). The test
    requires n samples and at most 10 % of the periods lost (every one reported),
    and prints the longest unbroken run. The Python receiver runs a shorter
    interoperability check (n = 50).
    """
    _need()
    cfg = tool.Config(period_ticks=PERIOD, syn_timeout=TIMEOUT, answer_timeout=TIMEOUT)
    img = tool.build(out, cfg, kind="sim", sim_samples=n + 20, name=f"fw_{n}_{impl}")
    res = tool.run(img, tool.LinkHost(impl), timeout=180)
    print(f"{img.size_report()}; {res.sim_seconds:.2f} s simulated in {res.wall_seconds:.1f} s, "
          f"max SP 0x{res.max_sp:02X}; host {res.host.stats()}")
    stream = res.stream  # raises if a loss report does not match the numbering
    assert isinstance(stream[0], tool.Report) and stream[0].kind == "boot"
    assert stream[0].link == "legacy" and stream[0].raw[3] & 0x80 == 0  # the legacy build announces legacy
    samples = _samples(stream)
    assert [s.seq for s in samples] == sorted({s.seq for s in samples})  # in order, no duplicate
    _assert_match_model(samples)
    run = best = 1
    for a, b in zip(samples, samples[1:]):
        run = run + 1 if b.seq == a.seq + 1 else 1
        best = max(best, run)
    lost = sum(x.count for x in stream[1:] if isinstance(x, tool.Report))
    print(f"longest run of consecutive samples: {best}; samples lost (reported): {lost}")
    assert len(samples) >= n and lost <= (len(samples) + lost) // 10
    assert all(x.kind == "overrun" for x in stream[1:] if isinstance(x, tool.Report))
    assert res.stats["naks"] == 0 and res.stats["gave_up"] == 0
    # one model step per scan; at the stop up to two scanned blocks may still be queued
    assert len(samples) <= res.stats["conversions"] <= len(samples) + 2
    assert res.max_sp <= 0x7F  # the sim image has the production RAM layout


def test_nak_resends_exactly_those_blocks_and_silence_times_out(out: Path) -> None:
    _need()
    cfg = tool.Config(period_ticks=PERIOD, syn_timeout=TIMEOUT, answer_timeout=TIMEOUT, max_attempts=3)
    img = tool.build(out, cfg, kind="sim", sim_blocks=24, name="fw_faults")
    host = tool.LinkHost(nak_blocks={3, 8}, silent={12: 2, 16: 3})
    res = tool.run(img, host, timeout=90)
    print(f"firmware {res.stats}; host {host.stats()}")
    # 0xFF: the receiver rejected the corrupted first attempt of blocks 3 and 8 ...
    naks = [i for i, a in enumerate(host.attempts) if a.answer == 0xFF]
    assert [host.attempts[i].index for i in naks] == [3, 8]
    for i in naks:  # ... and the firmware sent exactly the same block again, accepted
        again = host.attempts[i + 1]
        assert again.index == host.attempts[i].index and again.answer == 0x00
        assert again.data == host.attempts[i].data
    # silence after 0xAA: 2 timeouts then success for block 12; 3 = max_attempts for block 16
    assert host.ignored_syn == [12, 12, 16, 16, 16]
    assert res.stats["naks"] == 2 and res.stats["timeouts"] == 5 and res.stats["gave_up"] == 1
    stream = res.stream  # decode_stream checks every loss report's sample number
    gave_up = [x for x in stream if isinstance(x, tool.Report) and x.kind == "gave_up"]
    assert len(gave_up) == 1 and gave_up[0].count == 1
    assert stream.index(gave_up[0]) == 16  # reported in the place of the block given up
    samples = _samples(stream)
    assert gave_up[0].first not in {s.seq for s in samples}
    _assert_match_model(samples)  # the numbering survived the losses


@pytest.mark.parametrize("fault,status,code", [
    ("dout_stuck_high", -41, 0xFFF),  # mid-scale test input reads 0xFFF
    ("dout_stuck_low", -41, 0x000),   # ... reads 0x000
    ("eoc_stuck", -40, 0x000),        # EOC never rises: timeout
])
def test_selftest_failure_is_reported_over_the_link(out: Path, fault: str, status: int, code: int) -> None:
    _need()
    cfg = tool.Config(selftest_retry=36)  # retry every 10 ms
    img = tool.build(out, cfg, kind="sim", sim_blocks=3, faults=[fault], name=f"fw_{fault}")
    res = tool.run(img, tool.LinkHost(), timeout=60)
    stream = res.stream
    assert [x.kind for x in stream] == ["boot", "selftest", "selftest"]
    for attempt, rep in enumerate(stream[1:], start=1):
        assert (rep.status, rep.bad_code, rep.attempt) == (status, code, attempt)
    assert res.stats["samples"] >= 2  # no sampling: seq counts the failed attempts


def test_adc_error_is_reported_in_the_lost_samples_place(out: Path) -> None:
    """A scan that fails once (EOC stuck, sim fault adc_error_at=K) becomes an ADC_ERROR
    report for exactly that sample; the numbering and the samples after it are intact."""
    _need()
    cfg = tool.Config(period_ticks=PERIOD, syn_timeout=TIMEOUT, answer_timeout=TIMEOUT)
    img = tool.build(out, cfg, kind="sim", sim_blocks=12, faults=["adc_error_at=5"], name="fw_adc_error")
    res = tool.run(img, tool.LinkHost(), timeout=60)
    stream = res.stream  # decode_stream checks the report's sample number against the count
    errs = [x for x in stream if isinstance(x, tool.Report) and x.kind == "adc_error"]
    assert len(errs) == 1 and errs[0].status == -40  # TLC2543_E_EOC_TIMEOUT
    lost = errs[0].first
    assert lost >= 5  # sample 5, or the first one scanned after it (an overrun in between)
    samples = _samples(stream)
    assert lost not in {s.seq for s in samples} and max(s.seq for s in samples) > lost
    _assert_match_model(samples)


class _StallingHost(tool.LinkHost):
    """A host end descheduled (fault injection: a sleep standing for the OS running
    something else) for ``stall_s`` of wall time between accepting block ``at`` and
    answering it."""

    def __init__(self, at: int, stall_s: float) -> None:
        super().__init__()
        self.at, self.stall_s = at, stall_s

    def receive(self, data: bytes) -> bytes:
        before = len(self.blocks)
        reply = super().receive(data)
        if before <= self.at < len(self.blocks):
            time.sleep(self.stall_s)
        return reply


def test_a_descheduled_host_answers_in_time_in_simulated_time(out: Path) -> None:
    """Issue 27: s51 ran on while the host was descheduled, the firmware's answer timeout
    ran out for a block the host had accepted, and the legacy protocol delivered it
    twice (docs/link.md). In lockstep the firmware sees the answer within one step
    however long the host stalls: no timeout, no resend, the ADC error in its place."""
    _need()
    cfg = tool.Config(period_ticks=PERIOD, syn_timeout=TIMEOUT, answer_timeout=TIMEOUT)
    img = tool.build(out, cfg, kind="sim", sim_blocks=12, faults=["adc_error_at=5"], name="fw_stalled_host")
    # five answer timeouts of wall time: free-running s51 (>= 0.6 x real time, loaded) would time out
    host = _StallingHost(at=6, stall_s=5 * TIMEOUT / tool.TICK_HZ)
    res = tool.run(img, host, timeout=60)
    assert res.stats["timeouts"] == 0 and res.stats["sent"] == res.stats["accepted"] == 12
    assert [a.index for a in host.attempts] == list(range(12))  # one attempt per block: no resend
    assert 0 < res.max_step_s <= tool.LOCKSTEP_BOUND_S < TIMEOUT / tool.TICK_HZ
    errs = [x for x in res.stream if isinstance(x, tool.Report) and x.kind == "adc_error"]
    assert len(errs) == 1 and errs[0].first >= 5  # decode_stream checked it against the count
    _assert_match_model(_samples(res.stream))


def test_fastest_baud_57600(out: Path) -> None:
    _need()
    # an exchange is 1.7 ms on the wire at 57600; the period covers the host's latency
    cfg = tool.Config(baud=57600, period_ticks=PERIOD, syn_timeout=TIMEOUT, answer_timeout=TIMEOUT)
    img = tool.build(out, cfg, kind="sim", sim_blocks=41)
    res = tool.run(img, tool.LinkHost(), timeout=60)
    stream = res.stream  # decode_stream checks the numbering across any loss report
    samples = _samples(stream)
    # s51 may run faster than real time while the host answers in wall time: on a loaded
    # machine a late answer can cost an overrun, which the firmware reports in place
    assert len(samples) >= 35 and all(x.kind == "overrun" for x in stream[1:] if isinstance(x, tool.Report))
    assert [s.seq for s in samples] == sorted({s.seq for s in samples})
    _assert_match_model(samples)
    assert res.stream[0].raw[5] == 57600 // 1200  # the BOOT report carries the rate


# -- stream decoding (pure Python) --------------------------------------------------

def test_decode_stream_numbers_samples_across_loss_reports() -> None:
    boot = bytes([0xFE, 0, 1, 0, 108, 8])
    s = lambda a: bytes([0, a, 0, a, 0, a])
    over = bytes([0xFE, 3, 0, 2, 0, 3])  # samples 2, 3, 4 lost
    out = tool.decode_stream([boot, s(1), s(2), over, s(3)])
    assert [x.seq for x in out if isinstance(x, tool.Sample)] == [0, 1, 5]
    with pytest.raises(tool.FirmwareError, match="expected 2"):
        tool.decode_stream([boot, s(1), s(2), bytes([0xFE, 2, 0, 7, 0, 1])])
    with pytest.raises(tool.FirmwareError, match="sample code above 4095"):
        tool.decode_stream([bytes([0x10, 0, 0, 0, 0, 0])])
