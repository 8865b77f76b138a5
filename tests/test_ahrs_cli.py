"""``attitude ahrs``: a CSV recording with a reference, the outputs, one-line errors."""

from __future__ import annotations

import json

import numpy as np
from test_ahrs import motion  # tests/ is on the path (pytest's rootdir conftest)

from attitude_c.cli import main


def _csv(path, with_t=True):
    gyr, acc, mag, truth = motion(500, 100.0, (0.1, -0.2, 0.3), noise=0.001)
    t = np.arange(500) / 100.0
    cols = ([t[:, None]] if with_t else []) + [gyr, acc, mag, truth]
    head = ("t," if with_t else "") + "gx,gy,gz,ax,ay,az,mx,my,mz,qw,qx,qy,qz"
    np.savetxt(path, np.hstack(cols), delimiter=",", header=head, comments="")


def test_csv_with_reference(tmp_path, capsys):
    src = tmp_path / "rec.csv"
    _csv(src)
    out = tmp_path / "out"
    assert main(["ahrs", str(src), "--out", str(out), "--json", "--no-plots"]) == 0
    summary = json.loads(capsys.readouterr().out)
    # ideal sensors (1e-3 noise), aligned from the first sample: well under 1°
    assert summary["errors_deg"]["total"] < 1.0
    a = np.loadtxt(out / "attitude.csv", delimiter=",", skiprows=2)  # the frames line, the header
    assert a.shape == (500, 8)
    assert (out / "summary.json").is_file() and not (out / "attitude.png").exists()


def test_errors_are_one_line(tmp_path, capsys):
    src = tmp_path / "rec.csv"
    _csv(src, with_t=False)
    assert main(["ahrs", str(src), "--out", str(tmp_path / "o")]) == 2  # no t column, no --rate
    assert main(["ahrs", str(tmp_path / "missing.csv")]) == 1
    assert main(["ahrs", str(src), "--rate", "100", "--set", "acc_tau"]) == 2
    assert main(["ahrs", str(src), "--rate", "100", "--set", "acc_noise=-1"]) == 2
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n")
    assert main(["ahrs", str(bad), "--rate", "100"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 5 and all(line.startswith("attitude ahrs: error: ") for line in err)


def test_sensor_delays_and_the_mag_delay_estimate(tmp_path, capsys):
    """--set acc_delay/mag_delay run; --estimate-mag-delay prints the lag relative to the run's attitude."""
    from test_timing import RATE, _record

    d = 0.013
    t, truth, gyr, mag, acc = _record(d, n=3000)  # closed-form motion, field sampled at t − d
    src = tmp_path / "lagged.csv"
    np.savetxt(src, np.hstack([t[:, None], gyr, acc, mag, truth]), delimiter=",",
               header="t,gx,gy,gz,ax,ay,az,mx,my,mz,qw,qx,qy,qz", comments="")
    out = tmp_path / "o"
    assert main(["ahrs", str(src), "--out", str(out), "--json", "--no-plots", "--estimate-mag-delay",
                 "--set", "acc_delay=0.002", "--set", f"mag_delay={d}"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["settings"] == {"acc_delay": 0.002, "mag_delay": d}
    # relative to the filter's attitude the lag reads d + dt/2 (tests/test_timing.py, which
    # derives the ~1.4 ms bound of the attitude-error term for this motion)
    assert abs(summary["mag_delay_estimate_s"] - (d + 0.5 / RATE)) < 0.0015
    assert main(["ahrs", str(src), "--out", str(out), "--no-plots", "--estimate-mag-delay"]) == 0
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("magnetometer lag")]
    assert len(lines) == 1 and "use it with --set mag_delay=0.01" in lines[0]
    # a user mistake is one line, exit 2: out of the settings' domain; no magnetometer to estimate from
    assert main(["ahrs", str(src), "--out", str(out), "--set", "mag_delay=0.2"]) == 2
    assert main(["ahrs", str(src), "--out", str(out), "--six-axis", "--estimate-mag-delay"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all(line.startswith("attitude ahrs: error: ") for line in err)
    assert "mag_delay" in err[0] or "domain" in err[0]
