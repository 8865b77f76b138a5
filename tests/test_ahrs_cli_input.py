"""``attitude ahrs`` from a recording to a result (issue 27, items 3-6): .mat without
SciPy, the figure and summary.json, the CSV reader's mapping/units/axes/delimiters
and its refusal of a gyro in °/s, the frames and the aerospace z-y-x output."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from conftest import ROOT, motion

from attitude_c import reference as ref
from attitude_c.cli import main

HEAD = "t,gx,gy,gz,ax,ay,az,mx,my,mz,qw,qx,qy,qz"
#: constant body rate (rad/s) of the test recordings: not along the field, so the field turns
W = (0.3, -0.5, 0.4)


def _recording(n: int = 500, rate: float = 100.0):
    gyr, acc, mag, truth = motion(n, rate, W, noise=0.001)
    return np.arange(n) / rate, gyr, acc, mag, truth


def _write(path, cols, head=HEAD, delimiter=","):
    np.savetxt(path, np.column_stack(cols), delimiter=delimiter, fmt="%.9g", header=head, comments="")
    return path


def _attitude(out):
    return np.loadtxt(out / "attitude.csv", delimiter=",", comments="#", skiprows=2)


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("attitude ahrs: error: "), err
    return err[0]


# ---- item 3: a .mat without SciPy is one line naming the pip command ----------------------------

_NO_SCIPY = """
import sys
class Blocker:
    def find_spec(self, name, path=None, target=None):
        if name == "scipy" or name.startswith("scipy."):
            raise ImportError("No module named " + repr(name) + " (blocked by the test)")
        return None
