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

from attitude_c.noise import AllanResult, allan, filter_settings
from attitude_c.sim import acquire, make_trajectory

from .ahrs_acceptance import FULL, SHORT, TARGETS, config, run


def rest_recording(duration: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray, float]:
    """The host's gyro rates (rad/s) and the accelerometer's readings (m/s²) of the
    acceptance system at rest for ``duration`` s, and their rate (Hz)."""
    cfg = config(make_trajectory("static"), duration, calibrated=False, seed=seed)
    acq = acquire(cfg)
    dec = acq.decoded
    assert dec is not None
    return dec.increments / cfg.period, np.asarray(dec.aux["accel"]), 1.0 / cfg.period


def derived(duration: float = 7200.0, seed: int = 1) -> tuple[dict[str, float], AllanResult, AllanResult]:
    """The settings from a rest recording of ``duration`` s (another seed than the scenarios')."""
    gyr, acc, rate = rest_recording(duration, seed)
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
    a = p.parse_args(argv)
    settings, g, acc = derived(a.hours * 3600.0)
    for name, r in (("gyro (rad/s)", g), ("accel (m/s²)", acc)):
        for j, t in enumerate(r.terms):
            print(f"{name} {'xyz'[j]}: N {t.n:.4g} ± {t.n_sigma:.2g}, B {t.b:.4g} ± {t.b_sigma:.2g}, "
                  f"K {t.k:.4g} ± {t.k_sigma:.2g}")
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
