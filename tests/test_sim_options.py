"""The simulator's options as one table (attitude_c/sim/options.py), SimConfig.from_dict, and the
filter settings parsed in one place for every command (issue 31 item 1).

Nothing here runs a simulation: configurations are built and compared, not run.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pytest
from test_view_sources import _constant_rate_trial

import attitude_c
from attitude_c.cli import build_parser, main
from attitude_c.cli.simulate import build_config
from attitude_c.sim import SimConfig, options
from attitude_c.view import sources
from attitude_c.view.simsource import parse_simulate_options


def _simulate_parser() -> argparse.ArgumentParser:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    p: argparse.ArgumentParser = sub.choices["simulate"]
    return p


def _cli_config(*argv: str) -> SimConfig:
    return build_config(_simulate_parser().parse_args(list(argv)))


def test_the_command_line_is_made_from_the_table() -> None:
    """Every option of the table is an option of attitude simulate, in its group, with its
    choices and default (a text default through the table's type); the command adds only
    how a run is kept."""
    p = _simulate_parser()
    groups = {a.dest: g.title for g in p._action_groups for a in g._group_actions}
    actions = {a.dest: a for a in p._actions}
    for o in options.OPTIONS:
        a = actions[o.name]
        assert o.flag in a.option_strings and groups[o.name] == o.group, o.name
        assert (tuple(a.choices) if a.choices else None) == o.choices, o.name
        if not o.derived_default:
            assert p.parse_args([]).__dict__[o.name] == options.defaults()[o.name], o.name
    own = {d for d, t in groups.items() if t == options.RUN} - {o.name for o in options.OPTIONS}
    assert own == {"out", "budget", "methods", "budget_ber", "no_plots", "no_progress", "json"}
    assert [g.title for g in p._action_groups][2:] == list(options.GROUPS)


@pytest.mark.parametrize("argv, values", [
    ([], {}),
    (["--trajectory", "coning", "--cone-angle", "10", "--period", "0.005", "--ber", "1e-4"],
     {"trajectory": "coning", "cone_angle": 10, "period": 0.005, "ber": 1e-4}),
    (["--amplitude", "10,20,30", "--method", "rv1", "--precision", "fixed", "--oversample", "4"],
     {"amplitude": [10, 20, 30], "method": "rv1", "precision": "fixed", "oversample": 4}),
    (["--accel", "adis16405", "--mag", "hmr3000", "--estimator", "ahrs", "--ahrs-setting", "acc_tau=3",
      "--ahrs-setting", "method=rv1", "--disturbance", "5,8,20,0,0", "--soft-iron", "1,2,3", "--field", "50,60,-3"],
     {"accel": "adis16405", "mag": "hmr3000", "estimator": "ahrs", "ahrs_setting": [["acc_tau", 3], "method=rv1"],
      "disturbance": [[5, 8, 20, 0, 0]], "soft_iron": [1, 2, 3], "field": "50,60,-3"}),
    (["--board", "aided9", "--mag-sr", "--acc-every", "2", "--denoise", "db4", "--denoise-block", "64"],
     {"board": "aided9", "mag_sr": True, "acc_every": 2, "denoise": "db4", "denoise_block": 64}),
])
def test_from_dict_is_the_command_line(argv: list[str], values: dict[str, object]) -> None:
    """A dict of option values -- Python values or the command line's text -- gives the
    configuration the same options give on the command line."""
    want = _cli_config(*argv).params()
    assert SimConfig.from_dict(values).params() == want
    texts = {k: v if isinstance(v, (str, bool, list)) else repr(v) for k, v in values.items()}
    assert SimConfig.from_dict(texts).params() == want


@pytest.mark.parametrize("values, exc, words", [
    ({"perod": 0.1}, ValueError, "perod: not an option of the simulator"),
    ({"period": -1}, ValueError, "--period: must be a finite number > 0, got -1"),
    ({"period": "x"}, ValueError, "--period: expected a number, got 'x'"),
    ({"period": True}, TypeError, "--period: expected a number, got True"),
    ({"oversample": 8.0}, TypeError, "--oversample: expected an integer, got 8.0"),
    ({"oversample": 17}, ValueError, "--oversample: must be in 1..16, got 17"),
    ({"amplitude": [1, 2]}, ValueError, "--amplitude: give one value or three comma-separated values"),
    ({"amplitude": [1, float("nan"), 2]}, ValueError, "--amplitude: values must be finite"),
    ({"method": "rv9"}, ValueError, "--method: invalid choice: 'rv9' (choose from rv1,"),
    ({"method": 3}, TypeError, "--method: expected one of rv1"),
    ({"mag_sr": "yes"}, TypeError, "--mag-sr is a switch: give true or false"),
    ({"ahrs_setting": "nope=1"}, ValueError, "--ahrs-setting: unknown filter setting 'nope'"),
    ({"disturbance": "1,2,3"}, ValueError, "--disturbance: give START,END,X,Y,Z"),
    ({"estimator": "ahrs"}, ValueError, "--estimator ahrs needs an accelerometer"),
    ({"denoise_levels": 3}, ValueError, "--denoise-levels/-mode/-block need --denoise WAVELET"),
])
def test_from_dict_errors_name_the_option(values: dict[str, object], exc: type, words: str) -> None:
    with pytest.raises(exc) as ei:
        SimConfig.from_dict(values)
    assert words in str(ei.value)


def test_a_repeatable_option_takes_one_value_or_a_list() -> None:
    one = options.parse_value("disturbance", "5,8,20,0,0")
    assert one == options.parse_value("disturbance", [5, 8, 20, 0, 0]) == [(5.0, 8.0, (20.0, 0.0, 0.0), 0.0, "body")]
    two = options.parse_value("disturbance", ["5,8,20,0,0", [12, 14, 0, 10, 0, 1, "nav"]])
    assert two[1] == (12.0, 14.0, (0.0, 10.0, 0.0), 1.0, "nav")
    # the typed value, as JSON holds it, parses back to itself (a sweep's run on its worker)
    as_json = [[5.0, 8.0, [20.0, 0.0, 0.0], 0.0, "body"]]
    assert options.parse_value("disturbance", as_json) == one
    assert options.parse_value("ahrs_setting", [["acc_tau", 3.0]]) == [("acc_tau", 3.0)]


# ---- filter settings: one parser for ahrs --set, simulate --ahrs-setting, view --ahrs-setting ----

@pytest.mark.parametrize("text, words", [
    ("nope=1", "unknown filter setting 'nope' (known: "),
    ("acc_tau", "expects NAME=VALUE, got 'acc_tau'"),
    ("acc_tau=x", "acc_tau: expected a number, got 'x'"),
    ("acc_tau=nan", "acc_tau: must be finite, got 'nan'"),
])
def test_every_command_parses_filter_settings_alike(tmp_path: Path, capsys, text: str, words: str) -> None:
    rec = tmp_path / "r.csv"
    rec.write_text("gx,gy,gz,ax,ay,az\n" + "0,0,0,0,0,9.81\n" * 10)
    assert main(["ahrs", str(rec), "--rate", "100", "--out", str(tmp_path / "o"), "--set", text]) == 2
    errs = [capsys.readouterr().err]
    for argv in (["simulate", "--ahrs-setting", text], ["view", "--replay", "x.mat", "--ahrs-setting", text]):
        with pytest.raises(SystemExit) as ei:
            main(argv)
        assert ei.value.code == 2
        errs.append(capsys.readouterr().err)
    for option, err in zip(("--set", "--ahrs-setting", "--ahrs-setting"), errs):
        assert len(err.strip().splitlines()) == 1 and words in err and option in err, err
    assert not (tmp_path / "o").exists()


def test_view_settings_reach_the_filter(tmp_path: Path) -> None:
    """attitude view --ahrs-setting: a BROAD trial replayed through the filter with them,
    and the simulator's filter (before those given after --simulate)."""
    f = tmp_path / "02_nine_axis.mat"
    _constant_rate_trial(f, np.array([0.2, -0.1, 0.3]), attitude_c.euler_to_quat([0.3, -0.2, 0.1]), 120, 100.0)
    src = sources.ReplaySource(f, speed=50.0, settings={"acc_tau": 7.0, "method": "rv1"})
    s = src.estimator.filter.settings  # type: ignore[union-attr]
    assert s["acc_tau"] == 7.0 and s["method"] == "rv1"
    assert "ahrs (rv1)" in src.description
    with pytest.raises(ValueError, match="for the ahrs estimator, not the integrator"):
        sources.ReplaySource(f, estimator="integrator", settings={"acc_tau": 7.0})
    cfg = parse_simulate_options(["--accel", "ideal", "--estimator", "ahrs", "--ahrs-setting", "acc_tau=2"],
                                 ahrs_settings={"acc_tau": 7.0, "rest_noise": 1e-3})
    assert cfg.ahrs_settings == {"acc_tau": 2.0, "rest_noise": 1e-3}


def test_view_refuses_settings_where_no_filter_runs(capsys) -> None:
    pytest.importorskip("aiohttp", reason="attitude view needs aiohttp: pip install 'attitude-c[view]'")
    assert main(["view", "--stdin", "--ahrs-setting", "acc_tau=3"]) == 2
    assert "--ahrs-setting is for --replay and --simulate" in capsys.readouterr().err
    # outside the domain: a usage error before anything is opened, as attitude ahrs says it
    assert main(["view", "--replay", "x.mat", "--ahrs-setting", "acc_tau=-1"]) == 2
    assert "--ahrs-setting: settings: acc_tau=-1.0 outside its domain" in capsys.readouterr().err
