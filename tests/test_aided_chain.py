"""A real recording through the whole aided chain (issue 26): a BROAD excerpt (Laidig,
Caruso, Cereatti, Seel, Data 6(7), 2021, doi:10.3390/data6070072, CC BY 4.0) converted to
the board's codes (attitude_c.sim.board_codes), served by the TLC2543 model to the aided
firmware in s51, link v2 over a pty, attitude-rx (host, and ARMv4T under qemu-arm) with
its filter; against the library's filter run directly on the same converted samples.
The conversion itself against closed forms (no process)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import require_target, require_tools

from attitude_c import broad
from attitude_c.sim import board_codes as bc
from toolchain import aided_chain
from toolchain import firmware as tool

TRIAL = "07_undisturbed_fast_rotation_B"  # fast turns: rates up to 1450 °/s, the gyro range used
START, SECONDS = 30.0, 4.0  # inside its movement phase (26.5 s on): 200 samples at 50/s


def test_codes_round_trip_within_half_a_step_and_clip_at_the_range() -> None:
    ch = bc.board_channels()
    rng = np.random.default_rng(1)
    for c in ch.values():
        x = rng.uniform(-c.clip, c.clip, (500, 3))
        back = bc.values(bc.codes(x, c), c)
        # round to nearest: half a step, plus the double rounding of (code − 2048) · lsb (≤ 4096 · ulp)
        assert np.abs(back - x).max() <= c.lsb / 2 * (1 + 1e-12)
        big = bc.codes(np.full((1, 3), 10 * c.limit), c)
        assert (big == min(c.hi, round(bc.ZERO + c.limit * c.per_unit))).all()
    # the presets' resolutions (closed forms): ADXL335 0.3 V/g at 3 V over 4096 codes; AD623 G = 200
    # on 1 mV/V/gauss: 200 · 1e-3 · 4096 / 100 codes per µT
    assert ch["acc"].per_unit * 9.80665 == pytest.approx(0.3 / 3.0 * 4096, rel=1e-15)
    assert ch["mag"].per_unit == pytest.approx(200 * 1e-3 * 4096 / 100, rel=1e-15)
    assert ch["gyro"].per_unit * math.radians(2000.0) == pytest.approx(0.9 * 2048, rel=1e-15)


def test_rx_config_round_trips_the_scales() -> None:
    ch = bc.board_channels()
    kv = dict(ln.split(" = ") for ln in bc.rx_config(ch).splitlines())
    for c in ch.values():
        assert float(kv[f"{c.name}-scale"]) == c.lsb and int(kv[f"{c.name}-zero"]) == bc.ZERO


def test_data_file_holds_the_scan_order(tmp_path: Path) -> None:
    """Per sample: gyro, then the accelerometer and magnetometer when due, big-endian."""
    cfg = tool.Config(board="aided9", link="v2", baud=115200, acc_every=2, mag_every=4)
    g, a, m = (np.arange(15).reshape(5, 3) + 100 * i for i in range(3))
    n = tool.data_file(tmp_path / "d", cfg, g, a, m)
    words = np.frombuffer((tmp_path / "d").read_bytes(), dtype=">u2").reshape(-1, 3)
    want = [g[0], a[0], m[0], g[1], g[2], a[2], g[3], g[4], a[4], m[4]]
    assert n == len(want) == tool.data_records(cfg, 5)
    np.testing.assert_array_equal(words, want)


#: the default plan with the gyros oversampled (two conversions summed per sample)
#: (sums: link v2 carries them one record per RAW frame, so at a plan of 75 records/s, aiding every
#: 4th sample; docs/firmware.md "Gyro oversampling")
OVS2 = dataclasses.replace(tool.AIDED, gyro_oversample=2, acc_every=4, mag_every=4)
#: the gyros' two conversions sent as their rounded mean (a plain stream, packed by link v2), aiding
#: every 2nd sample (at the default plan's aiding in every sample this excerpt loses two samples at
#: 0.1 s, at startup, then none: docs/firmware.md "Gyro oversampling", not yet explained)
MEAN2 = dataclasses.replace(tool.AIDED, gyro_oversample=2, gyro_mean=True, acc_every=2, mag_every=2)


def _excerpt(config: tool.Config) -> bc.BoardRecording:
    folder = broad.default_dir()
    if folder is None:
        pytest.skip("BROAD data not found beside the checkout (../shared/data/broad)")
    return aided_chain.recording(broad.load_trial(folder / f"{TRIAL}.mat"), config, start=START, duration=SECONDS)


@pytest.fixture(scope="module")
def excerpt() -> bc.BoardRecording:
    return _excerpt(tool.AIDED)


def test_oversampled_recording_sums_the_conversions_at_the_sub_interval_midpoints() -> None:
    """Gyro oversampling: N conversions per sample, period/N apart, the last at the sample's
    instant (as the firmware's sub-scans); the words are their sums, and values() divides by N."""
    ch = bc.board_channels()

    class Ramp:  # a rate that rises 0.1 rad/s per second on every axis: the sub-instants readable
        rate = 100.0
        gyr = np.linspace(0.0, 1.0, 1001)[:, None] * np.ones(3)
        acc = mag = np.zeros((1001, 3))
        quat = np.tile([1.0, 0, 0, 0], (1001, 1))
        movement = np.ones(1001, bool)

    period = 0.04
    one, four = (bc.resample(Ramp(), period, ch, start=1.0, oversample=m) for m in (1, 4))
    sub = one.t[:, None] - (3 - np.arange(4)) * period / 4  # the sub-scans' instants
    np.testing.assert_array_equal(four.gyro_conversions, bc.codes((sub / 10).reshape(-1, 1) * np.ones(3), ch["gyro"])
                                  .reshape(-1, 4, 3))
    np.testing.assert_array_equal(four.codes["gyro"], four.gyro_conversions.sum(axis=1))
    np.testing.assert_array_equal(four.gyro_conversions[:, -1], one.codes["gyro"])  # the last at the instant
    # a sum of 4 codes / 4: the mean code, converted as attitude-rx converts (word / n − zero) · scale
    np.testing.assert_array_equal(bc.values(four.codes["gyro"], ch["gyro"], 4),
                                  (four.codes["gyro"] / 4 - bc.ZERO) * ch["gyro"].lsb)
    mean = bc.resample(Ramp(), period, ch, start=1.0, oversample=4, mean=True)
    np.testing.assert_array_equal(mean.codes["gyro"], (four.codes["gyro"] + 2) // 4)  # rounded, half up
    assert (mean.stream_n, four.stream_n) == (1, 4)
    with pytest.raises(ValueError, match="oversample"):
        bc.resample(Ramp(), period, ch, oversample=0)


def _chain(excerpt: bc.BoardRecording, tmp_path: Path, build: str,
           late: tuple[float, float] | None = None, config: tool.Config = tool.AIDED) -> aided_chain.ChainRun:
    from toolchain.tasks.cross import cross_build_target

    require_target("mcs52")
    require_tools("socat", apt="socat")  # toolchain.firmware.Session checks for it
    t = require_target(build)
    cmd = [*t.run_cmd, str(cross_build_target(build, out=tmp_path / build)["app"])]
    return aided_chain.run_chain(excerpt, cmd, tmp_path / "fw", late=late, config=config)


def _same_as_direct(run: aided_chain.ChainRun, excerpt: bc.BoardRecording, build: str,
                    config: tool.Config = tool.AIDED) -> None:
    q = aided_chain.direct(excerpt, config, lost=run.lost)
    # attitude-rx is built in double (ATT_REAL_F64) like the package's filter: the host build runs
    # the same C with the same IEEE operations and prints 17 digits (round trip), so the
    # quaternions are equal. ARMv4T: soft-float libm (sqrt, atan2, sin, cos) may differ from the
    # host's in the last ulp; the filter is stable, so 200 samples keep that below 1e-12.
    np.testing.assert_allclose(run.q, q, rtol=0, atol=0.0 if build == "host" else 1e-12)
    # and so BROAD's figure of the chain is the direct filter's: the target is 0.1°; equal
    # quaternions (within 1e-12) give the same RMS error within 1e-9° (rounding of the metric)
    e_chain = broad.errors(run.q, excerpt.quat, excerpt.movement).total
    assert e_chain == pytest.approx(broad.errors(q, excerpt.quat, excerpt.movement).total, abs=1e-9)


@pytest.mark.system
@pytest.mark.parametrize("build", ["host", pytest.param("armv4t", marks=pytest.mark.qemu)])
def test_broad_excerpt_through_the_chain_equals_the_library_filter(excerpt: bc.BoardRecording, tmp_path: Path,
                                                                     build: str) -> None:
    run = _chain(excerpt, tmp_path, build)
    # s51 runs in lockstep with attitude-rx (toolchain.aided_chain.Relay): every ACK reaches the
    # firmware within LOCKSTEP_BOUND_S of simulated time, however late attitude-rx is in wall time
    # (qemu-arm, a loaded machine), so the firmware's ring never fills: every record delivered once
    assert run.delivered_once(excerpt.n), (run.reports, run.stats)
    assert [r["report"] for r in run.reports] == ["BOOT", "CHANNELS"]
    assert run.stats["records"] >= tool.data_records(tool.AIDED, excerpt.n) + 2  # + BOOT, CHANNELS
    assert run.firmware["overrun_pending"] == 0 and run.stats["overrun"] == 0
    # one ACK per frame (no window update: the queue never filled), each within two steps
    assert run.stats["acks"] == run.stats["frames"] == run.frames, run.stats
    assert 0 < 2 * run.max_step_s <= tool.LOCKSTEP_BOUND_S
    _same_as_direct(run, excerpt, build)


@pytest.mark.system
@pytest.mark.parametrize("config", [OVS2, MEAN2], ids=["sums", "mean"])
def test_oversampled_gyros_through_the_chain_equal_the_library_filter(tmp_path: Path, config: tool.Config) -> None:
    """The same with gyro oversampling (N = 2): the TLC2543 model serves two gyro conversions per
    sample; the firmware sends their sums after an OVERSAMPLE report, attitude-rx divides by 2 (and
    the accelerometer's and magnetometer's words, their code times 2, back to the code) — or, with
    ``gyro_mean``, their rounded mean as a plain code: its quaternions are the
    direct filter's on the same words converted as attitude-rx converts them."""
    rec = _excerpt(config)
    run = _chain(rec, tmp_path, "host", config=config)
    assert run.delivered_once(rec.n), (run.reports, run.stats)
    head = ["BOOT", "CHANNELS"] if config.gyro_mean else ["BOOT", "OVERSAMPLE", "CHANNELS"]
    assert [r["report"] for r in run.reports] == head
    assert config.gyro_mean or run.reports[1]["n"] == 2
    assert run.stats["records"] >= tool.data_records(config, rec.n) + len(head)
    _same_as_direct(run, rec, "host", config)


#: The host made late on purpose: its answers held back this long (simulated s) from this instant,
#: inside the excerpt's 4 s (its samples start a few tens of ms after reset)
LATE_AT, LATE_S = 1.5, 0.5


@pytest.mark.system
def test_a_host_late_on_purpose_loses_samples_reported_and_held(excerpt: bc.BoardRecording, tmp_path: Path) -> None:
    run = _chain(excerpt, tmp_path, "host", late=(LATE_AT, LATE_S))
    # no ACK for LATE_S: the firmware's 16-record ring fills and it loses whole samples, each
    # reported in place (OVERRUN); once the answers flow again (within LOCKSTEP_BOUND_S) it drains.
    # So the losses lie in that window: at most its length in sample periods, plus the one in progress
    assert [r["report"] for r in run.reports[:2]] == ["BOOT", "CHANNELS"]
    assert run.reports[2:] and all(r["report"] == "OVERRUN" for r in run.reports[2:]), run.reports
    period = tool.AIDED.period_s
    assert 1 <= len(run.lost) <= (LATE_S + tool.LOCKSTEP_BOUND_S) / period + 1, run.lost
    assert run.lost[-1] - run.lost[0] < len(run.lost) + (LATE_S + tool.LOCKSTEP_BOUND_S) / period
    # every sample still printed once, in order: attitude-rx holds the lost ones (the last rate, no
    # aiding), and so does the direct filter given the same list
    assert run.ns[:excerpt.n] == list(range(excerpt.n)), run.ns[:5]
    assert run.stats["bad_frames"] == 0 and run.stats["held"] >= len(run.lost), run.stats
    _same_as_direct(run, excerpt, "host")
