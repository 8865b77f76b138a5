"""The block format (csrc/include/attitude/block.h): the Python wrapper over the
C encoder/decoder (attitude_c.link.block), an independent reading of the
format written from the header's table, the SDCC build of the encoders the
firmware links, and a guard that the format is written down only once.

The C test program csrc/tests/test_block.c runs under ASan/UBSan
(test_c_programs.py) and on ARMv4T (test_cross_bare.py)."""

from __future__ import annotations

import re
import subprocess
import time
from pathlib import Path

import pytest
from conftest import ROOT, require_tools
from hypothesis import given, settings
from hypothesis import strategies as st

from attitude_c.errors import BlockFormatError, InvalidArgument, InvalidType
from attitude_c.link import block

KINDS = ["boot", "selftest", "gave_up", "overrun", "adc_error", "oversample", "channels"]


def _channels_ok(board: int, ch: int, acc: int, mag: int) -> bool:
    """CHANNELS' fields by block.h's list: board 1 (gyros alone) or 2; gyros always; no bit
    above the magnetometer's; a decimation exactly for each of accelerometer, magnetometer."""
    return ((board == 2 or (board == 1 and ch == 1)) and ch & 1 == 1 and ch < 8
            and (ch & 2 != 0) == (acc != 0) and (ch & 4 != 0) == (mag != 0))


def _spec(raw: bytes) -> tuple[str, bool]:
    """(kind, valid) of 6 bytes, read from block.h's table by hand: the second opinion."""
    if raw[0] != 0xFE:
        words = [raw[i] << 8 | raw[i + 1] for i in (0, 2, 4)]
        return "sample", all(w <= 4095 for w in words)
    if raw[1] >= len(KINDS):
        return "unknown", False
    kind = KINDS[raw[1]]
    w34, w45 = raw[3] << 8 | raw[4], raw[4] << 8 | raw[5]
    ok = {"boot": raw[2] == 1 and 1 <= w34 & 0x7FFF and raw[5] != 0,  # top bit: the link v2 flag
          "selftest": raw[2] >= 0x80 and w34 <= 4095,
          "gave_up": w45 != 0, "overrun": w45 != 0,
          "adc_error": raw[4] >= 0x80 and raw[5] == 0,
          "oversample": 1 <= raw[2] <= 16 and raw[3:] == b"\0\0\0",
          "channels": _channels_ok(*raw[2:])}[kind]
    return kind, ok


def test_constants_come_from_the_library() -> None:
    from attitude_c._lib import ffi_lib

    _, lib = ffi_lib("f64")
    f = block.fmt()
    assert (f.size, f.code_max, f.mark, f.version, f.tick_hz) == (
        lib.ATT_BLOCK_SIZE, lib.ATT_BLOCK_CODE_MAX, lib.ATT_BLOCK_MARK, lib.ATT_BLOCK_VERSION, lib.ATT_BLOCK_TICK_HZ)
    assert sorted(f.kinds.values()) == sorted(["sample", *KINDS])


def test_encoders_give_the_bytes_of_the_table() -> None:
    assert block.encode_sample([0x123, 4095, 0]) == bytes.fromhex("01230fff0000")
    assert block.encode_boot(72, 9600) == bytes.fromhex("fe0001004808")  # docs/firmware.md's first block
    # a link v2 board: the top bit of the period word (docs/block.md)
    assert block.encode_boot(72, 9600, "v2") == bytes.fromhex("fe0001804808")
    r = block.decode(bytes.fromhex("fe0001804808"))
    assert (r.link, r.period_ticks, r.as_dict()["link"]) == ("v2", 72, "v2")
    assert block.decode(bytes.fromhex("fe0001004808")).link == "legacy"
    with pytest.raises(InvalidArgument, match="link"):
        block.encode_boot(72, 9600, "v3")  # type: ignore[arg-type]
    assert block.encode_selftest(-41, 0xFFF, 3) == bytes.fromhex("fe01d70fff03")
    assert block.encode_loss("gave_up", 0x1234, 1) == bytes.fromhex("fe0212340001")
    assert block.encode_loss("overrun", 2, 3) == bytes.fromhex("fe0300020003")
    assert block.encode_adc_error(7, -40) == bytes.fromhex("fe040007d800")


