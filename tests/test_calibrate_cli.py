"""``attitude calibrate`` (issue 26): a recording of simulated front-end codes in, the
attitude-rx config keys out (the same numbers as attitude_c.sensorcal on the same
codes), the rest of an existing config kept, and every mistake one line with its
documented exit status (docs/cli.md, docs/sensor.md), the old config untouched.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from attitude_c.cli import EXIT_OK, EXIT_OS, EXIT_USAGE, main
from attitude_c.cli.calibrate import EXIT_REFUSED, merged_config
from attitude_c.sensorcal import SensorConfig, fit_accel, fit_mag, pose_means
from attitude_c.sim.accelmag import G0
from attitude_c.sim.frontend import ACCEL_FRONTENDS, MAG_FRONTENDS, flip_code, tlc2543_codes

ACC = ACCEL_FRONTENDS["adxl335"]
MAG = MAG_FRONTENDS["hmc1043-ad623"]


def _recording(path: Path, positions: int = 14, rows: int = 40, seed: int = 0) -> tuple[np.ndarray, np.ndarray,
                                                                                        np.ndarray]:
    """A CSV of both sensors: ``positions`` still positions of ``rows`` samples (the
    six faces first), a moving row between positions (pose empty), the magnetometer
    turning through random directions all along."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(positions, 3))
    d[:6] = np.vstack([np.eye(3), -np.eye(3)])[:positions]
    d /= np.linalg.norm(d, axis=1)[:, None]
    f = np.repeat(d * G0, rows, axis=0)
    pose = np.repeat(np.arange(positions), rows)
    acc = tlc2543_codes(ACC.volts(f, ACC.draw_errors(rng), 0.01, rng), ACC.supply_v)
    u = rng.normal(size=(len(f), 3))
    h = u / np.linalg.norm(u, axis=1)[:, None] * 50.0 + [8.0, -4.0, 2.0]
    mag = flip_code(*MAG.set_reset_codes(h, MAG.draw_errors(rng), 0.01, rng))
    lines = ["# a recording", "t,pose,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z"]
    for i in range(len(f)):
        lines.append(f"{i * 0.01:.2f},{pose[i]},{','.join(map(str, acc[i]))},{','.join(map(str, mag[i]))}")
        if i % rows == rows - 1:
            lines.append(f"{i * 0.01:.2f},,{','.join(map(str, acc[i] + 50))},")  # moving, no magnetometer record
    path.write_text("\n".join(lines) + "\n")
    return acc, pose, mag


def _keys(text: str) -> dict[str, list[float] | str]:
    out: dict[str, list[float] | str] = {}
    for line in text.splitlines():
        if "=" in line and not line.startswith("#"):
            k, v = (x.strip() for x in line.split("=", 1))
            out[k] = v if k.endswith("axes") or not v[0].isdigit() and v[0] != "-" else [float(x) for x in v.split(",")]
    return out


def test_writes_the_keys_of_both_fits(tmp_path: Path, capsys) -> None:
    rec, out = tmp_path / "rec.csv", tmp_path / "rx.conf"
    acc, pose, mag = _recording(rec)
    assert main(["calibrate", "--acc", str(rec), "--mag", str(rec), "--out", str(out), "--mag-field", "50"]) == EXIT_OK
    keys = _keys(out.read_text())
    nominal_a = SensorConfig("acc", 2048, ACC.units_per_code)
    want_a = fit_accel(pose_means(nominal_a.convert(acc, corrected=False), pose)[0], nominal_a).config
    nominal_m = SensorConfig("mag", 2047.5, MAG.units_per_code)
    want_m = fit_mag(nominal_m.convert(mag, corrected=False), nominal_m, field_ut=50.0).config
    for cfg in (want_a, want_m):
        for line in cfg.lines():
            k, v = (x.strip() for x in line.split("=", 1))
            if k.endswith("axes"):
                assert keys[k] == v
            else:  # written with 10 significant digits
                np.testing.assert_allclose(keys[k], [float(x) for x in v.split(",")], rtol=1e-9, atol=1e-9)
    report = capsys.readouterr().out
    assert "accelerometer: 14 positions, model full" in report and f"written: {out}" in report


