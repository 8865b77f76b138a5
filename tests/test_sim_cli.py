"""`attitude simulate`: default run, --help, bad arguments, outputs, budget."""

from __future__ import annotations

import csv
import json
import math
import os
import re
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


def _noisy(x: float) -> bool:
    """A float printed with float64's rounding noise: 15 or more significant digits in
    its repr that round, at 12, to a short decimal (29.999999999999996, 46.900000000000006)."""
    import re

    def digits(v: float) -> int:
        return len(re.sub(r"[^0-9]", "", repr(v).split("e")[0]).strip("0"))

    return digits(x) >= 15 and digits(float(f"{x:.12g}")) <= 8


def _floats(x, path=""):
    if isinstance(x, dict):
        for k, v in x.items():
            yield from _floats(v, f"{path}.{k}")
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield from _floats(v, f"{path}[{i}]")
    elif isinstance(x, float):
        yield path, x


def test_errors_in_degrees_beside_radians_units_in_the_csv_names_no_float_noise(tmp_path, capsys,
                                                                                   monkeypatch) -> None:
    """The table and errors.png give each error in degrees beside radians; every CSV column
    name ends in its unit (the degree columns are the radian ones converted); the summary's
    numbers carry no float64 rounding noise (the paper's 30° amplitude stays 30.0)."""
    import math

    from matplotlib.figure import Figure

    figures = []
    save = Figure.savefig

    def keep(fig, *a, **k):
        fig.canvas.draw()  # the secondary axes take their limits at draw time
        figures.append(fig)
        return save(fig, *a, **k)

    monkeypatch.setattr(Figure, "savefig", keep)
    out = tmp_path / "run"
    assert main(["simulate", "--duration", "8", "--adc", "ideal", "--calibration", "1", "--accel", "adxl202",
                 "--no-progress", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    assert [p for p, x in _floats(summary) if _noisy(x)] == []
    tr = summary["parameters"]["trajectory"]
    assert tr["amplitude_deg"] == [30.0, 20.0, 25.0] and tr["phase_deg"] == [0.0, 30.0, 60.0]
    assert summary["parameters"]["environment"]["inclination_deg"] == 46.9
    assert summary["elapsed_s"] == round(summary["elapsed_s"], 3)  # a wall time, to the millisecond
    # the table: max, min, RMS in rad then in degrees (3 significant digits)
    head = next(ln for ln in text.splitlines() if ln.startswith("error"))
    assert head.split()[1:8] == ["max", "rad", "min", "rad", "RMS", "rad", "max"]
    for key in ("heading", "pitch", "roll", "attitude_angle"):
        row = next(ln for ln in text.splitlines() if ln.startswith(key + " ")).split()
        e = summary["errors_rad"][key]
        assert [float(v) for v in row[1:4]] == [float(f"{e[k]:.3e}") for k in ("max", "min", "rms")]
        assert [float(v) for v in row[4:7]] == [float(f"{math.degrees(e[k]):.3g}") for k in ("max", "min", "rms")]
    # the CSV files: units in every name; the degrees are the radians converted
    with open(out / "timeseries.csv") as fh:
        rows = list(csv.DictReader(fh))
    names = list(rows[0])
    assert [n for n in names if not n.endswith(("_s", "_rad", "_deg")) and not n.startswith("q")] == []
    for e in ("yaw", "pitch", "roll", "heading", "angle"):
        rad = np.array([float(r[f"err_{e}_rad"]) for r in rows])
        deg = np.array([float(r[f"err_{e}_deg"]) for r in rows])
        np.testing.assert_allclose(deg, np.degrees(rad), rtol=1e-11, atol=0)  # 13 digits printed in each
    with open(out / "sensors.csv") as fh:
        head = next(csv.reader(fh))
    assert head[:3] == ["sample", "t_start_s", "t_mid_s"]
    assert all(n.endswith(("_rad_s", "_m_s2")) for n in head[3:]), head
    # errors.png: each panel's error axis in rad with the same axis in degrees on its right
    errs = next(f for f in figures if f.texts and f.texts[0].get_text().startswith("Attitude error curves"))
    for ax in errs.axes:
        assert ax.get_ylabel() == "error / rad"
        (deg_ax,) = ax.child_axes
        assert deg_ax.get_ylabel() == "error / °"
        np.testing.assert_allclose(deg_ax.get_ylim(), np.degrees(ax.get_ylim()), rtol=1e-12)
        assert "°" in ax.get_title(loc="right")


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
    # every cell in rad and in degrees: the degrees are the rad value x 180/pi to the 3 digits shown
    cells = re.findall(r"(\d\.\d\de[-+]\d+) rad = (\d\.\d\de[-+]\d+)°", text)
    assert len(cells) >= 2 * 2  # at least two stages for each of the two methods
    for rad, deg in cells:
        assert float(deg) == pytest.approx(math.degrees(float(rad)), rel=0.01)  # both rounded to 3 digits
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