def test_decode_fields_and_errors() -> None:
    r = block.decode(block.encode_boot(216, 57600))
    assert (r.kind, r.version, r.period_ticks, r.baud, r.period_s) == ("boot", 1, 216, 57600, 0.06)
    assert r.as_dict() == {"report": "BOOT", "version": 1, "period_ticks": 216, "period_s": 0.06, "baud": 57600}
    r = block.decode(block.encode_adc_error(9, -40))
    assert (r.kind, r.first, r.count, r.status, r.is_loss) == ("adc_error", 9, 1, -40, True)
    assert block.decode(bytes([0, 1, 0, 2, 0, 3])).codes == (1, 2, 3)
    with pytest.raises(BlockFormatError, match=r"record 4 10 00 00 00 00 00: sample code above 4095") as e:
        block.decode(bytes([0x10, 0, 0, 0, 0, 0]), index=4)
    assert e.value.index == 4 and isinstance(e.value, ValueError)
    rec, status = block.try_decode(bytes([0x10, 0, 0, 0, 0, 0]))
    assert rec is not None and rec.codes == (4096, 0, 0) and block.fmt().errors[status].startswith("sample code")
    rec, status = block.try_decode(bytes([0xFE, 9, 0, 0, 0, 0]))
    assert rec is None and block.fmt().errors[status] == "unknown report kind"
    with pytest.raises(BlockFormatError, match="report field out of range"):
        block.decode(bytes.fromhex("fe0002004808"))  # BOOT of format version 2
    with pytest.raises(InvalidArgument, match="6 bytes, got 5"):
        block.decode(b"\0" * 5)
    with pytest.raises(InvalidType, match="bytes"):
        block.decode([0] * 6)  # type: ignore[arg-type]


def test_encoders_check_their_arguments() -> None:
    with pytest.raises(InvalidArgument, match=r"codes\[1\] must be 0..4095, got 4096"):
        block.encode_sample([0, 4096, 0])
    with pytest.raises(InvalidArgument, match="period_ticks must be 1..32767, got 0"):
        block.encode_boot(0, 9600)
    with pytest.raises(InvalidArgument, match="multiple of 1200"):
        block.encode_boot(72, 9000)
    with pytest.raises(InvalidArgument, match="status must be -128..-1"):
        block.encode_adc_error(1, 0)
    with pytest.raises(InvalidArgument, match="kind must be 'gave_up' or 'overrun'"):
        block.encode_loss("adc_error", 1, 1)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="count must be 1..65535, got 0"):
        block.encode_loss("overrun", 1, 0)
    with pytest.raises(InvalidType, match="attempt must be an integer"):
        block.encode_selftest(-41, 0, 1.5)  # type: ignore[arg-type]


@settings(max_examples=3000, deadline=None)
@given(st.binary(min_size=6, max_size=6) | st.builds(lambda k, t: bytes([0xFE, k]) + t,
                                                     st.integers(0, 7), st.binary(min_size=4, max_size=4))
       | st.builds(lambda n: bytes([0xFE, 5, n, 0, 0, 0]), st.integers(0, 20))
       | st.builds(lambda *f: bytes([0xFE, 6, *f]), st.integers(0, 3), st.integers(0, 15),
                   st.sampled_from([0, 1, 2, 255]), st.sampled_from([0, 1, 4, 255])))
def test_decoder_agrees_with_the_table_on_any_bytes(raw: bytes) -> None:
    kind, ok = _spec(raw)
    rec, status = block.try_decode(raw)
    assert (status == 0) == ok, (raw.hex(), kind, status)
    if kind == "unknown":
        assert rec is None
    else:
        assert rec is not None and rec.kind == kind and rec.raw == raw
    if ok:  # a valid record encodes back to the same bytes
        assert rec is not None
        again = {"sample": lambda: block.encode_sample(rec.codes),
                 "boot": lambda: block.encode_boot(rec.period_ticks, rec.baud, rec.link),
                 "selftest": lambda: block.encode_selftest(rec.status, rec.bad_code, rec.attempt),
                 "gave_up": lambda: block.encode_loss("gave_up", rec.first, rec.count),
                 "overrun": lambda: block.encode_loss("overrun", rec.first, rec.count),
                 "adc_error": lambda: block.encode_adc_error(rec.first, rec.status),
                 "oversample": lambda: block.encode_oversample(rec.oversample),
                 "channels": lambda: block.encode_channels(rec.board, rec.channels,  # type: ignore[arg-type]
                                                           rec.acc_every, rec.mag_every)}[rec.kind]()
        assert again == raw


