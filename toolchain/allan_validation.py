"""The noise identification's validation on the simulator's sensor models
(docs/noise.md): parts with known white noise N, bias instability B and bias
random walk K (attitude_c/sim/sensors.py, accelmag.py), their closed-form
terms, a rest recording of each, and a seed sweep of the fitted terms
against the truth: ``python -m toolchain.allan_validation [--seeds S]``
(``invoke allan-sweep``) prints, per sensor and term, the mean and spread
of the relative error, the largest, and the spread over the fit's reported
1σ (≈ 1 when the reported uncertainty is honest)."""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace

import numpy as np

from attitude_c.noise import PLATEAU, Terms, allan
from attitude_c.sim import make_trajectory
from attitude_c.sim.accelmag import VectorSensor, accel_preset
from attitude_c.sim.sensors import DEG, Gyro, gyro_preset

DT = 0.01  # s: 100 Hz
SAMPLES = 720_000  # two hours at 100 Hz (the validation recording)
#: where the white line meets the flicker floor, and the floor the random walk (s)
T_WHITE, T_WALK = 0.3, 2.0


def white_n(sigma_x: float, a: float) -> float:
    """N (units·√s) of the simulator's sampled white noise: an AR(1) sequence of σ_x and
    neighbour correlation a has the long-term density σ_x²·dt·(1 + a)/(1 − a)."""
    return math.sqrt(sigma_x ** 2 * DT * (1 + a) / (1 - a))


def drift_terms(n: float, t_white: float = T_WHITE, t_walk: float = T_WALK) -> tuple[float, float]:
    """B and K of a part whose white line N/√τ meets the flicker floor 0.664·B at
    ``t_white`` and whose floor meets the random walk K·√(τ/3) at ``t_walk``."""
    floor = n / math.sqrt(t_white)
    return floor / PLATEAU, floor * math.sqrt(3 / t_walk)


def gyro_rest(seed: int, samples: int = SAMPLES, **where: float) -> tuple[np.ndarray, tuple[float, float, float]]:
    """The ADXRS150 model with a flicker bias and a rate random walk at rest: rates (rad/s)
    and the true (N, B, K)."""
    g0 = gyro_preset("adxrs150")
    n = white_n(g0.noise_density * DEG * math.sqrt(math.pi / 2 * g0.bandwidth_hz), math.exp(-DT / g0.tau))
    b, k = drift_terms(n, **where)
    g = Gyro(replace(g0, bias_instability_dps=b / DEG, rate_random_walk=k / DEG), np.zeros(3))
    v = g.volts(make_trajectory("static"), np.arange(samples) * DT, DT, np.random.default_rng(seed), static=True)
    return (v - g0.null_v) / g0.scale_v_per_dps * DEG, (n, b, k)


def accel_rest(seed: int, samples: int = SAMPLES, **where: float) -> tuple[np.ndarray, tuple[float, float, float]]:
    """The ADIS16405 accelerometer model (its Markov bias off: not one of the three terms; not
    quantized) with a flicker bias and a random walk at rest: readings (m/s²) and (N, B, K)."""
    m0 = replace(accel_preset("adis16405"), markov_sigma=0.0, lsb=None)
    n = white_n(m0.noise_sigma_filtered, math.exp(-DT * 2 * math.pi * float(m0.bandwidth_hz)))
    b, k = drift_terms(n, **where)
    s = VectorSensor(replace(m0, bias_instability=b, random_walk=k))
    y = s.measure(make_trajectory("static"), np.arange(samples) * DT, DT, np.random.default_rng(seed), static=True)
    return y, (n, b, k)


def errors(terms: tuple[Terms, ...], truth: tuple[float, float, float]) -> np.ndarray:
    """Per axis: relative errors of N, B, K and their reported 1σ relative to the truth, (axes, 6)."""
    n, b, k = truth
    return np.array([[t.n / n - 1, t.b / b - 1, t.k / k - 1, t.n_sigma / n, t.b_sigma / b, t.k_sigma / k]
                     for t in terms])


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m toolchain.allan_validation", description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, default=6, help="recordings per sensor (3 axes each)")
    p.add_argument("--t-white", type=float, default=T_WHITE, help="τ where the white line meets the floor (s)")
    p.add_argument("--t-walk", type=float, default=T_WALK, help="τ where the floor meets the random walk (s)")
    p.add_argument("--plot", metavar="PNG", default=None,
                   help="also draw the first seed's deviations and fits (docs/img/allan-validation.png)")
    a = p.parse_args(argv)
    if a.plot:
        from attitude_c._io import write_with
        from attitude_c.noise import plot

        res = {"gyro": (allan(gyro_rest(100)[0], 1 / DT), "rad/s"), "accel": (allan(accel_rest(100)[0], 1 / DT), "m/s²")}
        write_with(a.plot, lambda tmp: plot(res, tmp, "simulated ADXRS150 gyro and ADIS16405 accelerometer with "
                                                      "known N, B, K: 2 h at rest, 100 Hz"))
    if a.seeds < 1:
        return 0
    print(f"2 h at 100 Hz, {a.seeds} seeds x 3 axes; floor from {a.t_white:g} s to {a.t_walk:g} s")
    print(f"{'sensor':<7}{'term':<5}{'mean err':>10}{'spread':>9}{'max |err|':>10}{'spread/σ':>10}")
    for name, fn in (("gyro", gyro_rest), ("accel", accel_rest)):
        e = np.concatenate([errors(allan(x, 1 / DT).terms, truth) for x, truth in
                            (fn(s, t_white=a.t_white, t_walk=a.t_walk) for s in range(100, 100 + a.seeds))])
        for i, term in enumerate("NBK"):
            sd = float(e[:, i].std())
            print(f"{name:<7}{term:<5}{e[:, i].mean():>+10.2%}{sd:>9.2%}{np.abs(e[:, i]).max():>10.2%}"
                  f"{sd / e[:, 3 + i].mean():>10.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
