"""`attitude simulate`: default run, --help, bad arguments, outputs, budget."""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from attitude_c.cli import main

pytestmark = pytest.mark.system  # runs attitude simulate end to end

ROOT = Path(__file__).resolve().parents[1]


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


@pytest.mark.system
def test_help_lists_the_options() -> None:
    r = subprocess.run([sys.executable, "-m", "attitude_c", "simulate", "--help"],
                       capture_output=True, text=True, env=_env(), cwd=ROOT, timeout=60,
                       check=False)
    assert r.returncode == 0, r.stderr
    for opt in ("--seed", "--budget", "--method", "--precision", "--ber", "--out", "--trajectory"):
        assert opt in r.stdout


def test_default_run_writes_every_output(tmp_path, capsys) -> None:
    """The bare command (defaults: the paper's 60 s scenario) with --out."""
    out = tmp_path / "run"
    assert main(["simulate", "--out", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "heading" in text and "pitch" in text and "paper max" in text
    summary = json.loads((out / "summary.json").read_text())
    assert summary["parameters"]["method"] == "rv3"
    assert summary["parameters"]["period_s"] == 0.08
    assert summary["parameters"]["duration_s"] == 60.0
    for k in ("heading", "pitch", "roll"):
        assert set(summary["errors_rad"][k]) >= {"max", "min", "rms"}
    assert summary["link"]["sent"] == 750
    with open(out / "timeseries.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == summary["updates"] == 250
    assert float(rows[-1]["t_s"]) == pytest.approx(60.0)
    import matplotlib.image as mpimg

    for png in ("errors.png", "attitude.png"):
        img = mpimg.imread(out / png)
        assert img.ndim == 3 and img.shape[0] > 300 and img.shape[1] > 500
        assert np.std(img) > 0.01  # not blank


def test_seed_reproducible(tmp_path) -> None:
    args = ["simulate", "--duration", "8", "--no-plots", "--no-progress", "--adc", "ideal"]
    for name, seed in (("a", "3"), ("b", "3"), ("c", "4")):
        assert main(args + ["--seed", seed, "--out", str(tmp_path / name)]) == 0
    s = {n: json.loads((tmp_path / n / "summary.json").read_text())["errors_rad"] for n in "abc"}
    assert s["a"] == s["b"]
    assert s["a"] != s["c"]


@pytest.mark.parametrize("argv, needle", [
    (["--period", "-1"], "--period"),
    (["--period", "abc"], "--period"),
    (["--method", "rv9"], "--method"),
    (["--ber", "0.9"], "BER"),
    (["--oversample", "40"], "--oversample"),
    (["--amplitude", "1,2"], "--amplitude"),
    (["--seed", "x"], "--seed"),
])
def test_bad_arguments_are_usage_errors(argv, needle, capsys) -> None:
    with pytest.raises(SystemExit) as ei:
        main(["simulate", *argv])
    assert ei.value.code == 2
    assert needle in capsys.readouterr().err


@pytest.mark.parametrize("argv, needle", [
    (["--trajectory", "csv"], "--trajectory-file"),
    (["--trajectory", "csv", "--trajectory-file", "/nonexistent/t.csv"], "cannot read"),
    (["--amplitude", "30,95,10"], "pitch"),
    (["--link", "none", "--ber", "1e-3"], "ber"),
])
def test_bad_values_give_clear_errors(argv, needle, tmp_path, capsys) -> None:
    rc = main(["simulate", "--no-progress", "--out", str(tmp_path / "x"), *argv])
    assert rc == 2
    err = capsys.readouterr().err
    assert err.startswith("attitude simulate: error:") and needle in err


def test_csv_trajectory_run(tmp_path) -> None:
    t = np.arange(0, 10.0001, 0.02)
    e = np.column_stack([20 * np.sin(t), 10 * np.sin(0.7 * t), 15 * np.cos(0.5 * t)])
    p = tmp_path / "traj.csv"
    np.savetxt(p, np.column_stack([t, e]), delimiter=",", header="time,yaw_deg,pitch_deg,roll_deg",
               comments="", fmt="%.12g")
    out = tmp_path / "o"
    assert main(["simulate", "--trajectory", "csv", "--trajectory-file", str(p), "--duration", "9",
                 "--sensors", "ideal", "--no-plots", "--no-progress", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["parameters"]["trajectory"]["trajectory"] == "csv"
    assert s["errors_rad"]["attitude_angle"]["max_abs"] < 1e-3


def test_budget_cli(tmp_path, capsys) -> None:
    out = tmp_path / "b"
    assert main(["simulate", "--budget", "--duration", "9", "--methods", "rv1,rv3",
                 "--budget-ber", "0", "--no-progress", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "dominant source" in text
    b = json.loads((out / "budget.json").read_text())
    assert b["methods"] == ["rv1", "rv3"]
    assert b["dominant_source"]["rv1"] == "algorithm"
    assert (out / "budget.md").read_text().startswith("| stage |")
    import matplotlib.image as mpimg

    assert mpimg.imread(out / "budget.png").shape[0] > 200


def _table_summary(heading_max_abs: float, pitch_max_abs: float) -> dict:
    from attitude_c.sim import PAPER_MAXIMA

    err = {k: {"max": 0.0, "min": 0.0, "rms": 0.0, "max_abs": 0.0}
           for k in ("heading", "pitch", "roll", "attitude_angle")}
    err["heading"].update(max=heading_max_abs, max_abs=heading_max_abs)
    err["pitch"].update(max=pitch_max_abs, max_abs=pitch_max_abs)
    return {
        "parameters": {"trajectory": {"trajectory": "paper"}, "method": "rk4", "precision": "f64",
                       "sensors": "full", "gyro": {"name": "cg-l53"}, "period_s": 0.08,
                       "duration_s": 60.0, "seed": 0},
        "errors_rad": err,
        "paper_maxima_rad": {"heading": PAPER_MAXIMA["heading"][1], "pitch": PAPER_MAXIMA["pitch"][1]},
        "times_better_than_paper": {"heading": PAPER_MAXIMA["heading"][1] / heading_max_abs,
                                    "pitch": PAPER_MAXIMA["pitch"][1] / pitch_max_abs},
        "link": {}, "updates": 250,
    }


def test_table_prints_the_true_ratio_below_one_when_worse() -> None:
    """A run worse than the paper (heading 0.87 rad against 0.12; pitch 0.25
    against 0.15) shows ratios below 1, truncated, never rounded up to 1."""
    from attitude_c.sim.report import format_table

    text = format_table(_table_summary(0.87, 0.25))
    rows = {ln.split()[0]: ln.split() for ln in text.splitlines() if ln.startswith(("heading", "pitch"))}
    assert rows["heading"][-1] == "0.13"  # 0.12 / 0.87 = 0.1379...
    assert rows["pitch"][-1] == "0.6"  # 0.15 / 0.25
    assert "larger than the paper's maximum" in text


@pytest.mark.parametrize("ratio, shown", [
    (0.996, "0.99"), (0.999999, "0.99"), (0.138, "0.13"), (0.6, "0.6"), (0.00123, "0.0012"),
    (3e-5, "3.0e-05"), (1.0, "1"), (3.46, "3.4"), (9.99, "9.9"), (212.9, "212"), (float("inf"), "inf"),
])
def test_ratio_is_truncated_never_rounded_up(ratio, shown) -> None:
    from attitude_c.sim.report import format_ratio

    assert format_ratio(ratio) == shown


def _short_csv(tmp_path: Path) -> Path:
    """A 10 s trajectory file (rows every 0.02 s)."""
    t = np.arange(0, 10.0001, 0.02)
    e = np.column_stack([20 * np.sin(t), 10 * np.sin(0.7 * t), 15 * np.cos(0.5 * t)])
    p = tmp_path / "short.csv"
    np.savetxt(p, np.column_stack([t, e]), delimiter=",", header="time,yaw_deg,pitch_deg,roll_deg",
               comments="", fmt="%.12g")
    return p


def test_csv_file_alone_runs_the_files_span(tmp_path) -> None:
    """`--trajectory-file` alone means `--trajectory csv`, and the duration is
    the file's span (10 s), not the 60 s default held at the last row."""
    out = tmp_path / "o"
    assert main(["simulate", "--trajectory-file", str(_short_csv(tmp_path)), "--sensors", "ideal",
                 "--no-plots", "--no-progress", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["parameters"]["trajectory"]["trajectory"] == "csv"
    assert s["parameters"]["duration_s"] == pytest.approx(10.0)
    assert s["updates"] == 41  # rv3: one update per 3 samples of 0.08 s in 10 s (125 samples)


def test_csv_shorter_than_an_explicit_duration_is_an_error(tmp_path, capsys) -> None:
    p = _short_csv(tmp_path)
    rc = main(["simulate", "--trajectory-file", str(p), "--duration", "60", "--no-progress",
               "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert rc == 2
    assert "--duration 60 s is longer than the trajectory file" in err and "10 s" in err
    assert not (tmp_path / "x").exists()
    # the library refuses the same run
    from attitude_c.errors import InvalidArgument
    from attitude_c.sim import SimConfig, make_trajectory, simulate

    with pytest.raises(InvalidArgument, match="longer than the trajectory's data"):
        simulate(SimConfig(trajectory=make_trajectory("csv", path=p), duration=10.5, sensors="ideal",
                           link="none"))
    # an explicit paper trajectory with a file is still a contradiction
    rc = main(["simulate", "--trajectory", "paper", "--trajectory-file", str(p), "--no-progress"])
    assert rc == 2 and "only used with --trajectory csv" in capsys.readouterr().err