def test_number_stream_accounts_for_every_sample() -> None:
    s = lambda a: block.encode_sample([a, a, a])
    boot = block.encode_boot(72, 9600)
    out = block.number_stream([boot, s(1), s(2), block.encode_loss("overrun", 2, 3), s(3),
                               block.encode_adc_error(6, -40), s(4)])
    assert [(r.kind, sp.first, sp.count) for r, sp in out] == [
        ("boot", 0, 0), ("sample", 0, 1), ("sample", 1, 1), ("overrun", 2, 3), ("sample", 5, 1),
        ("adc_error", 6, 1), ("sample", 7, 1)]
    # a link block of N = 12 carries two records
    assert [sp.first for _, sp in block.number_stream([boot, s(1) + s(2)])] == [0, 0, 1]
    with pytest.raises(BlockFormatError, match=r"record 3 .*its first sample is 7, expected 2") as e:
        block.number_stream([boot, s(1), s(2), block.encode_loss("gave_up", 7, 1)])
    assert e.value.index == 3
    # not strict: the slip is followed, the unreported samples are counted as missing
    out = block.number_stream([boot, s(1), s(2), block.encode_loss("gave_up", 7, 1), s(3)], strict=False)
    assert [(sp.first, sp.count, sp.slip) for _, sp in out[3:]] == [(2, 6, 5), (8, 1, 0)]
    with pytest.raises(BlockFormatError, match="record 1 .*sample code above 4095"):
        block.number_stream([boot, bytes([0x10, 0, 0, 0, 0, 0])])
    # not strict: a bad sample keeps its number (it is missing), an unknown record is skipped
    out = block.number_stream([boot, bytes([0x10, 0, 0, 0, 0, 0]), bytes.fromhex("fe0900000000"), s(1)],
                              strict=False)
    assert [(r.kind, sp.first) for r, sp in out] == [("boot", 0), ("sample", 0), ("sample", 1)]


def test_oversampled_stream_keeps_the_sums() -> None:
    """A board that sums n conversions announces n (OVERSAMPLE, right after BOOT); its
    sample records carry the sums, up to min(n × 4095, 0xFDFF) (block.h: byte 0 of a
    sample stays below the report mark), and the stream's tracker checks that limit."""
    assert block.encode_oversample(16) == bytes.fromhex("fe0510000000")
    assert block.decode(block.encode_oversample(3)).as_dict() == {"report": "OVERSAMPLE", "n": 3}
    assert block.encode_sums([0x8000, 0xFDFF, 0], 16) == bytes.fromhex("8000fdff0000")
    assert block.encode_sums([1, 2, 3], 1) == block.encode_sample([1, 2, 3])
    assert [block.sum_limit(n) for n in (1, 2, 15, 16)] == [4095, 8190, 61425, 0xFDFF]
    with pytest.raises(InvalidArgument, match=r"sums\[1\] must be 0..65023, got 65024"):
        block.encode_sums([0, 0xFE00, 0], 16)
    with pytest.raises(InvalidArgument, match="n must be 1..16, got 17"):
        block.encode_oversample(17)
    boot = block.encode_boot(72, 9600)
    sums = [block.encode_sums([16 * 2048 + k, 5, 65000], 16) for k in range(3)]
    out = block.number_stream([boot, block.encode_oversample(16), *sums])
    assert [(r.kind, sp.first, sp.count) for r, sp in out] == [
        ("boot", 0, 0), ("oversample", 0, 0), ("sample", 0, 1), ("sample", 1, 1), ("sample", 2, 1)]
    assert out[3][0].codes == (32769, 5, 65000)
    # the same records in a plain stream (no OVERSAMPLE) are codes above 4095: rejected
    with pytest.raises(BlockFormatError, match="record 1 .*sample code above 4095"):
        block.number_stream([boot, *sums])
    tr = block.SeqTracker()
    for raw in (boot, block.encode_oversample(2)):
        tr.decode(raw)
    assert (tr.oversample, tr.code_limit) == (2, 8190)
    _, span, st = tr.decode(block.encode_sums([8191 - 1, 0, 0], 16))
    assert st == 0 and span is not None and span.first == 0
    _, span, st = tr.decode(bytes([0x20, 0, 0, 0, 0, 0]))  # 8192 > 2 × 4095
    assert tr.error(st) == "sample code above 8190" and span is not None and span.first == 1
    tr.decode(boot)  # a new stream is plain
    assert tr.oversample == 1


