"""Filter settings from the simulator's own sensors by the Allan deviation
(docs/noise.md): a rest recording of the acceptance tests' system
(toolchain/ahrs_acceptance.py: cg-l53 gyros through the 12-bit chain, the
ADIS16405 accelerometer), its Allan terms, the settings
:func:`attitude_c.noise.filter_settings` derives from them, and the
acceptance scenarios run with those settings beside the defaults.

``python -m toolchain.allan_settings [--short] [--hours H]`` (``invoke allan-settings``)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

import numpy as np

from attitude_c.noise import AllanResult, allan, filter_settings, horizontal_field
from attitude_c.sim import acquire, make_trajectory

from .ahrs_acceptance import (
    FULL,
    NEES_INSIDE_MIN,
    SHORT,
    TARGETS,
    config,
    disturbance,
    run,
    static,
    turntable,
)


def rest_recording(duration: float, seed: int = 0, calibrated: bool = False
                   ) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """The host's gyro rates (rad/s), the accelerometer's readings (m/s²) of the
    acceptance system at rest for ``duration`` s, their rate (Hz), and the magnetometer's (µT)."""
    cfg = config(make_trajectory("static"), duration, calibrated=calibrated, seed=seed)
    acq = acquire(cfg)
    dec = acq.decoded
    assert dec is not None
    return dec.increments / cfg.period, np.asarray(dec.aux["accel"]), 1.0 / cfg.period, np.asarray(dec.aux["mag"])


def calibrated_settings(duration: float = 600.0, seed: int = 11
                        ) -> tuple[dict[str, float], dict[str, AllanResult]]:
    """The settings for the calibrated parts (``filter_settings(..., calibrated=True)``) from a
    rest recording of ``duration`` s of the calibrated system, seed ``seed`` (not a scenario's),
    and the Allan results they come from."""
    gyr, acc, rate, mag = rest_recording(duration, seed, calibrated=True)
    r = {"gyro (rad/s)": allan(gyr, rate), "accel (m/s²)": allan(acc, rate), "mag (µT)": allan(mag, rate)}
    return filter_settings(r["gyro (rad/s)"], r["accel (m/s²)"], calibrated=True, mag=r["mag (µT)"],
                           mag_h=horizontal_field(acc, mag)), r


def print_terms(results: dict[str, AllanResult]) -> None:
    for name, r in results.items():
        for j, t in enumerate(r.terms):
            print(f"{name} {'xyz'[j]}: N {t.n:.4g} ± {t.n_sigma:.2g}, B {t.b:.4g} ± {t.b_sigma:.2g}, "
                  f"K {t.k:.4g} ± {t.k_sigma:.2g}")


def consistency(lengths: dict[str, dict[str, float]], seeds: tuple[int, ...] = (0, 1, 2)) -> int:
    """The NEES in-band fractions of the consistency motions (tests/test_sim_ahrs_consistency.py)
    with the settings derived for the calibrated parts; 0 when every one reaches NEES_INSIDE_MIN."""
    settings, res = calibrated_settings()
    print_terms(res)
    print("settings (calibrated): " + ", ".join(f"{k} {v:.4g}" for k, v in settings.items()))
    ok = True
    for seed in seeds:
        f = [static(**lengths["static"], seed=seed, settings=settings, calibrated=True).info["nees_inside"],
             turntable(**lengths["turntable"], seed=seed, settings=settings).info["nees_inside"],
             disturbance(**lengths["disturbance"], seed=seed, settings=settings).info["nees_inside"]]
        ok &= min(f) >= NEES_INSIDE_MIN
        print(f"seed {seed}: NEES inside its 95 % band: static {f[0]:.1%}, turntable {f[1]:.1%}, "
              f"disturbance {f[2]:.1%}", flush=True)
    return 0 if ok else 1


def derived(duration: float = 7200.0, seed: int = 1) -> tuple[dict[str, float], AllanResult, AllanResult]:
    """The settings from a rest recording of ``duration`` s (another seed than the scenarios')."""
    gyr, acc, rate, _ = rest_recording(duration, seed)
    g, a = allan(gyr, rate), allan(acc, rate)
    return filter_settings(g, a), g, a


def compare(settings: dict[str, float], lengths: dict[str, dict[str, float]], seed: int = 0) -> dict[str, Any]:
    """Each acceptance figure with the defaults and with ``settings``: name → (default, derived, target)."""
    base, mine = run(lengths, seed), run(lengths, seed, settings)
    return {k: (base[n].values[k], mine[n].values[k], TARGETS[k][0]) for n in base for k in base[n].values}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m toolchain.allan_settings", description=__doc__.split("\n\n")[0])
    p.add_argument("--short", action="store_true", help="the acceptance scenarios' shortened runs")
    p.add_argument("--hours", type=float, default=2.0, help="length of the rest recording (h)")
    p.add_argument("--nees", action="store_true",
                   help="the consistency motions (seeds 0-2) with the settings for the calibrated parts "
                        "(10 min at rest, seed 11)")
    p.add_argument("--seeds", default="0,1,2", help="--nees: the motions' seeds (comma-separated; the test's 0,1,2)")
    a = p.parse_args(argv)
    if a.nees:
        return consistency(SHORT if a.short else FULL, tuple(int(x) for x in a.seeds.split(",") if x))
    settings, g, acc = derived(a.hours * 3600.0)
    print_terms({"gyro (rad/s)": g, "accel (m/s²)": acc})
    print("settings: " + ", ".join(f"{k} {v:.4g}" for k, v in settings.items()))
    rows = compare(settings, SHORT if a.short else FULL)
    print(f"{'figure':<26}{'default':>10}{'derived':>10}{'target':>9}")
    ok = True
    for k, (d, m, lim) in rows.items():
        ok &= m <= lim
        print(f"{k:<26}{d:>10.4f}{m:>10.4f}{lim:>9g}  {'ok' if m <= lim else 'MISSED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
