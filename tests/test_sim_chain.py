"""The whole chain: accuracy against the paper, method ranking, error budget,
link errors, bad input."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from attitude_c.errors import InvalidArgument
from attitude_c.sim import (
    AdcModel,
    ConingTrajectory,
    PaperTrajectory,
    SimConfig,
    StaticTrajectory,
    acquire,
    gyro_preset,
    run_budget,
    simulate,
)

PAPER_HEADING, PAPER_PITCH = 0.12, 0.15  # sec. 4 of the paper, rad
ADC = "tlc2543"


def _max(res, key: str) -> float:
    return res.summary["errors_rad"][key]["max_abs"]


def test_ideal_sensors_rv3_is_1000x_better_than_the_paper() -> None:
    res = simulate(SimConfig(sensors="ideal", link="none", method="rv3"))
    assert res.t[-1] == pytest.approx(60.0)
    assert _max(res, "heading") <= PAPER_HEADING / 1000
    assert _max(res, "pitch") <= PAPER_PITCH / 1000


@pytest.mark.parametrize("seed", [0, 1])
def test_full_default_chain_is_100x_better_than_the_paper(seed: int) -> None:
    cfg = SimConfig(seed=seed, adc=AdcModel(backend=ADC))  # defaults: cg-l53, 12-bit, calibration
    res = simulate(cfg)
    assert res.summary["parameters"]["sensors"] == "full"
    assert _max(res, "heading") <= PAPER_HEADING / 100
    assert _max(res, "pitch") <= PAPER_PITCH / 100
    # the noise really is in: a different seed gives different errors
    assert res.summary["errors_rad"]["heading"]["rms"] > 1e-5


def _drift(method: str, tr, h: float, duration: float) -> float:
    res = simulate(SimConfig(trajectory=tr, sensors="ideal", link="none", method=method,
                             period=h, duration=duration))
    return res.summary["errors_rad"]["attitude_angle"]["max_abs"]


def test_methods_rank_as_coning_theory_predicts() -> None:
    """Classical coning (α = 20°, 0.5 Hz, h = 0.08 s, 30 s): the coning drift of
    an N-sample algorithm falls as (Ωh)^(2N) (Ignagni 1990), and the 9/20, 27/40
    coefficients minimize it for three samples, so
    rv1 ≫ rv2 > rv3 (Miller) > rv3-coning."""
    tr = ConingTrajectory()
    d = {m: _drift(m, tr, 0.08, 30.0) for m in ("rv1", "rv2", "rv3", "rv3-coning")}
    assert d["rv1"] > 30 * d["rv2"]
    assert d["rv2"] > d["rv3"] > d["rv3-coning"]


def test_error_orders_on_the_paper_motion() -> None:
    """Halving h on the paper's motion: rv1's error falls ~4× (second order),
    the multi-sample methods' ~16× (fourth order), the reuse forms' ~8× (third
    order: they extrapolate the newest interval's correction from the past
    increments; docs/integrator.md, sec. 3.3). Bounds leave ±25 % for the
    higher-order terms at h = 0.08 s (Ωh ≈ 0.15)."""
    tr = PaperTrajectory()
    for m, order in (("rv1", 2), ("rv2", 4), ("rv3", 4), ("rv3-reuse", 3), ("rv3-reuse-poly", 3)):
        ratio = _drift(m, tr, 0.08, 30.0) / _drift(m, tr, 0.04, 30.0)
        assert 0.75 * 2**order < ratio < 1.25 * 2**order, (m, ratio)


def test_budget_shows_the_dominant_source() -> None:
    base = SimConfig(duration=30.0, adc=AdcModel(backend=ADC))
    b = run_budget(base, methods=("rv1", "rv3"), ber=0.0)
    assert b.stages[:3] == ["algorithm", "+ quantization", "+ gyro noise/bias"]
    # rv1's non-commutativity error (~1e-3 rad) dwarfs the sensors; for rv3 the
    # algorithm error (~2e-5) is far below the 12-bit quantization (~3e-4) and
    # the gyro noise of the default chain
    assert b.dominant["rv1"] == "algorithm"
    assert b.dominant["rv3"] in ("+ quantization", "+ gyro noise/bias")
    j = b.methods.index("rv3")
    assert 5 * b.rms[0, j] < b.rms[1, j]
    assert b.rms[0, j] < b.rms[2, j]
    assert "float32" in " ".join(b.stages)


def test_static_full_chain_stays_put() -> None:
    """At rest only noise and the calibration residual remain: noise
    0.002 °/s/√Hz → 0.27 mrad (1σ) after 60 s; 2 mrad is > 5σ."""
    res = simulate(SimConfig(trajectory=StaticTrajectory(), adc=AdcModel(backend=ADC)))
    assert _max(res, "attitude_angle") < 2e-3


def test_adxrs150_noise_is_what_limits_a_mems_chain() -> None:
    """With the thesis's ADXRS150 (0.05 °/s/√Hz) the angle random walk alone is
    0.05°·√60 s ≈ 6.8 mrad (1σ): the 100× target is out of reach for it, as
    docs/error-budget.md explains; still far better than the paper."""
    res = simulate(SimConfig(gyro=gyro_preset("adxrs150"), adc=AdcModel(backend=ADC)))
    assert 1e-3 < _max(res, "attitude_angle") < PAPER_HEADING / 3


def test_f32_and_reproducible_seed() -> None:
    a = simulate(SimConfig(duration=10.0, precision="f32", seed=7, adc=AdcModel(backend="ideal")))
    b = simulate(SimConfig(duration=10.0, precision="f32", seed=7, adc=AdcModel(backend="ideal")))
    c = simulate(SimConfig(duration=10.0, precision="f32", seed=8, adc=AdcModel(backend="ideal")))
    assert np.array_equal(a.q_est, b.q_est)
    assert not np.array_equal(a.q_est, c.q_est)


def test_rk4_and_reuse_run_through_the_chain() -> None:
    for m in ("rk4", "rv3-reuse", "rv3-reuse-poly"):
        res = simulate(SimConfig(method=m, sensors="ideal", link="none", duration=20.0))
        assert len(res.t) > 100
        assert _max(res, "attitude_angle") < 1e-3


def test_rv3_reuse_no_worse_than_rv3_on_the_paper_scenario() -> None:
    """Issue 11, sec. 1: ``attitude simulate --method rv3-reuse`` on the
    paper scenario is no worse than ``--method rv3`` on any error figure of
    the summary. This is the CLI's default run itself (paper trajectory,
    60 s, h = 0.08 s, full sensor chain, C link, seed 0; the CLI's
    summary.json holds the same figures), not a shortened one: through the
    API it takes ~0.3 s. Both methods see the same acquisition. The
    margins are small (pitch 0.15 %): the sensor chain's errors
    (~6e-4 rad) are 13× the algorithms' on this motion (ideal sensors:
    rv3-reuse 4.5e-5, rv3 3.2e-5 rad, docs/simulation.md), so a shorter run
    can tip single figures either way (at 20 s roll is 0.4 % worse)."""
    cfg = SimConfig()
    acq = acquire(cfg)
    err = {m: simulate(replace(cfg, method=m), acquired=acq).summary["errors_rad"]
           for m in ("rv3", "rv3-reuse")}
    for fig in ("heading", "pitch", "roll", "attitude_angle"):
        for stat in ("max_abs", "rms"):
            assert err["rv3-reuse"][fig][stat] <= err["rv3"][fig][stat], (fig, stat, err)


@pytest.mark.parametrize("kw, match", [
    ({"method": "rv9"}, "method"),
    ({"precision": "f16"}, "precision"),
    ({"period": -0.1}, "period"),
    ({"duration": float("nan")}, "duration"),
    ({"sensors": "perfect"}, "sensors"),
    ({"ber": 0.7}, "ber"),
    ({"ber": 1e-3, "link": "none"}, "ber"),
    ({"duration": 0.01}, "duration"),
])
def test_bad_config(kw, match) -> None:
    with pytest.raises(InvalidArgument, match=match):
        simulate(replace(SimConfig(), **kw))