def test_channels_report_announces_the_aided_stream() -> None:
    """CHANNELS (block.h): board, channel set, decimations, in the bytes of the table."""
    assert block.encode_channels("aided9", ["gyr", "acc", "mag"], 1, 4) == bytes.fromhex("fe0602070104")
    assert block.encode_channels("gyro3", ["gyr"]) == bytes.fromhex("fe0601010000")
    assert block.encode_channels("aided9", ["gyr", "mag"], 0, 2) == bytes.fromhex("fe0602050002")
    r = block.decode(bytes.fromhex("fe0602070104"))
    assert (r.kind, r.board, r.channels, r.acc_every, r.mag_every) == (
        "channels", "aided9", ("gyr", "acc", "mag"), 1, 4)
    assert r.as_dict() == {"report": "CHANNELS", "board": "aided9", "channels": ["gyr", "acc", "mag"],
                           "acc_every": 1, "mag_every": 4}
    with pytest.raises(BlockFormatError, match="report field out of range"):
        block.decode(bytes.fromhex("fe0601030100"))  # a gyro3 board with an accelerometer
    for args, msg in [(("aided8", ["gyr"]), "board must be one of"),
                      (("aided9", ["acc"], 1), "must include 'gyr'"),
                      (("aided9", ["gyr", "baro"]), "channels must be among"),
                      (("gyro3", ["gyr", "acc"], 1), "'gyro3' board has the gyros alone"),
                      (("aided9", ["gyr", "acc"], 0), "acc_every must be 1..255, got 0"),
                      (("aided9", ["gyr", "acc"], 256), "acc_every must be 1..255, got 256"),
                      (("aided9", ["gyr"], 0, 3), "mag_every must be 0 when 'mag' is not in channels")]:
        with pytest.raises(InvalidArgument, match=msg):
            block.encode_channels(*args)  # type: ignore[arg-type]
    with pytest.raises(InvalidType, match="sequence of names"):
        block.encode_channels("aided9", "gyr")  # type: ignore[arg-type]


def _aided_group(n: int, acc_every: int, mag_every: int) -> list[tuple[str, int]]:
    """(part, sample) of the records of sample n, from block.h's rule for groups."""
    return ([("gyr", n)] + ([("acc", n)] if n % acc_every == 0 else [])
            + ([("mag", n)] if n % mag_every == 0 else []))


def test_tracker_places_every_record_of_an_aided_stream() -> None:
    """Sample n = its gyro record, then accelerometer (n % acc_every == 0), then magnetometer
    (n % mag_every == 0); losses count whole samples; a report inside a group cuts it short."""
    rec = block.encode_sample([1, 2, 3])
    head = [block.encode_boot(36, 57600, "v2"), block.encode_channels("aided9", ["gyr", "acc", "mag"], 2, 3)]
    want = [g for n in range(7) for g in _aided_group(n, 2, 3)]
    out = block.number_stream(head + [rec] * len(want) + [block.encode_loss("overrun", 7, 2), rec])
    assert out[1][0].as_dict()["acc_every"] == 2
    assert [(sp.part, sp.first) for _, sp in out[2:-2]] == want
    assert [(sp.first, sp.count, sp.part) for _, sp in out[-2:]] == [(7, 2, "gyr"), (9, 1, "gyr")]
    # sample 6's group (gyr, acc, mag) cut after its gyro record: E_SEQ naming the record due
    cut = head + [rec] * (len(want) - 2) + [block.encode_loss("gave_up", 7, 1)]
    with pytest.raises(BlockFormatError, match=r"record \d+ .*report out of sequence \(it cut sample 6's group "
                                               r"short before its acc record\)"):
        block.number_stream(cut)
    out = block.number_stream(cut + [rec], strict=False)
    assert [(sp.first, sp.count, sp.slip, sp.part) for _, sp in out[-3:]] == [
        (6, 1, 0, "gyr"), (7, 1, 0, "acc"), (8, 1, 0, "gyr")]
    tr = block.SeqTracker()
    for raw in head + [rec]:
        tr.decode(raw)
    assert (tr.channels, tr.acc_every, tr.mag_every, tr.part, tr.next) == (("gyr", "acc", "mag"), 2, 3, "acc", 1)
    tr.decode(head[0])  # a BOOT: gyro-only again
    assert (tr.channels, tr.acc_every, tr.mag_every, tr.part) == (("gyr",), 0, 0, "gyr")


# -- the 8051 side ------------------------------------------------------------------

SDCC = ["sdcc", "-mmcs51", "--model-small", "--iram-size", "128", "--xram-size", "0", "--std-c99", "--Werror",
        "-DATT_REAL_F32", f"-I{ROOT / 'csrc' / 'include'}"]


