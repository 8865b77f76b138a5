"""The aided board in the simulator (attitude_c/sim/aided.py, ``--board aided9``): the chain
front ends → TLC2543 → the firmware's groups → link v2 → tracker → att_sensor → att_ahrs.

Bounds come from the front ends' figures (frontend.py presets), never from the chain's output:
with ``sensors="quantized"`` the parts are perfect and each reading is off by at most half a
code per axis (the per-period sums of noise-free codes do not dither), so the attitude the
readings imply is off by at most

* tilt: √2 · ½ code / (codes per g)                    (two horizontal axes, small angles)
* heading: √2 · ½ code / (codes per µT · H) + tilt · tan(I)  (H horizontal field, I inclination:
  a tilt error turns the vertical field component into the horizontal plane)

and a filter that starts at the true attitude moves only toward that attitude.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from attitude_c.cli import main
from attitude_c.errors import InvalidArgument
from attitude_c.sim import SimConfig, simulate
from attitude_c.sim.aided import AidedPlan, nominal_configs
from attitude_c.sim.frontend import ACCEL_FRONTENDS, MAG_FRONTENDS
from attitude_c.sim.trajectory import EARTH, StaticTrajectory, TurntableTrajectory
from attitude_c.view.simsource import SimulatorSource, parse_simulate_options

PLAN = AidedPlan()
ACC = ACCEL_FRONTENDS[PLAN.accel]
MAG = MAG_FRONTENDS[PLAN.mag]
TILT_BOUND = math.sqrt(2) * 0.5 / ACC.codes_per_g
H_UT = EARTH.field_ut * math.cos(EARTH.inclination)
HEADING_BOUND = math.sqrt(2) * 0.5 / (MAG.codes_per_ut * H_UT) + TILT_BOUND * math.tan(EARTH.inclination)


def _run(traj: object = None, **kw: object) -> object:
    base = {"trajectory": traj or StaticTrajectory(), "duration": 4.0, "period": PLAN.period_s, "calibration_s": 1.0,
                "sensors": "quantized", "board_kind": "aided9", "estimator": "ahrs"}
    base.update(kw)
    return simulate(SimConfig(**base))  # type: ignore[arg-type]


def test_plan_is_the_firmware_default_build() -> None:
    """The package repeats toolchain.firmware.AIDED's figures (it imports nothing outside itself)."""
    from toolchain import firmware

    fw = firmware.AIDED
    tick = 1 / 3600  # the firmware's timer tick (BOOT's period unit)
    assert (PLAN.acc_every, PLAN.mag_every, PLAN.baud, PLAN.mag_sr) == (fw.acc_every, fw.mag_every, fw.baud,
                                                                         fw.mag_sr)
    assert (PLAN.ring, PLAN.frame_records) == (fw.v2_ring, fw.v2_samples)
    assert PLAN.period_s == pytest.approx(fw.period_ticks * tick, rel=1e-12)
    assert PLAN.rto_s == pytest.approx(fw.v2_rto * tick, rel=1e-12)


def test_static_every_record_once_and_attitude_within_quantization() -> None:
    r = _run()
    lk = r.summary["link"]
    n = r.summary["samples"]
    assert lk["link"] == "v2" and lk["overrun_samples"] == 0 and lk["lost"] == 0 and lk["held"] == []
    assert lk["records_sent"] == lk["records_received"] == {"gyr": n, "acc": n, "mag": n}
    # the link delivered exactly what was pushed, in order: BOOT, OVERSAMPLE, CHANNELS and 3 per sample
    assert lk["records_pushed"] == lk["records_delivered"] == lk["records_in_order"] == 3 + 3 * n
    assert r.summary["estimator"]["axes"] == 9
    # readings: within half a code of the exact period mean (+1e-9: float rounding of the conversion)
    for name, part in (("accel", ACC), ("mag", MAG)):
        assert max(r.summary["sensors"][name]["max_abs_error"]) <= 0.5 * part.units_per_code + 1e-9
    tilt = np.abs(r.err[:, 1:]).max()
    heading = np.abs(r.err[:, 0]).max()
    assert tilt <= TILT_BOUND and heading <= HEADING_BOUND, (tilt, heading)


def test_turntable_heading_follows_within_quantization_and_lag() -> None:
    traj = TurntableTrajectory()
    r = _run(traj)
    rate = math.radians(traj.params()["rate_dps"])
    # the front ends' RC filters delay the field by tau (the board does not compensate it): ω·τ of heading
    lag = rate * MAG.tau
    assert np.abs(r.err[:, 0]).max() <= HEADING_BOUND + lag
    assert np.abs(r.err[:, 1:]).max() <= TILT_BOUND
    assert r.summary["link"]["lost"] == 0


def test_decimated_plan_feeds_the_filter_null_between_records() -> None:
    plan = AidedPlan(acc_every=2, mag_every=4)
    r = _run(aided=plan, duration=1.0)
    n = r.summary["samples"]
    lk = r.summary["link"]
    assert lk["records_received"] == {"gyr": n, "acc": len(range(0, n, 2)), "mag": len(range(0, n, 4))}
    k = np.arange(n)
    assert np.array_equal(~np.isnan(r.aux["accel"].values).any(axis=1), k % 2 == 0)
    assert np.array_equal(~np.isnan(r.aux["mag"].values).any(axis=1), k % 4 == 0)
    assert np.abs(r.err[:, 1:]).max() <= TILT_BOUND and np.abs(r.err[:, 0]).max() <= HEADING_BOUND


