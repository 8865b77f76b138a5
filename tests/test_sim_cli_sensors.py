"""`attitude simulate` with the sensors and stages of issues 14 and 16: the
accelerometer and magnetometer options, the new motions, --denoise, --adc ad7927;
and that the bare command is still the paper's gyro-only system."""

from __future__ import annotations

import argparse
import csv
import json
import math

import numpy as np
import pytest

from attitude_c.cli import main
from attitude_c.cli.simulate import build_config, register

pytestmark = pytest.mark.system  # runs attitude simulate end to end


def _args(*argv: str) -> argparse.Namespace:
    p = argparse.ArgumentParser()
    sub = p.add_subparsers()
    register(sub)
    return p.parse_args(["simulate", *argv])


def test_defaults_stay_the_papers_gyro_only_system() -> None:
    cfg = build_config(_args())
    assert cfg.accel is None and cfg.mag is None and cfg.denoise is None
    assert cfg.adc.backend == "tlc2543" and cfg.gyro.name == "cg-l53" and not cfg.conditioning.follower
    assert cfg.trajectory.name == "paper" and cfg.duration == 60.0
    p = cfg.params()
    for key in ("accel", "mag", "environment", "denoise", "conditioning_follower"):
        assert key not in p


def test_motions_have_their_tests_lengths() -> None:
    assert build_config(_args("--trajectory", "static")).duration == 1800.0
    tt = build_config(_args("--trajectory", "turntable"))
    assert tt.duration == 360.0 and tt.trajectory.rate[2] == pytest.approx(math.radians(5.0))
    lt = build_config(_args("--trajectory", "level-turn", "--turn-rate", "20", "--rest", "2"))
    assert lt.duration == pytest.approx(2 * 2 + 36.0)
    pt = build_config(_args("--trajectory", "paper-translation", "--translation", "1,2,3"))
    assert pt.trajectory.name == "paper-translation" and pt.trajectory.translation.tolist() == [1, 2, 3]
    assert build_config(_args("--trajectory", "static", "--duration", "5")).duration == 5.0


def test_thesis_board_preset() -> None:
    cfg = build_config(_args("--adc", "ad7927"))
    assert cfg.adc.backend == "ad7927" and cfg.conditioning.follower
    assert cfg.gyro.name == "adxrs150" and cfg.accel is not None and cfg.accel.name == "adxl202"
    cfg = build_config(_args("--adc", "ad7927", "--accel", "none", "--gyro", "cg-l53"))
    assert cfg.accel is None and cfg.gyro.name == "cg-l53"