@pytest.mark.system
def test_block_sources_compile_for_the_8051_and_the_encoders_stay_small(tmp_path: Path) -> None:
    """block.c (what the firmware links), block_channels.c (what the aided firmware adds), block_decode.c
    and block_sums.c compile warning-free with SDCC; the encoders are leaf functions whose parameters
    SDCC overlays: no RAM of their own, and code small enough for the 4 KB image (294 bytes when written)."""
    require_tools("sdcc", apt="sdcc")
    segs = {}
    for src in ("block.c", "block_channels.c", "block_decode.c", "block_sums.c"):
        rel = tmp_path / src.replace(".c", ".rel")
        proc = subprocess.run([*SDCC, "-c", str(ROOT / "csrc" / "src" / src), "-o", str(rel)],
                              capture_output=True, text=True, timeout=120, check=False)
        assert proc.returncode == 0 and "warning" not in (proc.stdout + proc.stderr).lower(), proc.stderr
        text = rel.read_text()
        segs[src] = {k: int(v, 16) for k, v in re.findall(r"^A (CSEG|DSEG|OSEG) size ([0-9A-F]+)", text, re.MULTILINE)}
    enc = segs["block.c"]
    assert enc["DSEG"] == 0, enc
    assert enc["OSEG"] <= 8, enc
    assert enc["CSEG"] <= 320, f"block.c grew to {enc['CSEG']} bytes of 8051 code"
    ch = segs["block_channels.c"]
    assert ch.get("DSEG", 0) == 0 and ch.get("OSEG", 0) <= 8, ch


def test_the_format_is_written_down_once() -> None:
    """No second copy of the block format: no 0xFE report marker or report-kind table
    in the firmware, attitude-rx or the Python package (block.h and its two C files hold it)."""
    pat = re.compile(r"0x[fF][eE]\b|\b(FW_)?REPORT_(MARK|KINDS|BOOT|SELFTEST|GAVE_UP|OVERRUN|ADC_ERROR)\b")
    files = [*ROOT.glob("firmware/**/*.c"), *ROOT.glob("firmware/**/*.h"), *ROOT.glob("firmware/*.py"),
             *ROOT.glob("csrc/app/*.[ch]"), *ROOT.glob("attitude_c/**/*.py")]
    hits = []
    for f in files:
        for n, line in enumerate(f.read_text().splitlines(), 1):
            code = line.split("#", 1)[0] if f.suffix == ".py" else line
            if pat.search(code) and "/*" not in code and "//" not in code and not code.lstrip().startswith("*"):
                hits.append(f"{f.relative_to(ROOT)}:{n}: {line.strip()}")
    assert not hits, "\n".join(hits)


# -- attitude link-rx --decode -------------------------------------------------------

def test_link_rx_decode_prints_numbered_records(capsys: pytest.CaptureFixture[str]) -> None:
    """`attitude link-rx --decode` decodes with the same C decoder and tracker."""
    import json
    import threading

    from attitude_c.cli import main
    from attitude_c.link.transport import PtyPair, open_port, run_sender

    stream = [block.encode_boot(72, 9600), block.encode_sample([1, 2, 3]),
              block.encode_loss("overrun", 1, 2), block.encode_sample([4, 5, 6]),
              bytes([0x10, 0, 0, 0, 0, 0]), bytes.fromhex("fe0900000000"),
              block.encode_loss("gave_up", 7, 1)]
    with PtyPair() as (p0, p1):
        def send() -> None:
            time.sleep(0.3)  # link-rx opens its port first
            pa = open_port(p0)
            try:
                run_sender(pa, stream, syn_timeout_ms=1000, answer_timeout_ms=1000)
            finally:
                pa.close()

        th = threading.Thread(target=send, daemon=True)
        th.start()
        rc = main(["link-rx", "--port", p1, "--decode", "--count", str(len(stream)), "--duration", "30",
                   "--gap-timeout-ms", "400"])
        th.join(timeout=30)
    assert rc == 0
    recs = [json.loads(ln) for ln in capsys.readouterr().out.splitlines()]
    assert recs == [
        {"report": "BOOT", "version": 1, "period_ticks": 72, "period_s": 0.02, "baud": 9600},
        {"n": 0, "codes": [1, 2, 3]},
        {"report": "OVERRUN", "first": 1, "count": 2, "slip": 0},
        {"n": 3, "codes": [4, 5, 6]},
        {"n": 4, "codes": [4096, 0, 0], "error": "sample code above 4095"},
        {"error": "unknown report kind", "raw": "fe0900000000"},
        {"report": "GAVE_UP", "first": 5, "count": 3, "slip": 2},
    ]
    assert main(["link-rx", "--port", "loop://", "--decode", "--block-size", "8"]) == 2
