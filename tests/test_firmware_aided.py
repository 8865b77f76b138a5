"""The aided board's firmware (AT89S52, ``Config(board="aided9")``, firmware/config.h
FW_AIDED): nine TLC2543 channels, link v2 on Timer 2, BOOT + CHANNELS, sample groups.

* the image fits the AT89S52 (8 KB / 256 B) with the stack s51 measures plus a margin;
  the configuration refuses what the board cannot do;
* in s51 (C52 core) with libattitude's link v2 receiver on the pty, the C one and the
  Python one, for a decimated plan and for the default (aiding in every sample): BOOT (link v2, the period, the baud), CHANNELS (board, channel set,
  decimations), then groups numbered by the block format's tracker in order, every record
  in its place (gyro, accelerometer when n % acc_every == 0, magnetometer when
  n % mag_every == 0) and every code within 1 LSB of the device model's closed form
  (toolchain.firmware.GYROS, AUX) at its sample's number;
* the UART's bit time on Timer 2: the firmware times two back-to-back bytes at 57600
  and 115200 baud; the software's constant share cancels in the difference, which must
  be 10 bit times of the difference in rate;
* a failing ADC self-test at power-up: SELFTEST reports after BOOT and CHANNELS.

s51 runs in simulated time, the host in wall time: a host descheduled on a loaded
machine shows up as latency, which the firmware survives by reporting the samples it
could not keep (OVERRUN) in their place; the checks hold for any number of them.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import require_target, require_tools

from attitude_c.link import block
from toolchain import firmware as tool

pytestmark = pytest.mark.system  # builds the aided firmware and runs it in s51

#: the margin of stack s51 never saw used that tests/test_firmware.py requires too
STACK_MARGIN = 4
#: the test's plan: 50 samples/s, accelerometer every 2nd, magnetometer every 4th sample
CFG = dataclasses.replace(tool.AIDED, period_ticks=72, acc_every=2, mag_every=4)
#: model input of each channel: gyros on AIN0-2, accelerometer AIN3-5, magnetometer AIN6-8
CHANNELS = (*tool.GYROS, *tool.AUX)
PART_AIN = {"gyr": 0, "acc": 3, "mag": 6}


def _need() -> None:
    require_target("mcs52")
    require_tools("socat", apt="socat")


@pytest.fixture(scope="module")
def out(build_root: Path) -> Path:
    return build_root / "firmware_aided"


def test_aided_image_fits_the_at89s52(out: Path) -> None:
    require_target("mcs52")
    img = tool.build(out, tool.AIDED, kind="production")
    print(img.size_report())
    assert img.flash <= tool.FLASH_SIZE_52 and img.ram_static <= tool.IRAM_SIZE_52
    for bad, msg in [(dict(link="legacy"), "link v2 only"), (dict(baud=9000), "baud"),
                     (dict(acc_every=3), "acc_every"), (dict(mag_every=256), "mag_every"),
                     (dict(v2_batch=17), "v2_batch"), (dict(v2_hold=40000), "v2_hold"),
                     (dict(mag_sr=True, mag_every=0), "mag_sr")]:
        with pytest.raises(ValueError, match=msg):
            dataclasses.replace(tool.AIDED, **bad)
    with pytest.raises(ValueError, match="aided board"):  # batching is the aided image's only
        tool.Config(link="v2", v2_batch=2)
    with pytest.raises(ValueError, match="mag_sr"):
        tool.Config(link="v2", mag_sr=True)
    for bad, msg in [(dict(gyro_oversample=3), "gyro_oversample must be one of"),
                     (dict(gyro_oversample=4, period_ticks=74), "multiple"), (dict(gyro_mean=True), "gyro_mean")]:
        with pytest.raises(ValueError, match=msg):
            dataclasses.replace(tool.AIDED, **bad)
    with pytest.raises(ValueError, match="aided board"):
        tool.Config(gyro_oversample=2)
    with pytest.raises(ValueError, match="baud"):  # 115200 is Timer 2's, not Timer 1's
        tool.Config(baud=115200)
    assert 115200 in tool.BAUD_RATES_T2 and 57600 in tool.BAUD_RATES_T2


def test_crc_table_is_crc32c() -> None:
    """The aided image's CRC table (toolchain.firmware.crc32c_table, ATT_LINK2_CRC_TABLE)
    gives CRC-32C's check value on "123456789" (0xE3069283, docs/link.md); the image's own
    lookup code prints it in every sim run below."""
    t = tool.crc32c_table()
    reg = 0xFFFFFFFF
    for b in b"123456789":
        reg = (reg >> 8) ^ t[(reg ^ b) & 0xFF]
    assert reg ^ 0xFFFFFFFF == 0xE3069283


def _uart_cycles(output: str) -> int:
    line = next(ln for ln in output.splitlines() if ln.startswith("UART "))
    return int(line.split()[1], 16)


def _check_stream(records: list[bytes], cfg: tool.Config) -> int:
    """The stream against the format and the model; returns the sample records seen."""
    stream = block.number_stream(records)  # strict: a slip or a cut group raises
    boot, chans = stream[0][0], stream[1][0]
    assert (boot.kind, boot.link, boot.period_ticks, boot.baud) == ("boot", "v2", cfg.period_ticks, cfg.baud)
    assert (chans.kind, chans.board, chans.channels, chans.acc_every, chans.mag_every) == (
        "channels", "aided9", ("gyr", "acc", "mag"), cfg.acc_every, cfg.mag_every)
    want: list[tuple[int, str]] = []  # (sample, part) of every record the tracker placed, by the rule
    got: list[tuple[int, str]] = []
    n_samples = 0
    for rec, span in stream[2:]:
        if rec.kind != "sample":
            assert rec.kind == "overrun", rec  # the only report a healthy run may send
            continue
        got.append((span.first, span.part))
        if span.part == "gyr":
            n = span.first
            want += [(n, "gyr")] + [(n, p) for p, every in (("acc", cfg.acc_every), ("mag", cfg.mag_every))
                                    if n % every == 0]
        # the model's input at sample n (exact sine); the converter floors, the model's
        # sine table adds < 0.02 LSB: within 1 LSB (docs/firmware.md)
        for axis, code in enumerate(rec.codes):
            lsb = CHANNELS[PART_AIN[span.part] + axis].lsb(span.first)
            if span.part == "mag" and not cfg.mag_sr:
                lsb += tool.BRIDGE / 16  # the model's bridge offset, which set/reset cancels
            assert abs(code - math.floor(lsb)) <= 1, (span, axis, code, lsb)
        n_samples += 1
    assert got == want[:len(got)] and len(want) - len(got) <= 2  # the last group may still be under way
    return n_samples


PLANS = {"test": CFG, "default": tool.AIDED, "sr": dataclasses.replace(tool.AIDED, mag_sr=True)}


@pytest.mark.parametrize("impl,baud,plan", [("c", 115200, "test"), ("python", 57600, "test"),
                                           ("c", 115200, "default"), ("c", 115200, "sr")])
def test_aided_firmware_delivers_groups_in_order(out: Path, impl: str, baud: int, plan: str) -> None:
    """The test's plan (decimated aiding: frames mostly started by the hold's 30 ms), the
    shipped default (aiding in every sample: frames of a batch or more; the magnetometer's
    codes carry the model's bridge offset) and the default with set/reset (the offset
    cancelled: the codes the model's field gives)."""
    _need()
    cfg = dataclasses.replace(PLANS[plan], baud=baud)
    n = 60
    img = tool.build(out, cfg, kind="sim", sim_samples=n, name=f"aided_{impl}_{baud}_{plan}")
    res = tool.run_v2(img, impl, timeout=180)  # type: ignore[arg-type]
    assert "CRC E3069283" in res.output.upper()
    assert _check_stream(res.records, cfg) >= n
    assert res.receiver["duplicates"] == 0 and res.receiver["bad_frames"] == 0
    assert res.max_sp <= cfg.iram_size - 1 - STACK_MARGIN, f"SP reached 0x{res.max_sp:02X}"
    # 10 bits on Timer 2 (docs/firmware.md); the byte after: ISR, return, next write
    bit = tool.MACHINE_HZ / baud
    print(f"\n{impl} receiver, {baud} baud: {res.stats}; receiver {res.receiver}; max SP 0x{res.max_sp:02X}; "
          f"two bytes {_uart_cycles(res.output)} cycles apart (10 bits = {10 * bit:.0f})")
    assert 10 * bit <= _uart_cycles(res.output) <= 10 * bit + 100


def test_timer2_bit_time(out: Path) -> None:
    """Two bytes timed by the firmware at 57600 and at 115200 baud: the software between
    them is the same code, so the difference is 10 bit times' difference, 10 x (16 - 8)
    machine cycles, to within one bit of UART start synchronisation (8 cycles)."""
    _need()
    t = {}
    for baud in (57600, 115200):
        img = tool.build(out, dataclasses.replace(CFG, baud=baud), kind="sim", sim_samples=2, name=f"uart_{baud}")
        t[baud] = _uart_cycles(tool.run_v2(img, "c", timeout=120).output)
    want = 10 * (tool.MACHINE_HZ / 57600 - tool.MACHINE_HZ / 115200)
    print(f"\nUART: {t}; difference {t[57600] - t[115200]} cycles, 10 bits' difference {want:.0f}")
    assert abs((t[57600] - t[115200]) - want) <= tool.MACHINE_HZ / 115200


def test_selftest_failure_is_reported_after_boot_and_channels(out: Path) -> None:
    _need()
    img = tool.build(out, CFG, kind="sim", sim_blocks=3, faults=["dout_stuck_high"], name="aided_selftest")
    res = tool.run_v2(img, "c", timeout=120)
    recs = [block.decode(r) for r in res.records]
    assert [r.kind for r in recs[:3]] == ["boot", "channels", "selftest"]
    assert (recs[2].status, recs[2].bad_code, recs[2].attempt) == (-41, 0xFFF, 1)  # MID read 0xFFF


@pytest.mark.parametrize("n_ovs,mean", [(2, False), (4, False), (2, True)])
def test_oversampled_gyro_sums_equal_the_models_codes_summed(out: Path, tmp_path: Path, n_ovs: int,
                                                             mean: bool) -> None:
    """Gyro oversampling (``gyro_oversample`` N, FW_GYRO_OVERSAMPLE): the TLC2543 model serves
    codes from a file, one per conversion (N gyro triples per sample, then the accelerometer's
    and magnetometer's when due: toolchain.firmware.data_file); the stream is BOOT, OVERSAMPLE N,
    CHANNELS, then groups whose gyro words are exactly the sums of their sample's N triples and
    whose accelerometer and magnetometer words are exactly N times their one code (a receiver's
    division by N gives the code back), every group at its sample's number (losses skip groups
    in the file: the tracker's numbers still match). ``gyro_mean``: no OVERSAMPLE report, the
    gyro words the rounded means (sum + N/2) // N, the others the codes themselves."""
    _need()
    cfg = dataclasses.replace(CFG, gyro_oversample=n_ovs, gyro_mean=mean)
    n, pad = 40, 32  # pad: the firmware scans ahead of its acknowledgements (toolchain.aided_chain)
    rng = np.random.default_rng(n_ovs)
    gyro = rng.integers(0, 4096, (n + pad, n_ovs, 3))
    acc, mag = rng.integers(0, 4096, (2, n + pad, 3))
    tool.data_file(tmp_path / "codes.bin", cfg, gyro, acc, mag)
    img = tool.build(out, cfg, kind="sim", sim_samples=tool.data_records(cfg, n), data=True,
                     name=f"aided_ovs{n_ovs}{'_mean' if mean else ''}")
    res = tool.run_v2(img, "c", timeout=180, data=tmp_path / "codes.bin")
    stream = block.number_stream(res.records)  # strict: a slip or a cut group raises
    head = ["boot", "channels"] if mean else ["boot", "oversample", "channels"]
    assert [r.kind for r, _ in stream[:len(head)]] == head
    assert mean or stream[1][0].oversample == n_ovs
    k = cfg.stream_n  # the receiver's divisor
    want = {"gyr": (gyro.sum(axis=1) + n_ovs // 2) // n_ovs if mean else gyro.sum(axis=1), "acc": k * acc,
            "mag": k * mag}
    seen = lost = 0
    for rec, span in stream[len(head):]:
        if rec.kind != "sample":
            assert rec.kind == "overrun", rec  # the only report a healthy run may send
            lost += rec.count
        elif span.first < n + pad:  # past the file's end the model reads code 0
            assert list(rec.codes) == list(want[span.part][span.first]), (span, rec.codes)
            seen += 1
    print(f"\nN = {n_ovs}, mean {mean}: {seen} records checked, {lost} samples lost (OVERRUN); max SP 0x{res.max_sp:02X}")
    assert seen >= tool.data_records(cfg, n) // 2  # most: a host late in wall time loses some
    assert res.max_sp <= cfg.iram_size - 1 - STACK_MARGIN, f"SP reached 0x{res.max_sp:02X}"
