"""``attitude demo``: the integrator methods on motions with a known answer.

Classical coning (exact attitude and exact increments in closed form) and
a constant-rate rotation: prints each method's final attitude error and
drift next to the theoretical coning drift of docs/integrator.md.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

import numpy as np

FRAME = {"rv1": 1, "rv2": 2, "rv3": 3, "rv3-coning": 3, "rv3-reuse": 1}


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "demo",
        help="integrator methods under coning and constant rate (errors vs theory)",
        description=__doc__,
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--beta", type=float, default=0.01, help="cone half-angle (rad)")
    p.add_argument("--freq", type=float, default=10.0, help="coning frequency (Hz)")
    p.add_argument("--period", type=float, default=0.004, help="increment interval T (s)")
    p.add_argument("--seconds", type=float, default=12.0, help="duration (s)")
    p.add_argument("--precision", choices=("f64", "f32"), default="f64")
    p.set_defaults(func=main)


def _theory(method: str, beta: float, omega: float, T: float) -> float:
    from .. import reference as ref

    lam = omega * T
    k12, k13, k23 = (float(k) for k in ref.COEFFICIENTS[method])
    pairs = {"rv1": [], "rv2": [(k12, 1)]}.get(method, [(k12, 1), (k13, 2), (k23, 1)])
    s2 = np.sin(beta) ** 2
    corr = sum(k * 2 * s2 * (1 - np.cos(lam)) * np.sin(d * lam) for k, d in pairs)
    h = FRAME[method] * T
    return float((corr - 0.5 * s2 * (omega * h - np.sin(omega * h))) / h)


def main(args: argparse.Namespace) -> int:
    from .. import core
    from .. import reference as ref
    from ..errors import AttitudeError, InvalidArgument

    try:
        if not (args.beta > 0 and args.freq > 0 and args.period > 0 and args.seconds > 0):
            raise InvalidArgument("--beta, --freq, --period and --seconds must be > 0")
        omega, T = 2 * np.pi * args.freq, args.period
        n = round(args.seconds / T)
        if n < 3:
            raise InvalidArgument("--seconds must cover at least 3 periods")
        t = np.arange(n + 1) * T
        b = args.beta
        d = np.stack([np.full(n, -2 * omega * np.sin(b / 2) ** 2 * T),
                      np.sin(b) * np.diff(np.cos(omega * t)),
                      np.sin(b) * np.diff(np.sin(omega * t))], axis=-1)

        def truth(tt: np.ndarray) -> np.ndarray:
            return np.stack([np.full_like(tt, np.cos(b / 2)), 0 * tt, np.sin(b / 2) * np.cos(omega * tt),
                             np.sin(b / 2) * np.sin(omega * tt)], -1)

        print(f"classical coning: beta = {b} rad, {args.freq} Hz, T = {T * 1e3:g} ms "
              f"(lambda = {omega * T:.3f} rad), {args.seconds:g} s, precision {args.precision}")
        print(f"{'method':<11} {'updates':>8} {'final error (rad)':>18} {'drift (rad/s)':>14} "
              f"{'theory (rad/s)':>14}")
        for m in core.INCREMENT_METHODS:
            q = core.integrate(d, m, q0=truth(t[:1])[0], precision=args.precision)
            tt = t[FRAME[m]::FRAME[m]][: len(q)]
            e = ref.quat_to_rotvec(ref.quat_multiply(q, ref.quat_conj(truth(tt))))
            slope = np.polyfit(tt, e[:, 0], 1)[0] / np.cos(b)
            print(f"{m:<11} {len(q):>8} {np.linalg.norm(e[-1]):>18.3e} {slope:>14.3e} "
                  f"{_theory(m, b, omega, T):>14.3e}")
        w = np.array([0.3, -0.5, 1.0])
        dc = np.tile(w * T, (n, 1))
        print(f"\nconstant rate {w.tolist()} rad/s for {args.seconds:g} s (every method exact):")
        for m in core.INCREMENT_METHODS:
            q = core.integrate(dc, m, precision=args.precision)
            exact = ref.rotvec_to_quat(w * T * FRAME[m] * len(q))
            err = np.linalg.norm(ref.quat_to_rotvec(ref.quat_multiply(q[-1], ref.quat_conj(exact))))
            print(f"{m:<11} final error {err:.3e} rad")
    except AttitudeError as exc:
        print(f"attitude demo: {exc}", file=sys.stderr)
        return 2
    return 0