def test_keeps_the_other_lines_of_an_existing_config(tmp_path: Path, capsys) -> None:
    rec, out = tmp_path / "rec.csv", tmp_path / "rx.conf"
    _recording(rec)
    out.write_text("# my board\nport = /dev/ttyS1\nacc-zero = 1,2,3  # old\ngyr_noise = 0.01\nacc-bias = 9,9,9\n")
    assert main(["calibrate", "--acc", str(rec), "--out", str(out), "--json"]) == EXIT_OK
    lines = out.read_text().splitlines()
    assert lines[:2] == ["# my board", "port = /dev/ttyS1"]
    assert lines[2].startswith("acc-zero = ") and lines[7] == "gyr_noise = 0.01"
    assert [ln.split(" = ")[0] for ln in lines[2:7]] == ["acc-zero", "acc-scale", "acc-axes", "acc-matrix", "acc-bias"]
    assert len(lines) == 8 and not any(ln.startswith("mag-") for ln in lines)
    report = json.loads(capsys.readouterr().out)
    assert report["acc"]["positions"] == 14 and len(report["acc"]["poses"]) == 14


def test_merged_config_appends_when_absent() -> None:
    cfg = SensorConfig("mag", 2047.5, 0.12)
    assert merged_config("port = x\n", [cfg]).splitlines() == ["port = x", "# attitude calibrate", *cfg.lines()]


def _one_line(capsys, code_seen: int, code: int, *words: str) -> None:
    err = capsys.readouterr().err.strip().splitlines()
    assert code_seen == code and len(err) == 1 and err[0].startswith("attitude calibrate: error: "), err
    for w in words:
        assert w in err[0], err


def _first_row(field: int, value: str):
    """An edit of the recording: field ``field`` of its first data row (file line 3) set to ``value``."""
    def edit(text: str) -> str:
        lines = text.split("\n")
        cells = lines[2].split(",")
        cells[field] = value
        lines[2] = ",".join(cells)
        return "\n".join(lines)
    return edit


@pytest.mark.parametrize("edit, words", [
    (lambda t: t.replace("acc_z", "accz"), ["no column acc_z"]),
    (_first_row(2, "x1"), ["rec.csv:3", "not a number"]),
    (_first_row(2, "nan"), ["rec.csv:3", "not a finite number"]),
    (_first_row(3, "5000"), ["rec.csv:3", "not words of 1 12-bit"]),
    (_first_row(1, "0.5"), ["pose must be an integer"]),
], ids=["column", "cell", "nan", "word", "pose"])
def test_bad_file_content_is_a_usage_error(tmp_path: Path, capsys, edit, words) -> None:
    rec, out = tmp_path / "rec.csv", tmp_path / "rx.conf"
    _recording(rec, positions=7, rows=5)
    rec.write_text(edit(rec.read_text()))
    out.write_text("port = /dev/ttyS1\n")
    _one_line(capsys, main(["calibrate", "--acc", str(rec), "--out", str(out)]), EXIT_USAGE, *words)
    assert out.read_text() == "port = /dev/ttyS1\n"  # untouched


def test_refusals_exit_3_and_leave_the_config(tmp_path: Path, capsys) -> None:
    rec, out = tmp_path / "rec.csv", tmp_path / "rx.conf"
    _recording(rec, positions=5, rows=5)
    _one_line(capsys, main(["calibrate", "--acc", str(rec), "--out", str(out)]), EXIT_REFUSED,
              "accelerometer:", "needs 6 static positions")
    _recording(rec, positions=8, rows=5)
    _one_line(capsys, main(["calibrate", "--acc", str(rec), "--out", str(out), "--acc-model", "full"]),
              EXIT_REFUSED, "needs 12")
    _recording(rec, positions=3, rows=5)  # 15 magnetometer samples: the ellipsoid fit wants 20
    _one_line(capsys, main(["calibrate", "--mag", str(rec), "--out", str(out)]), EXIT_REFUSED, "magnetometer:")
    assert not out.exists()


def test_usage_and_os_errors(tmp_path: Path, capsys) -> None:
    out = tmp_path / "rx.conf"
    _one_line(capsys, main(["calibrate", "--out", str(out)]), EXIT_USAGE, "--acc FILE..., --mag FILE...")
    _one_line(capsys, main(["calibrate", "--acc", str(tmp_path / "none.csv"), "--out", str(out)]), EXIT_OS,
              "none.csv", "No such file")
    rec = tmp_path / "rec.csv"
    _recording(rec, positions=7, rows=5)
    _one_line(capsys, main(["calibrate", "--acc", str(rec), "--out", str(tmp_path / "no" / "rx.conf")]), EXIT_OS,
              "No such file")
    _one_line(capsys, main(["calibrate", "--acc", str(rec), "--out", str(out), "--acc-axes", "x,x,z"]),
              EXIT_USAGE, "--acc-axes", "each channel")
    with pytest.raises(SystemExit) as ei:
        main(["calibrate", "--acc", str(rec), "--out", str(out), "--gravity", "-1"])
    assert ei.value.code == EXIT_USAGE
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv"]  # no temporary left