def test_losses_on_a_noisy_line_are_reported_and_held() -> None:
    # BER 6e-3 at 115200 baud: frames of 16 records mostly fail their CRC, the 16-record ring
    # fills and whole samples are lost (the seed gives a run with some loss, not all)
    r = _run(ber=6e-3, seed=1)
    lk = r.summary["link"]
    n = r.summary["samples"]
    assert 0 < lk["overrun_samples"] < n
    assert lk["lost"] == lk["overrun_samples"] and lk["delivered"] + lk["lost"] == n
    assert lk["records_delivered"] == lk["records_in_order"] == lk["records_pushed"]  # link v2: nothing twice
    got = lk["records_received"]
    assert got["gyr"] == got["acc"] == got["mag"] == lk["delivered"]  # groups whole or not at all
    assert "overrun" in lk["reports"] and len(lk["held"]) <= lk["lost"]
    assert np.abs(r.err[:, 1:]).max() <= TILT_BOUND  # held gyros, no aiding: a still body stays put


def test_gyro_only_default_unchanged() -> None:
    """Numbers of main before the aided board (a fixed seed): the default chain draws the same."""
    r = simulate(SimConfig(duration=4.0, calibration_s=2.0, seed=7, ber=1e-3))
    assert r.summary["errors_rad"]["attitude_angle"]["rms"] == 0.00017103488820795757
    assert r.q_est[-1].tolist() == [0.9487743004366908, 0.09497103155623184, 0.17812967827735096,
                                    -0.24305893876346252]
    assert "board_kind" not in r.summary["parameters"] and "aided" not in r.summary["parameters"]


def test_nominal_config_is_the_front_ends_figures() -> None:
    c = nominal_configs(PLAN)
    assert c["accel"].scale[0] == ACC.units_per_code and c["mag"].scale[0] == MAG.units_per_code
    assert c["accel"].zero.tolist() == [2048.0] * 3  # Vs/2 on a REF+ = Vs converter


@pytest.mark.parametrize("kw, message", [
    ({"estimator": "integrator"}, "estimator must be 'ahrs'"),
    ({"sensors": "ideal"}, "'quantized' or 'full'"),
    ({"aided": AidedPlan(acc_every=0)}, "acc_every must be an integer 1..255"),
    ({"aided": AidedPlan(host_config="perfect")}, "host_config must be"),  # type: ignore[arg-type]
])
def test_config_refusals(kw: dict[str, object], message: str) -> None:
    base: dict[str, object] = {"trajectory": StaticTrajectory(), "duration": 1.0, "board_kind": "aided9", "estimator": "ahrs"}
    base.update(kw)
    with pytest.raises(InvalidArgument, match=message):
        SimConfig(**base).validate()  # type: ignore[arg-type]


def test_view_plays_the_filter_bias() -> None:
    cfg = parse_simulate_options(["--board", "aided9", "--trajectory", "static", "--duration", "1",
                                  "--calibration", "1", "--sensors", "quantized"])
    assert cfg.board_kind == "aided9" and cfg.estimator == "ahrs" and cfg.period == PLAN.period_s
    src = SimulatorSource(cfg)
    res = simulate(cfg)
    items = list(src.items(res))
    counters = [p for _, what, p in items if what == "counters"]
    assert len(counters) == len(res.bias_t) and {"bias_x_dps", "bias_y_dps", "bias_z_dps"} <= set(counters[-1])
    assert counters[-1]["bias_z_dps"] == round(float(np.degrees(res.bias[-1][2])), 4)
    assert sum(1 for _, what, _ in items if what == "sample") == len(res.t)


@pytest.mark.system
def test_cli_aided_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "run"
    rc = main(["simulate", "--board", "aided9", "--trajectory", "static", "--duration", "2", "--calibration", "1",
               "--acc-every", "2", "--host-config", "calibrated", "--no-progress", "--no-plots", "--out", str(out)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "aided board (link v2 at 115200 baud" in text and "acc 50/50" in text
    s = json.loads((out / "summary.json").read_text())
    assert s["parameters"]["aided"]["acc_every"] == 2 and s["parameters"]["period_s"] == PLAN.period_s
    assert (out / "sensors.csv").stat().st_size > 0


@pytest.mark.parametrize("argv, message", [
    (["--acc-every", "2"], "need --board aided9"),
    (["--board", "aided9", "--accel", "adis16405"], "drop --accel and --mag"),
    (["--board", "aided9", "--precision", "fixed"], "not fixed"),
])
def test_cli_refusals(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", *argv, "--no-progress"]) == 2
    assert message in capsys.readouterr().err


def test_update_sparse_is_update_when_every_sample_has_aiding() -> None:
    """Ahrs.update_sparse (one att_ahrs_update per sample) against the batch call on the same
    samples: the same C update in the same order, so equal to the last bit."""
    from attitude_c.ahrs_filter import Ahrs

    rng = np.random.default_rng(5)
    gyr = rng.normal(0, 0.1, (50, 3))
    acc = np.array([0.0, 0.0, 9.81]) + rng.normal(0, 0.05, (50, 3))
    mag = np.array([20.0, 0.0, -40.0]) + rng.normal(0, 0.2, (50, 3))
    a, b = Ahrs(q0=[1, 0, 0, 0]), Ahrs(q0=[1, 0, 0, 0])
    np.testing.assert_array_equal(a.update_sparse(gyr, acc, mag, dt=0.02), b.update(gyr, acc, mag, dt=0.02))
    with pytest.raises(InvalidArgument, match="same number of samples"):
        a.update_sparse(gyr, acc[:3], dt=0.02)
