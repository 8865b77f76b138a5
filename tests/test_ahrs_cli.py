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
    a = np.loadtxt(out / "attitude.csv", delimiter=",", skiprows=1)
    assert a.shape == (500, 8)
    assert (out / "errors.json").is_file() and not (out / "errors.png").exists()


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