def _print_decoded(acc: np.ndarray, mag: np.ndarray, n: int) -> None:
    """``attitude link-rx --decode`` output of an aided board's stream carrying these
    accelerometer and magnetometer words (sums of n codes; the gyros at mid-scale):
    the printer of link-rx itself, fed the records."""
    from attitude_c.cli.link import _block_printer
    from attitude_c.link import block

    show = _block_printer()
    recs = [block.encode_boot(72, 9600), block.encode_oversample(n),
            block.encode_channels("aided9", ["gyr", "acc", "mag"], 1, 1)]
    for a, m in zip(acc, mag):
        recs += [block.encode_sums([2048 * n] * 3, n), block.encode_sums(a, n), block.encode_sums(m, n)]
    show(b"".join(recs))


def _session(rng: np.random.Generator, rows: int = 120, ramp: int = 30) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Accelerometer codes of the six faces held ``rows`` samples each, the board turned
    between them over ``ramp`` samples (pose −1), and magnetometer codes of a rotation."""
    faces = np.vstack([np.eye(3), -np.eye(3)]) * G0
    f, pose = [], []
    for k in range(6):
        f.append(np.repeat(faces[k:k + 1], rows, axis=0))
        pose += [k] * rows
        if k < 5:
            f.append(np.linspace(faces[k], faces[k + 1], ramp))  # a straight path: |f| dips, it is moving anyway
            pose += [-1] * ramp
    fa = np.vstack(f)
    acc = tlc2543_codes(ACC.volts(fa, ACC.draw_errors(rng), 0.01, rng), ACC.supply_v)
    u = rng.normal(size=(len(fa), 3))
    mag = flip_code(*MAG.set_reset_codes(u / np.linalg.norm(u, axis=1)[:, None] * 50.0, MAG.draw_errors(rng), 0.01,
                                         rng))
    return acc, np.array(pose), mag


def test_link_rx_decode_recording_cut_into_still_positions(tmp_path: Path, capsys) -> None:
    """One link-rx --decode recording of an aided board, oversampled by 4, the board
    turned from face to face: the six positions are found, and the calibration agrees
    with the CSV of the same codes labelled with the true positions."""
    acc, pose, mag = _session(np.random.default_rng(3))
    rec, jsonl = tmp_path / "rec.csv", tmp_path / "session.jsonl"
    lines = ["pose,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z"]
    lines += [f"{p},{','.join(map(str, a))},{','.join(map(str, m))}" for p, a, m in zip(pose, acc, mag)]
    rec.write_text("\n".join(lines) + "\n")
    _print_decoded(acc * 4, mag * 4, 4)  # 4 identical conversions: the same codes, ×4
    jsonl.write_text(capsys.readouterr().out)
    assert '"part": "acc"' in jsonl.read_text()
    out_csv, out_jsonl = tmp_path / "a.conf", tmp_path / "b.conf"
    assert main(["calibrate", "--acc", str(rec), "--out", str(out_csv)]) == EXIT_OK
    capsys.readouterr()
    assert main(["calibrate", "--acc", str(jsonl), "--mag", str(jsonl), "--out", str(out_jsonl), "--json"]) == EXIT_OK
    report = json.loads(capsys.readouterr().out)
    assert report["acc"]["positions"] == 6 and all(p["rows"] >= 120 - 3 * 20 for p in report["acc"]["poses"])
    a, b = _keys(out_csv.read_text()), _keys(out_jsonl.read_text())
    # the segmented positions hold ≥ 60 of each position's 120 samples: a mean moves by about the
    # noise's 0.57 code/√60 = 0.07 code, a zero (the mean of two) by 0.05; 0.3 code is 6 of those.
    # A scale comes from two means 819 codes apart: 0.07·√2/819 = 1.2e-4 relative; 1.5e-3 is 12 of those
    np.testing.assert_allclose(b["acc-zero"], a["acc-zero"], atol=0.3)
    np.testing.assert_allclose(b["acc-scale"], a["acc-scale"], rtol=1.5e-3)
    assert "mag-matrix" in b and "mag-matrix" not in a
    (tmp_path / "gyro.jsonl").write_text('{"n": 0, "codes": [1, 2, 3]}\n')
    _one_line(capsys, main(["calibrate", "--acc", str(tmp_path / "gyro.jsonl"), "--out", str(out_csv)]),
              EXIT_USAGE, 'no "part": "acc" records')
    (tmp_path / "bad.jsonl").write_text('{"report": "OVERSAMPLE", "n": 99}\n')
    _one_line(capsys, main(["calibrate", "--mag", str(tmp_path / "bad.jsonl"), "--out", str(out_csv)]), EXIT_USAGE,
              "bad.jsonl:1", "OVERSAMPLE")