sys.meta_path.insert(0, Blocker())
from attitude_c.cli import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.system
def test_a_mat_file_without_scipy_is_one_line_naming_the_extra(tmp_path):
    trial = tmp_path / "01_trial.mat"
    trial.write_bytes(b"MATLAB 5.0 MAT-file")  # SciPy is asked for before the file is read
    r = subprocess.run([sys.executable, "-c", _NO_SCIPY, "ahrs", str(trial), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert r.returncode == 3, r.stderr
    assert r.stderr == ("attitude ahrs: error: 01_trial.mat: reading BROAD .mat files needs SciPy: "
                        "pip install 'attitude-c[broad]'\n")


def test_the_extra_the_message_names_installs_scipy():
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover - the test extra installs tomli there
        import tomli as tomllib

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert any(d.startswith("scipy") for d in extras["broad"])


# ---- item 4: the figure and summary.json ---------------------------------------------------------

def test_plot_and_summary_with_a_reference(tmp_path, capsys):
    t, gyr, acc, mag, truth = _recording()
    src = _write(tmp_path / "rec.csv", [t, gyr, acc, mag, truth])
    out = tmp_path / "out"
    assert main(["ahrs", str(src), "--out", str(out), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert json.loads((out / "summary.json").read_text()) == printed
    assert printed["files"] == ["attitude.csv", "attitude.png", "summary.json"]
    assert (out / "attitude.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # ideal sensors (1e-3 noise), constant rate: well under 1° (tests/test_ahrs_cli.py)
    assert printed["errors_deg"]["total"] < 1.0 and printed["errors_over"] == "all samples"
    assert set(printed["flag_fractions"]) == {"rest", "acc gated out", "mag disturbed"}
    assert printed["flag_fractions"]["rest"] == 0.0  # turning at |W| = 0.71 rad/s throughout: never at rest
    assert not list(out.glob(".*tmp*"))  # no temporary file left behind


def test_the_blockwise_run_is_the_batch_filter(tmp_path, capsys):
    """The command runs the filter in 20 ms blocks to sample its flags and bias: the
    attitude is the batch call's (same state, same samples)."""
    from attitude_c import ahrs

    t, gyr, acc, mag, truth = _recording(n=437)  # not a multiple of the block
    src = _write(tmp_path / "rec.csv", [t, gyr, acc, mag, truth])
    assert main(["ahrs", str(src), "--out", str(tmp_path / "o"), "--no-plots"]) == 0
    q = ahrs(np.loadtxt(src, delimiter=",", skiprows=1)[:, 1:4], acc, mag, rate=100.0)
    # attitude.csv prints 9 significant digits: the quaternions agree to that
    assert np.max(np.abs(_attitude(tmp_path / "o")[:, 1:5] - q)) < 1e-8


def test_rest_and_bias_of_the_example_recording(tmp_path, capsys):
    """examples/imu.csv: rest for 3 s, 4 s of motion, rest for 5 s, gyro bias 0.5 °/s on x."""
    out = tmp_path / "o"
    assert main(["ahrs", str(ROOT / "examples" / "imu.csv"), "--out", str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    # rest is declared 1.5 s (rest_time) into a rest once the detector's 0.5 s low-pass has settled:
    # at most 1.5 + 3.5 of the 8 s at rest; at least 1.5 s of the first rest
    assert 1.5 / 12 <= s["flag_fractions"]["rest"] <= (8 - 1.5) / 12
    # the zero-rate updates at rest find the 0.5 °/s bias; 0.05 °/s is 3x the noise's 0.003 rad/s
    # averaged over ~2.5 s at 50 Hz, plus the filter's own convergence
    assert abs(s["bias_final_deg_s"][0] - 0.5) < 0.05
    # the example's noise: gyro 0.003 rad/s, acc 0.03 m/s², field 0.3 µT: measured 0.97° total
    assert s["errors_deg"]["total"] < 1.5
    assert (out / "attitude.png").is_file()


def test_a_broad_trial_summary_scores_the_movement_phases(tmp_path, capsys):
    from scipy.io import savemat

    t, gyr, acc, mag, truth = _recording(n=600)
    movement = (t > 1.0) & (t < 5.0)
    truth = truth.copy()
    truth[:100] = np.nan  # markers lost before the movement: not scored
    trial = tmp_path / "01_undisturbed_test.mat"
    savemat(trial, {"imu_gyr": gyr, "imu_acc": acc, "imu_mag": mag, "opt_quat": truth,
                    "movement": movement[:, None].astype(float), "sampling_rate": 100.0})
    out = tmp_path / "o"
    assert main(["ahrs", str(trial), "--out", str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["errors_over"] == "movement phases" and s["errors_deg"]["samples"] == int(movement[100:].sum())
    assert (out / "attitude.png").is_file() and (out / "summary.json").is_file()
    assert main(["ahrs", str(trial), "--out", str(out), "--axes", "flu"]) == 2  # CSV options: refused
    assert "--axes: for CSV files" in _one_error_line(capsys)


def test_without_a_reference_the_figure_and_summary_still_come(tmp_path, capsys):
    t, gyr, acc, mag, _ = _recording()
    src = _write(tmp_path / "rec.csv", [t, gyr, acc, mag], head="t,gx,gy,gz,ax,ay,az,mx,my,mz")
    out = tmp_path / "o"
    assert main(["ahrs", str(src), "--out", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[-1] == f"wrote {out}/ (attitude.csv, attitude.png, summary.json)"
    s = json.loads((out / "summary.json").read_text())
    assert "errors_deg" not in s and len(s["bias_final_deg_s"]) == 3


# ---- item 5: the CSV reader ----------------------------------------------------------------------

def _flu(v):
    """Vectors of the library's body frame (x right, y forward, z up) as an IMU mounted
    x forward, y left, z up reads them: x_imu = forward, y_imu = −right, z_imu = up."""
    return np.column_stack([v[:, 1], -v[:, 0], v[:, 2]])


def test_mapping_units_axes_and_delimiter_give_the_same_attitude(tmp_path, capsys):
    """One recording written twice: in the library's frame and units, and as an x-forward
    IMU in °/s, g and gauss under other column names with ';' — the same attitude."""
    t, gyr, acc, mag, truth = _recording()
    plain = _write(tmp_path / "plain.csv", [t, gyr, acc, mag, truth])
    q_flu = ref.quat_multiply(truth, [math.cos(math.pi / 4), 0, 0, math.sin(math.pi / 4)])  # C_imu = C_rfu R_z(90°)
    other = _write(tmp_path / "other.csv",
                   [t, np.degrees(_flu(gyr)), _flu(acc) / 9.80665, _flu(mag) / 100.0, q_flu],
                   head="TIME;GyroX;GyroY;GyroZ;AccX;AccY;AccZ;MagX;MagY;MagZ;QW;QX;QY;QZ", delimiter=";")
    assert main(["ahrs", str(plain), "--out", str(tmp_path / "a"), "--no-plots", "--json"]) == 0
    a = json.loads(capsys.readouterr().out)
    assert main(["ahrs", str(other), "--out", str(tmp_path / "b"), "--no-plots", "--json", "--axes", "flu",
                 "--columns", "t=time,gx=gyrox,gy=GyroY,gz=GyroZ", "--columns", "ax=AccX,ay=AccY,az=AccZ",
                 "--columns", "mx=MagX,my=MagY,mz=MagZ", "--gyr-unit", "deg/s", "--acc-unit", "g",
                 "--mag-unit", "gauss"]) == 0
    b = json.loads(capsys.readouterr().out)
    # the inputs differ by the 9-digit printing of the converted values (≤ 5e-10 relative);
    # the filter carries such a perturbation through 500 samples far below 1e-7
    assert np.max(np.abs(_attitude(tmp_path / "a") - _attitude(tmp_path / "b"))) < 1e-6
    assert abs(a["errors_deg"]["total"] - b["errors_deg"]["total"]) < 1e-6


@pytest.mark.parametrize("delimiter", ["\t", " ", ";"])
def test_the_delimiter_is_found_from_the_header(tmp_path, delimiter):
    from attitude_c.recording import read_csv

    t, gyr, acc, mag, truth = _recording(n=50)
    path = _write(tmp_path / "r.csv", [t, gyr, acc, mag, truth], head=HEAD.upper().replace(",", delimiter),
                  delimiter=delimiter)
    rec = read_csv(path)
    assert rec.rate == pytest.approx(100.0) and np.allclose(rec.gyr, gyr, rtol=1e-8)
    assert rec.mag is not None and rec.ref is not None


def test_a_gyro_in_deg_per_s_is_refused_with_the_numbers(tmp_path, capsys):
    t, gyr, acc, mag, truth = _recording()
    src = _write(tmp_path / "deg.csv", [t, np.degrees(gyr), acc, mag, truth])
    assert main(["ahrs", str(src), "--out", str(tmp_path / "o")]) == 2
    line = _one_error_line(capsys)
    assert "looks like deg/s" in line and "--gyr-unit deg/s" in line
    ratio = float(line.split("its rotation is ")[1].split("x")[0])
    assert 50 < ratio < 65  # 57.3 = 180/π, measured on a noisy field
    # said: runs, and the attitude is right
    assert main(["ahrs", str(src), "--out", str(tmp_path / "o"), "--gyr-unit", "deg/s", "--json",
                 "--no-plots"]) == 0
    assert json.loads(capsys.readouterr().out)["errors_deg"]["total"] < 1.0
    # without a magnetometer: the magnitude rule, a rate above 2000 °/s as rad/s
    fast = _write(tmp_path / "fast.csv", [t, np.degrees(gyr) * 80, acc], head="t,gx,gy,gz,ax,ay,az")
    assert main(["ahrs", str(fast), "--out", str(tmp_path / "o")]) == 2
    assert "beyond a MEMS gyro's largest full scale (2000 deg/s = 34.9 rad/s)" in _one_error_line(capsys)


def test_an_accelerometer_in_g_is_refused_with_the_number(tmp_path, capsys):
    t, gyr, acc, mag, truth = _recording()
    src = _write(tmp_path / "g.csv", [t, gyr, acc / 9.80665, mag, truth])
    assert main(["ahrs", str(src), "--out", str(tmp_path / "o")]) == 2
    assert "the accelerometer looks like g: its median norm is 1 (m/s^2: about 9.81)" in _one_error_line(capsys)
    assert main(["ahrs", str(src), "--out", str(tmp_path / "o"), "--acc-unit", "g", "--no-plots"]) == 0


def test_the_gyro_scale_is_1_on_rad_per_s_and_pi_over_180_on_deg_per_s():
    from attitude_c.recording import DEG_PER_S_SCALE, gyro_scale

    _, gyr, _, mag, _ = _recording()
    k = gyro_scale(gyr, mag, 100.0)
    # the field's noise (0.05 µT on ~45 µT) over 50 ms smoothing: within 2 %
    assert k == pytest.approx(1.0, rel=0.02)
    assert gyro_scale(np.degrees(gyr), mag, 100.0) == pytest.approx(k * math.pi / 180, rel=1e-9)
    assert math.pi / 180 < DEG_PER_S_SCALE < 1.0


def test_a_recording_at_rest_is_not_judged_by_the_field(tmp_path, capsys):
    """At rest the field does not turn: the scale is noise over noise, not a verdict."""
    from attitude_c.recording import gyro_scale

    t = np.arange(500) / 100.0
    gyr0, acc0, mag0, truth0 = motion(500, 100.0, (0, 0, 0), noise=0.001, seed=3)
    assert math.isnan(gyro_scale(gyr0, mag0, 100.0))
    src = _write(tmp_path / "rest.csv", [t, gyr0, acc0, mag0, truth0])
    assert main(["ahrs", str(src), "--out", str(tmp_path / "o"), "--no-plots"]) == 0


@pytest.mark.parametrize("argv, words", [
    (["--axes", "xyz"], "--axes: give three letters of r l f b u d"),
    (["--axes", "ffu"], "names one direction twice"),
    (["--axes", "fru"], "left-handed"),
    (["--columns", "gyro_x=Gx"], "unknown name(s) gyro_x"),
    (["--columns", "gx=Nope"], "gx='Nope': no such column"),
    (["--columns", "gx"], "expected NAME=HEADER"),
    (["--gyr-unit", "rpm"], "invalid choice: 'rpm'"),
])
def test_csv_option_mistakes_are_one_line(tmp_path, capsys, argv, words):
    t, gyr, acc, mag, truth = _recording(n=50)
    src = _write(tmp_path / "r.csv", [t, gyr, acc, mag, truth])
    try:
        rc = main(["ahrs", str(src), "--out", str(tmp_path / "o"), *argv])
    except SystemExit as exc:  # argparse's own usage errors (attitude_c.cli._Parser: one line)
        rc = exc.code
    assert rc == 2
    assert words in _one_error_line(capsys)


def test_a_spreadsheet_export_reads(tmp_path):
    """Byte-order mark, CRLF line ends, upper-case names, ';' between the columns."""
    from attitude_c.recording import read_csv

    t, gyr, acc, mag, truth = _recording(n=50)
    rows = "\r\n".join(";".join(f"{v:.9g}" for v in r) for r in np.column_stack([t, gyr, acc]))
    path = tmp_path / "export.csv"
    path.write_bytes(("\ufeffT;GX;GY;GZ;AX;AY;AZ\r\n" + rows + "\r\n").encode("utf-8"))
    rec = read_csv(path)
    assert np.allclose(rec.gyr, gyr, rtol=1e-8) and np.allclose(rec.t, t) and rec.mag is None


def test_an_unwritable_out_is_refused_before_the_run(tmp_path, capsys):
    t, gyr, acc, mag, truth = _recording(n=50)
    src = _write(tmp_path / "r.csv", [t, gyr, acc, mag, truth])
    assert main(["ahrs", str(src), "--out", str(src)]) == 1
    assert "exists and is not a directory" in _one_error_line(capsys)


def test_the_header_lacks_columns_names_them(tmp_path, capsys):
    src = tmp_path / "r.csv"
    src.write_text("time,wx,wy,wz,ax,ay,az\n0,0,0,0,0,0,9.8\n0.01,0,0,0,0,0,9.8\n")
    assert main(["ahrs", str(src), "--out", str(tmp_path / "o")]) == 2
    assert "the header lacks column(s) gx, gy, gz" in _one_error_line(capsys)


@pytest.mark.system
def test_the_example_is_what_its_script_writes(tmp_path):
    r = subprocess.run([sys.executable, str(ROOT / "examples" / "make_imu_csv.py"), str(tmp_path / "imu.csv")],
                       capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert r.returncode == 0, r.stderr
    new, shipped = tmp_path / "imu.csv", ROOT / "examples" / "imu.csv"
    assert new.read_text().splitlines()[:2] == shipped.read_text().splitlines()[:2]
    # 6 significant digits printed: the last one may round differently with another libm
    a, b = (np.loadtxt(f, delimiter=",", skiprows=2) for f in (new, shipped))
    assert a.shape == b.shape and np.allclose(a, b, rtol=1e-5, atol=1e-6)


def test_the_format_is_in_the_help_and_the_readme(capsys):
    with pytest.raises(SystemExit):
        main(["ahrs", "--help"])
    text = capsys.readouterr().out
    for needle in ("t,gx,gy,gz,ax,ay,az,mx,my,mz,qw,qx,qy,qz", "examples/imu.csv", "--columns", "--axes",
                   "x right, y forward, z up", "z-x-y", "--euler zyx"):
        assert needle in text, needle
    assert "``" not in text  # plain text, no reStructuredText markup
    readme = (ROOT / "README.md").read_text()
    assert "attitude ahrs examples/imu.csv" in readme and "gx,gy,gz" in readme


# ---- item 6: frames and the aerospace z-y-x output -----------------------------------------------

def test_axes_presets_map_the_imu_axes_into_the_library_frame():
    from attitude_c.frames import axes_matrix

    # columns of R: where the IMU's x, y, z point in x right / y forward / z up
    assert np.array_equal(axes_matrix("flu"), [[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    assert np.array_equal(axes_matrix("frd"), [[0, 1, 0], [1, 0, 0], [0, 0, -1]])
    assert np.array_equal(axes_matrix("RFU"), np.eye(3))


def _rot(axis, a):
    return ref._rot(axis, np.asarray(a, dtype=float))


def test_zyx_is_the_aerospace_sequence_of_the_frd_body_in_ned():
    """Closed form: C_frd^ned = R_z(ψ) R_y(θ) R_x(φ); the library's C_rfu^enu = M C M
    (M swaps x, y and negates z); euler(q, "zyx") gives (ψ, θ, φ) back."""
    from attitude_c.frames import euler

    rng = np.random.default_rng(4)
    n = 2000
    ang = np.column_stack([rng.uniform(-np.pi, np.pi, n), rng.uniform(-1.5, 1.5, n), rng.uniform(-np.pi, np.pi, n)])
    D = _rot(2, ang[:, 0]) @ _rot(1, ang[:, 1]) @ _rot(0, ang[:, 2])
    M = np.array([[0, 1, 0], [1, 0, 0], [0, 0, -1.0]])
    q = ref.dcm_to_quat(M @ D @ M)
    got = euler(q, "zyx")
    # double rounding through the quaternion near |θ| = 1.5: 1e-9 rad is ~1e4 ulp of margin
    assert np.max(np.abs(got - ang)) < 1e-9
    # the two sequences: same pitch and roll, yaw −ψ (frames.py's module doc)
    zxy = euler(q, "zxy")
    assert np.max(np.abs(zxy[:, 1:] - got[:, 1:])) < 1e-9
    assert np.max(np.abs(np.angle(np.exp(1j * (zxy[:, 0] + got[:, 0]))))) < 1e-9


def test_zyx_at_gimbal_lock_reproduces_the_matrix():
    from attitude_c.frames import euler

    M = np.array([[0, 1, 0], [1, 0, 0], [0, 0, -1.0]])
    for theta in (np.pi / 2, -np.pi / 2):
        D = _rot(2, 0.7) @ _rot(1, theta) @ _rot(0, 0.3)
        yaw, pitch, roll = euler(ref.dcm_to_quat(M @ D @ M), "zyx")
        assert roll == 0.0 and abs(pitch - theta) < 1e-7  # sqrt near the lock: 1e-7 from 1e-16 rounding
        back = _rot(2, yaw) @ _rot(1, pitch) @ _rot(0, roll)
        assert np.max(np.abs(back - D)) < 1e-7


def test_level_facing_east_reads_yaw_minus_90_zxy_and_heading_90_zyx():
    from attitude_c.frames import euler

    # forward (library y) to east: C = R_z(−90°) in the library's ENU
    q = ref.dcm_to_quat(_rot(2, -np.pi / 2))
    assert np.allclose(np.degrees(euler(q, "zxy")), [-90, 0, 0], atol=1e-9)
    assert np.allclose(np.degrees(euler(q, "zyx")), [90, 0, 0], atol=1e-9)
    with pytest.raises(ValueError, match="sequence: choose from zxy, zyx"):
        euler(q, "xyz")  # type: ignore[arg-type]


def test_the_csv_header_states_the_frame_and_the_sequence(tmp_path, capsys):
    from attitude_c.frames import euler

    t, gyr, acc, mag, truth = _recording(n=100)
    src = _write(tmp_path / "r.csv", [t, gyr, acc, mag, truth])
    for seq in ("zxy", "zyx"):
        out = tmp_path / seq
        assert main(["ahrs", str(src), "--out", str(out), "--no-plots", "--euler", seq, "--axes", "flu",
                     "--columns", "qw=nothere"]) == 2  # a missing mapped column: refused
        capsys.readouterr()
        assert main(["ahrs", str(src), "--out", str(out), "--no-plots", "--euler", seq]) == 0
        first, head = (out / "attitude.csv").read_text().splitlines()[:2]
        assert first.startswith("# body x right, y forward, z up") and "body -> ENU" in first
        assert ("z-x-y" if seq == "zxy" else "z-y-x aerospace") in first
        assert head == f"t,qw,qx,qy,qz,yaw_{seq}_deg,pitch_{seq}_deg,roll_{seq}_deg"
        a = _attitude(out)
        assert np.max(np.abs(a[:, 5:] - np.degrees(euler(a[:, 1:5], seq)))) < 1e-5  # 9 printed digits