def test_sensors_end_to_end_write_the_streams_and_truth(tmp_path, capsys) -> None:
    """Accelerometer + magnetometer + a disturbance window + hard/soft iron + a field,
    on the translating paper motion: summary, table and sensors.csv (one row per
    period: the host's readings beside the exact truth)."""
    out = tmp_path / "run"
    rc = main(["simulate", "--trajectory", "paper-translation", "--duration", "6", "--adc", "ideal",
               "--accel", "adis16488", "--mag", "hmr3000", "--field", "48,60,3", "--hard-iron", "10,-5,2",
               "--soft-iron", "1.05,0.95,1", "--disturbance", "2,4,30,0,0,0.5,nav", "--seed", "2",
               "--no-plots", "--no-progress", "--out", str(out)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "accel (adis16488)" in text and "mag (hmr3000)" in text and "disturbed 25" in text
    s = json.loads((out / "summary.json").read_text())
    assert s["parameters"]["mag"]["disturbances"][0]["frame"] == "nav"
    assert s["parameters"]["environment"]["field_ut"] == 48.0
    assert s["sensors"]["mag"]["disturbed_samples"] == 25  # 2 s of 0.08 s periods
    with open(out / "sensors.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 75
    cols = set(rows[0])
    for c in ("accel_x_m_s2", "accel_true_z_m_s2", "mag_y_ut", "mag_true_x_ut", "mag_disturbance_x_ut",
              "gyro_z_rad_s", "gyro_true_y_rad_s"):
        assert c in cols
    m = np.array([[float(r[f"mag_true_{a}_ut"]) for a in "xyz"] for r in rows])
    # the period mean of a 48 µT vector turning at ω is shorter by ≈ (ωh)²/24: ≤ 3e-4 at ω ≤ 1.1 rad/s
    np.testing.assert_allclose(np.linalg.norm(m, axis=1), 48.0, rtol=5e-4)
    f = np.array([[float(r[f"accel_{a}_m_s2"]) - float(r[f"accel_true_{a}_m_s2"]) for a in "xyz"] for r in rows])
    assert np.abs(f).max() < 1.0  # ADIS16488: 16 mg bias, 0.5 % scale of ≤ 13 m/s², 0.035°: ≪ 1 m/s²


def test_default_run_writes_no_sensor_file(tmp_path) -> None:
    out = tmp_path / "d"
    assert main(["simulate", "--duration", "2", "--no-plots", "--no-progress", "--adc", "ideal",
                 "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["summary.json", "timeseries.csv"]


def test_denoise_and_ad7927_from_the_cli(tmp_path, capsys) -> None:
    out = tmp_path / "dn"
    rc = main(["simulate", "--trajectory", "static", "--duration", "12", "--period", "0.005", "--link", "none",
               "--calibration", "2", "--denoise", "db4", "--denoise-levels", "3", "--denoise-mode", "hard",
               "--denoise-block", "64", "--adc", "ideal", "--no-plots", "--no-progress", "--out", str(out)])
    assert rc == 0
    assert "denoise (db4, L3, hard, N 64" in capsys.readouterr().out
    d = json.loads((out / "summary.json").read_text())["denoise"]
    assert (d["edge_start"], d["edge_end"]) == (28, 12)  # the default edges scaled to the block
    out = tmp_path / "ad"
    assert main(["simulate", "--adc", "ad7927", "--duration", "3", "--calibration", "1", "--no-plots",
                 "--no-progress", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["backends"]["adc"] == "ad7927" and s["sensors"]["accel"]["part"] == "adxl202"


@pytest.mark.parametrize("argv, needle", [
    (["--disturbance", "1,2,3"], "--disturbance"),
    (["--soft-iron", "1,2"], "--soft-iron"),
    (["--field", "50,60"], "--field"),
    (["--accel", "mpu6050"], "--accel"),
    (["--adc", "max1270"], "--adc"),
    # the shared numeric validator (attitude_c/cli/options.py): refused by the parser
    (["--trajectory", "turntable", "--turntable-rate", "nan"], "--turntable-rate: must be a finite number"),
])
def test_bad_sensor_arguments_are_usage_errors(argv, needle, capsys) -> None:
    with pytest.raises(SystemExit) as ei:
        main(["simulate", *argv])
    assert ei.value.code == 2
    assert needle in capsys.readouterr().err


@pytest.mark.parametrize("argv, needle", [
    (["--hard-iron", "1,2,3"], "need a magnetometer"),
    (["--denoise-levels", "3"], "need --denoise"),
    (["--denoise", "db4", "--duration", "2"], "at least one block"),
    (["--mag", "ideal", "--soft-iron", "0,1,1"], "invertible"),
    (["--mag", "ideal", "--disturbance", "5,4,1,0,0"], "end > start"),
    (["--field", "50,95,0", "--mag", "ideal"], "inclination"),
])
def test_bad_sensor_values_give_one_clear_line(argv, needle, tmp_path, capsys) -> None:
    rc = main(["simulate", "--no-progress", "--no-plots", "--duration", "2", "--adc", "ideal",
               "--out", str(tmp_path / "x"), *argv])
    assert rc == 2
    err = capsys.readouterr().err
    assert err.startswith("attitude simulate: error:") and needle in err and "Traceback" not in err
