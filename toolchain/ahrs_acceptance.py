"""The simulated acceptance tests of the attitude filter (issue 15), with the
simulator's sensors: ``python -m toolchain.ahrs_acceptance [--short]``
(``invoke sim-acceptance``) runs the four scenarios at their full lengths
and prints each figure beside its target; tests/test_sim_ahrs_acceptance.py
runs the same scenarios shortened.

The system: the simulator's chain (gyros cg-l53 with noise, bias and the
host's 60 s zero-rate calibration, 12-bit conversions summed 16 per period,
h = 0.08 s), an ADIS16405 accelerometer and an HMR3000 magnetometer
(attitude_c/sim/accelmag.py presets), the filter with its default settings
(``attitude simulate --estimator ahrs``). The ADC is the vectorized 12-bit
quantizer and the link is off: the TLC2543 driver and the link deliver the
same codes (tests/test_sim_stages.py) at a hundred times the cost.

* static, 30 min: roll and pitch against the truth offset by the tilt the
  accelerometer's own errors imply (its noise-free mean reading: bias,
  scale, misalignment; unobservable at rest), the filter aligning itself;
* turntable, 5°/s about z for 360 s: calibrated parts (turn-on bias, scale
  and misalignment removed, as a turntable test is run; noise, in-run
  Markov bias and the parts' filters kept), roll/pitch and heading errors;
* a gyro bias step at rest (0.5°/s on each axis, added to the host's rates):
  the filter's bias estimate 10 s later;
* a 30 s magnetic disturbance at rest (field norm +30 %, dip +20°, nav
  frame): how far it moves roll, pitch and heading.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass
from typing import Any

import numpy as np

from attitude_c.sim import (
    AdcModel,
    MagDisturbance,
    SimConfig,
    accel_preset,
    acquire,
    mag_preset,
    make_trajectory,
    simulate,
)
from attitude_c.sim.chain import SimResult
from attitude_c.sim.trajectory import EARTH
from attitude_c.uncertainty import attitude_error, chi2_band, nees

DEG = math.pi / 180
PERIOD = 0.08  # s, the paper's period, the simulator's default
#: settling excluded from the static and turntable figures (kept at the value first chosen, not
#: re-chosen for later defaults). With the current defaults at 12.5 Hz the filter's covariance
#: is not fully steady at 10 s: static, tilt σ 0.50° at 10 s and 0.41° from 60 s on (at rest the
#: tilt time constant is acc_noise/gyr_noise_rest = 0.025/0.002 = 12.5 s); turntable, tilt σ
#: 1.05° at 10 s and 0.92° at 60 s, the bias σ still shrinking (0.23°/s at 10 s, 0.08°/s at 60 s).
#: The static run starts from the filter's own one-sample alignment
SETTLE = 10.0
#: the bias step: 0.5°/s per axis, the cg-l53's turn-on bias (1σ) — what a host calibration misses
BIAS_STEP = np.array([0.5, -0.5, 0.5]) * DEG

#: targets (issue 15): name → (limit, unit)
TARGETS: dict[str, tuple[float, str]] = {
    "static_tilt_deg": (0.05, "°"),
    "turntable_tilt_deg": (0.1, "°"),
    "turntable_heading_deg": (0.5, "°"),
    "bias_step_err_dps": (0.05, "°/s"),
    "disturbance_tilt_deg": (0.2, "°"),
    "disturbance_heading_deg": (2.0, "°"),
}


def config(trajectory: Any, duration: float, calibrated: bool, seed: int = 0, init: str = "truth",
           settings: dict[str, Any] | None = None, disturbances: tuple[MagDisturbance, ...] = ()) -> SimConfig:
    accel, mag = accel_preset("adis16405"), mag_preset("hmr3000")
    if calibrated:
        accel = accel.without(bias=True, scale=True, misalignment=True)
        mag = mag.without(bias=True, scale=True, misalignment=True)
    return SimConfig(trajectory=trajectory, duration=duration, period=PERIOD, accel=accel, mag=mag,
                     estimator="ahrs", ahrs_settings=dict(settings or {}), ahrs_init=init,  # type: ignore[arg-type]
                     adc=AdcModel(backend="ideal"), link="none", seed=seed, disturbances=disturbances)


def implied_tilt(res: SimResult) -> tuple[float, float]:
    """(pitch, roll) (rad) of the accelerometer's mean reading at rest: the tilt
    the filter must find when the part's errors cannot be told from a tilt.
    Body x right, y forward, z up; pitch about x, roll about y (z-x-y Euler):
    f = g (−sin γ cos θ, sin θ, cos γ cos θ)."""
    f = res.aux["accel"].values.mean(axis=0)
    return math.asin(f[1] / float(np.linalg.norm(f))), math.atan2(-f[0], f[2])


#: consistency (issue 32): the NEES of the attitude inside its two-sided 95 % χ²(3) band for at
#: least this fraction of the samples after SETTLE
NEES_BAND_P = 0.95
NEES_INSIDE_MIN = 0.90


def nees_inside(res: SimResult) -> float:
    """Fraction of the samples after SETTLE whose NEES (the true attitude error against the
    filter's reported covariance) lies inside the 95 % band of χ²(3)."""
    assert res.cov is not None, "the filter's covariance was not recorded"
    judged = res.t >= SETTLE
    n = nees(attitude_error(res.q_est[judged], res.q_true[judged]), res.cov[judged])
    lo, hi = chi2_band(NEES_BAND_P)
    return float(np.mean((n >= lo) & (n <= hi)))


@dataclass
class Figures:
    values: dict[str, float]
    info: dict[str, Any]


def static(duration: float = 1800.0, seed: int = 0, settings: dict[str, Any] | None = None,
           calibrated: bool = False) -> Figures:
    """``calibrated``: the parts' bias, scale and misalignment removed (the consistency runs:
    an uncalibrated accelerometer's tilt is no error the filter's model holds)."""
    res = simulate(config(make_trajectory("static"), duration, calibrated=calibrated, seed=seed, init="align",
                          settings=settings))
    pitch, roll = implied_tilt(res)
    ep, er = res.err[:, 1] - pitch, res.err[:, 2] - roll
    judged = res.t >= SETTLE
    b = np.asarray(res.aux["accel"].errors["bias"])
    g = EARTH.gravity
    return Figures({"static_tilt_deg": max(np.max(np.abs(ep[judged])), np.max(np.abs(er[judged]))) / DEG},
                   {"pitch_max_deg": np.max(np.abs(ep[judged])) / DEG, "roll_max_deg": np.max(np.abs(er[judged])) / DEG,
                    "pitch_rms_deg": float(np.sqrt(np.mean(ep[judged] ** 2))) / DEG,
                    "roll_rms_deg": float(np.sqrt(np.mean(er[judged] ** 2))) / DEG,
                    "whole_run_tilt_deg": max(np.max(np.abs(ep)), np.max(np.abs(er))) / DEG,
                    "implied_pitch_deg": pitch / DEG, "implied_roll_deg": roll / DEG,
                    "bias_over_g_pitch_deg": math.asin(b[1] / g) / DEG, "bias_over_g_roll_deg": -math.asin(b[0] / g) / DEG,
                    "raw_tilt_error_deg": float(np.max(np.abs(res.err[judged, 1:]))) / DEG,
                    "nees_inside": nees_inside(res)})


def turntable(duration: float = 360.0, seed: int = 0, settings: dict[str, Any] | None = None,
              calibrated: bool = True) -> Figures:
    traj = make_trajectory("turntable", rate=[0.0, 0.0, 5.0 * DEG])
    res = simulate(config(traj, duration, calibrated=calibrated, seed=seed, settings=settings))
    judged = res.t >= SETTLE
    tilt = float(np.max(np.abs(res.err[judged, 1:])))
    head = float(np.max(np.abs(res.err_heading[judged])))
    return Figures({"turntable_tilt_deg": tilt / DEG, "turntable_heading_deg": head / DEG},
                   {"whole_run_tilt_deg": float(np.max(np.abs(res.err[:, 1:]))) / DEG,
                    "whole_run_heading_deg": float(np.max(np.abs(res.err_heading))) / DEG,
                    "pitch_rms_deg": float(np.sqrt(np.mean(res.err[:, 1] ** 2))) / DEG,
                    "roll_rms_deg": float(np.sqrt(np.mean(res.err[:, 2] ** 2))) / DEG,
                    "heading_rms_deg": float(np.sqrt(np.mean(res.err_heading ** 2))) / DEG,
                    "bias_final_dps": (np.asarray(res.summary["estimator"]["bias_final_rad_s"]) / DEG).tolist(),
                    "nees_inside": nees_inside(res)})


def bias_step(t_step: float = 60.0, after: float = 30.0, seed: int = 0,
              settings: dict[str, Any] | None = None) -> Figures:
    """The step is added to the host's rates from ``t_step`` (the acquisition
    run once, then the estimator on the stepped rates)."""
    cfg = config(make_trajectory("static"), t_step + after, calibrated=True, seed=seed, settings=settings)
    acq = acquire(cfg)
    dec = acq.decoded
    assert dec is not None
    h = cfg.period
    t_start = cfg.trajectory.t_start + dec.sample_index * h  # start of each sample period
    pre = t_start + h <= t_step
    true = cfg.trajectory.increments(cfg.trajectory.t_start, h, acq.samples)[dec.sample_index] / h
    before = np.mean(dec.increments[pre] / h - true[pre], axis=0)  # what the rates carried before the step
    dec.increments[t_start >= t_step] += BIAS_STEP * h
    res = simulate(cfg, acquired=acq)
    assert res.bias is not None and res.bias_t is not None
    out: dict[str, float] = {}
    for dt in (2.0, 5.0, 10.0, 20.0):
        if dt <= after:
            i = int(np.searchsorted(res.bias_t, t_step + dt - 1e-9))
            out[f"err_after_{dt:g}s_dps"] = float(np.max(np.abs(res.bias[i] - before - BIAS_STEP))) / DEG
    moved = res.t >= t_step
    return Figures({"bias_step_err_dps": out["err_after_10s_dps"]},
                   {**out, "tilt_max_deg": float(np.max(np.abs(res.err[moved, 1:]))) / DEG,
                    "heading_max_deg": float(np.max(np.abs(res.err_heading[moved]))) / DEG,
                    "nees_inside": nees_inside(res)})


def disturbance_field(norm: float = 0.3, dip: float = 20.0 * DEG) -> tuple[float, float, float]:
    """The nav-frame field (µT) that, added to the geomagnetic field, makes its
    norm (1 + norm) times and its dip ``dip`` steeper, the declination unchanged."""
    def nav(f: float, i: float) -> np.ndarray:
        d = EARTH.declination
        return np.array([f * math.cos(i) * math.sin(d), f * math.cos(i) * math.cos(d), -f * math.sin(i)])

    v = nav(EARTH.field_ut * (1 + norm), EARTH.inclination + dip) - nav(EARTH.field_ut, EARTH.inclination)
    return float(v[0]), float(v[1]), float(v[2])


def disturbance(start: float = 60.0, length: float = 30.0, after: float = 60.0, seed: int = 0,
                settings: dict[str, Any] | None = None) -> Figures:
    d = MagDisturbance(start, start + length, disturbance_field(), "nav")
    res = simulate(config(make_trajectory("static"), start + length + after, calibrated=True, seed=seed,
                          settings=settings, disturbances=(d,)))
    before = (res.t >= start - 10.0) & (res.t < start)
    moved = res.t >= start
    e = np.column_stack([res.err_heading, res.err[:, 1], res.err[:, 2]])
    move = np.max(np.abs(e[moved] - e[before].mean(axis=0)), axis=0)
    return Figures({"disturbance_tilt_deg": float(max(move[1], move[2])) / DEG,
                    "disturbance_heading_deg": float(move[0]) / DEG},
                   {"pitch_move_deg": float(move[1]) / DEG, "roll_move_deg": float(move[2]) / DEG,
                    "mag_rejected_fraction": res.summary["estimator"]["mag_rejected_fraction"],
                    "nees_inside": nees_inside(res)})


#: full-length (the issue's) and shortened (the default test suite's) runs
FULL: dict[str, dict[str, float]] = {"static": {"duration": 1800.0}, "turntable": {"duration": 360.0},
                                     "bias_step": {"t_step": 60.0, "after": 30.0},
                                     "disturbance": {"start": 60.0, "length": 30.0, "after": 60.0}}
SHORT: dict[str, dict[str, float]] = {"static": {"duration": 240.0}, "turntable": {"duration": 90.0},
                                      "bias_step": {"t_step": 30.0, "after": 12.0},
                                      "disturbance": {"start": 30.0, "length": 30.0, "after": 30.0}}
SCENARIOS = {"static": static, "turntable": turntable, "bias_step": bias_step, "disturbance": disturbance}


def run(lengths: dict[str, dict[str, float]], seed: int = 0, settings: dict[str, Any] | None = None,
        only: tuple[str, ...] = ()) -> dict[str, Figures]:
    return {name: fn(**lengths[name], seed=seed, settings=settings)  # type: ignore[operator]
            for name, fn in SCENARIOS.items() if not only or name in only}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m toolchain.ahrs_acceptance", description=__doc__.split("\n\n")[0])
    p.add_argument("--short", action="store_true", help="the shortened runs of the default test suite")
    p.add_argument("--seed", type=int, default=0, help="simulator seed")
    p.add_argument("--only", default="", help="comma-separated scenarios (static,turntable,bias_step,disturbance)")
    p.add_argument("--setting", action="append", default=[], metavar="NAME=VALUE",
                   help="a filter setting (attitude_c.ahrs keywords; repeatable)")
    p.add_argument("--json", metavar="FILE", default=None, help="also write the figures as JSON")
    a = p.parse_args(argv)
    settings: dict[str, Any] = {}
    for s in a.setting:
        k, _, v = s.partition("=")
        settings[k] = v if k == "method" else float(v)
    only = tuple(x for x in a.only.split(",") if x)
    bad = [x for x in only if x not in SCENARIOS]
    if bad:
        print(f"ahrs_acceptance: error: unknown scenario {bad[0]!r} (known: {', '.join(SCENARIOS)})", file=sys.stderr)
        return 2
    figs = run(SHORT if a.short else FULL, a.seed, settings, only)
    ok = True
    print(f"{'figure':<26}{'measured':>12}{'target':>10}")
    for f in figs.values():
        for k, v in f.values.items():
            lim, unit = TARGETS[k]
            ok &= v <= lim
            print(f"{k:<26}{v:>12.4f}{lim:>9g}{unit}  {'ok' if v <= lim else 'MISSED'}")
        print("    " + ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in f.info.items()))
    if a.json:
        from pathlib import Path

        out = Path(a.json)
        tmp = out.with_suffix(out.suffix + ".tmp")
        tmp.write_text(json.dumps({n: {"figures": f.values, "info": f.info} for n, f in figs.items()}, indent=2,
                                  default=float) + "\n")
        tmp.replace(out)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
