"""The attitude filter as the simulator's estimator stage (issue 15, simulator
side): ``SimConfig(estimator="ahrs")``, ``attitude simulate --estimator ahrs``,
the bias in the summary and plots, and the filter in ``attitude view``'s
registry. The acceptance figures are in tests/test_sim_ahrs_acceptance.py."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import attitude_c
from attitude_c.ahrs_filter import Ahrs, default_settings
from attitude_c.ahrs_filter import ahrs as ahrs_batch
from attitude_c.cli import main
from attitude_c.cli.simulate import build_config, register
from attitude_c.errors import InvalidArgument
from attitude_c.sim import (
    AdcModel,
    AhrsFilter,
    SimConfig,
    accel_preset,
    acquire,
    mag_preset,
    make_trajectory,
    simulate,
)
from attitude_c.sim.estimator import to_period_end
from attitude_c.view.estimators import ESTIMATORS, make_estimator


def _args(*argv: str) -> argparse.Namespace:
    p = argparse.ArgumentParser()
    sub = p.add_subparsers()
    register(sub)
    return p.parse_args(["simulate", *argv])


def _fast(**kw: Any) -> SimConfig:  # the vectorized ADC and no link: the acquisition in a fraction of a second
    base: dict[str, Any] = {"adc": AdcModel(backend="ideal"), "link": "none", "estimator": "ahrs"}
    base.update(kw)
    return SimConfig(**base)


def test_stage_feeds_the_filter_the_hosts_rates_and_readings() -> None:
    """The stage is exactly attitude_c.ahrs on Δθ/h, the accelerometer and the
    magnetometer rows moved to the period's end, dt = h, from the true attitude at the first sample's
    start, with the environment's declination and gravity; each attitude is
    at the end of its sample period. Same library both sides: agreement to
    rounding (f64, 1e-12)."""
    cfg = _fast(trajectory=make_trajectory("turntable", rate=[0.0, 0.0, math.radians(5.0)]), duration=8.0,
                period=0.02, accel=accel_preset("adis16405"), mag=mag_preset("hmr3000"))
    acq = acquire(cfg)
    dec = acq.decoded
    assert dec is not None
    h = cfg.period
    est = cfg.estimator_stage().run(dec, cfg.trajectory.quat, cfg.trajectory.t_start, h)
    q0 = cfg.trajectory.quat(cfg.trajectory.t_start + dec.sample_index[0] * h)
    inc = dec.increments
    q = ahrs_batch(inc / h, to_period_end(inc, dec.aux["accel"]), to_period_end(inc, dec.aux["mag"]), dt=h, q0=q0,
                        declination=cfg.environment.declination, gravity=cfg.environment.gravity)
    np.testing.assert_allclose(est.q, q, atol=1e-12)
    np.testing.assert_allclose(est.t, cfg.trajectory.t_start + (dec.sample_index + 1) * h, rtol=1e-12)
    assert est.bias is not None and est.bias_t is not None and est.bias.shape == (len(est.bias_t), 3)
    assert est.info["axes"] == 9


def test_period_means_move_to_the_period_end() -> None:
    """Closed form: the body turns at ω about a fixed axis; a nav-fixed vector
    seen in the body turns at −ω, so its mean over [0, h] points where the
    vector is at h/2 (its norm shrinks by sinc), and moved by −Δθ/2 it points
    where the vector is at h. Exact for a constant rate: rounding (1e-15)."""
    h, w = 0.08, np.array([0.3, -0.5, 1.2])
    a = np.linalg.norm(w * h)
    k = w / np.linalg.norm(w)
    v0 = np.array([0.2, 20.0, -40.0])

    def at(t: float) -> np.ndarray:  # the body-frame vector at t: rotated by −ω t (Rodrigues)
        th = -np.linalg.norm(w) * t
        return v0 * np.cos(th) + np.cross(k, v0) * np.sin(th) + k * (k @ v0) * (1 - np.cos(th))

    mid, end = at(h / 2), at(h)
    par = k * (k @ mid)  # the mean: the axial part as is, the rest scaled by sinc(a/2)
    mean = par + (mid - par) * np.sin(a / 2) / (a / 2)
    got = to_period_end((w * h)[None, :], mean[None, :])[0]
    want = k * (k @ end) + (end - k * (k @ end)) * np.sin(a / 2) / (a / 2)
    np.testing.assert_allclose(got, want, atol=1e-13)
    np.testing.assert_array_equal(to_period_end(np.zeros((1, 3)), v0[None, :])[0], v0)


def test_perfect_sensors_keep_the_truth() -> None:
    """Exact increments, exact specific force and field (moved to the period
    end), started at the truth: every innovation is zero and the attitude
    stays the truth (the only error is the integrator's on a constant-rate
    turn, exact to rounding); the bias estimate stays 0. 1e-9 rad and
    1e-9 rad/s: rounding over 250 samples is ~1e-13; without the move to the
    period end the heading would lag by ωh/2 = 3.5e-3 rad."""
    cfg = _fast(trajectory=make_trajectory("turntable", rate=[0.0, 0.0, math.radians(5.0)]), duration=20.0,
                sensors="ideal", accel=accel_preset("ideal"), mag=mag_preset("ideal"))
    res = simulate(cfg)
    assert np.max(res.err_angle) < 1e-9
    assert res.bias is not None and np.max(np.abs(res.bias)) < 1e-9


def test_six_axis_without_a_magnetometer_and_errors() -> None:
    cfg = _fast(trajectory=make_trajectory("static"), duration=5.0, accel=accel_preset("adis16405"))
    res = simulate(cfg)
    assert res.summary["estimator"]["axes"] == 6
    assert res.summary["backends"]["estimator"].startswith("attitude_c.Ahrs (f64")
    with pytest.raises(InvalidArgument, match="needs an accelerometer"):
        _fast(duration=1.0).validate()
    with pytest.raises(InvalidArgument, match="f64 or f32"):
        _fast(duration=1.0, accel=accel_preset("ideal"), precision="fixed").validate()
    with pytest.raises(InvalidArgument, match="unknown filter setting 'nope'"):
        _fast(duration=1.0, accel=accel_preset("ideal"), ahrs_settings={"nope": 1.0}).validate()
    with pytest.raises(InvalidArgument, match="outside its domain"):
        _fast(duration=1.0, accel=accel_preset("ideal"), ahrs_settings={"rest_noise": -1.0}).validate()
    with pytest.raises(InvalidArgument, match="need the ahrs estimator"):
        SimConfig(ahrs_settings={"rest_noise": 1e-3}).validate()
    with pytest.raises(InvalidArgument, match="'f64' or 'f32'"):
        AhrsFilter(precision="fixed")


def test_default_run_is_still_the_integrator() -> None:
    cfg = build_config(_args())
    assert cfg.estimator == "integrator" and "estimator" not in cfg.params()


@pytest.mark.system
def test_cli_options_reach_the_filter(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "run"
    rc = main(["simulate", "--trajectory", "static", "--duration", "4", "--adc", "ideal", "--link", "none",
               "--accel", "adis16405", "--mag", "hmr3000", "--estimator", "ahrs", "--ahrs-setting",
               "rest_noise=3e-4", "--ahrs-setting", "method=rv3", "--ahrs-init", "align", "--precision", "f32",
               "--no-progress", "--out", str(out)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "estimator ahrs" in text and "gyro bias estimate at the end" in text
    s = json.loads((out / "summary.json").read_text())
    e = s["estimator"]
    assert e["settings"]["rest_noise"] == pytest.approx(3e-4) and e["settings"]["method"] == "rv3"
    assert e["init"] == "align" and e["axes"] == 9 and len(e["bias_final_rad_s"]) == 3
    # the simulated environment's declination reaches the filter unless a setting overrides it
    assert e["settings"]["declination"] == pytest.approx(math.radians(-5.1))
    assert s["parameters"]["estimator"] == "ahrs" and s["parameters"]["ahrs_settings"]["method"] == "rv3"
    assert s["backends"]["estimator"] == "attitude_c.Ahrs (f32, rv3)"
    assert (out / "bias.png").stat().st_size > 0


@pytest.mark.parametrize("argv, message", [
    (["--estimator", "ahrs"], "--estimator ahrs needs an accelerometer: give --accel PART"),
    (["--ahrs-setting", "rest_noise=1"], "--ahrs-setting and --ahrs-init need --estimator ahrs"),
    (["--estimator", "ahrs", "--accel", "ideal", "--precision", "fixed"], "f64 or f32, not fixed"),
    (["--estimator", "ahrs", "--accel", "ideal", "--budget"], "--budget compares the integrator's methods"),
    (["--estimator", "ahrs", "--accel", "ideal", "--ahrs-setting", "acc_tau=-2"], "outside its domain"),
])
def test_cli_errors_are_one_line(argv: list[str], message: str, capsys: pytest.CaptureFixture[str],
                                 tmp_path: Path) -> None:
    rc = main(["simulate", "--duration", "1", "--no-progress", "--out", str(tmp_path / "x"), *argv])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize("value, message", [("foo=1", "unknown filter setting 'foo'"),
                                            ("acc_tau", "expects NAME=VALUE"),
                                            ("acc_tau=x", "expected a number")])
def test_cli_setting_names_are_the_filters(value: str, message: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        _args("--estimator", "ahrs", "--accel", "ideal", "--ahrs-setting", value)
    assert e.value.code == 2 and message in capsys.readouterr().err


# ---- attitude view ------------------------------------------------------------------------

def test_view_registry_has_the_filter() -> None:
    spec = ESTIMATORS["ahrs"]
    assert spec.needs_acc
    with pytest.raises(InvalidArgument, match="needs accelerometer samples"):
        make_estimator("ahrs", has_acc=False)
    q0 = attitude_c.euler_to_quat([0.3, -0.2, 0.1])
    est = make_estimator("ahrs", has_acc=True, method="rv3", q0=q0, rate=100.0)
    assert est.label == f"ahrs ({default_settings()['method']})"
    # per-sample streaming equals the filter's batch call on the same samples (same library: rounding)
    rng = np.random.default_rng(1)
    n = 300
    gyr = rng.normal(0.0, 0.2, (n, 3))
    acc = np.array([0.0, 0.0, 9.81]) + rng.normal(0.0, 0.05, (n, 3))
    mag = np.array([0.0, 20.0, -40.0]) + rng.normal(0.0, 0.2, (n, 3))
    mag[100:110] = np.nan  # a sample without a field: six-axis for it
    got = np.array([est.update(gyr[k], 0.01, acc[k], mag[k]) for k in range(n)])
    f = Ahrs(rate=100.0, q0=q0)
    want = np.array([f.update(gyr[k], acc[k], None if k in range(100, 110) else mag[k]) for k in range(n)])
    np.testing.assert_allclose(got, want, atol=1e-12)
    assert est.update(np.array([np.nan, 0, 0]), 0.01, acc[0], mag[0]) is None  # skipped, not an error


def test_view_serial_refuses_the_filter(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("aiohttp", reason="attitude view needs aiohttp: pip install 'attitude-c[view]'")
    rc = main(["view", "--serial", "/dev/null-not-a-port", "--estimator", "ahrs"])
    err = capsys.readouterr().err
    assert rc == 2 and "--estimator ahrs needs accelerometer samples" in err


def test_view_simulate_runs_the_filter() -> None:
    from attitude_c.view.simsource import SimulatorSource, parse_simulate_options

    opts = ["--trajectory", "static", "--duration", "2", "--adc", "ideal", "--link", "none", "--accel",
            "adis16405", "--estimator", "ahrs"]
    src = SimulatorSource(parse_simulate_options(opts))
    assert "static trajectory" in src.description and "ahrs (f64)" in src.description
    res = simulate(parse_simulate_options(opts))
    items = list(src.items(res))
    samples = [i for i in items if i[1] == "sample"]
    assert len(samples) == len(res.t) == 25  # one attitude per 0.08 s sample
    # and the filter's gyro-bias estimate as counters, each time the run recorded it
    assert sum(1 for i in items if i[1] == "counters") == len(res.bias_t)
