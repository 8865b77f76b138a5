"""``attitude demo``: the integrator methods on motions with a known answer.

Classical coning (exact attitude, increments and rates in closed form,
:mod:`attitude_c.reference`) and a constant-rate rotation: prints each
method's final attitude error and measured drift next to the theoretical
coning drift of docs/integrator.md (all orders in ΩT) and its leading term.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

import numpy as np

from . import options

if TYPE_CHECKING:
    from .. import core


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "demo",
        help="integrator methods under coning and constant rate (errors vs theory)",
        description="Every integrator method on classical coning (exact attitude, increments and rates in "
        "closed form, attitude_c.reference) and on a constant-rate rotation: each method's final attitude "
        "error and measured drift next to the theoretical coning drift of docs/integrator.md (all orders "
        "in ΩT) and its leading term.",
        epilog="exit statuses: 0 done; 2 bad option. See docs/integrator.md.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--beta", type=options.real("--beta", gt=0, lt=1.5707963267948966), default=0.01, help="cone half-angle (rad)")
    p.add_argument("--freq", type=options.positive("--freq"), default=10.0, help="coning frequency (Hz)")
    p.add_argument("--period", type=options.positive("--period"), default=0.004,
                   help="sample interval T (s): increments, or rk4's rate rows")
    p.add_argument("--seconds", type=options.real("--seconds", gt=0, le=86400), default=12.0, help="duration (s)")
    p.add_argument("--precision", choices=("f64", "f32"), default="f64", help="the C library's arithmetic")
    p.set_defaults(func=main)


def coning_drifts(beta: float, omega: float, T: float, seconds: float,
                  precision: core.Precision = "f64") -> dict[str, tuple[int, float, float]]:
    """Every method of :data:`attitude_c.METHODS` under classical coning
    (half-angle ``beta`` rad, rate ``omega`` rad/s), sampled every ``T`` s
    for ``seconds``: ``{method: (updates, final error angle (rad), drift
    (rad/s))}``. The drift is the least-squares slope of the cone-axis
    component of the navigation-frame error, divided by cos β (the cone
    axis seen from the navigation frame); increment methods get the exact
    increments, rk4 the exact rates at every T (steps of 2T)."""
    from .. import core, names
    from .. import reference as ref

    n = round(seconds / T)
    d, t = ref.coning_increments(beta, omega, T, n)
    q0 = ref.coning_attitude(beta, omega, 0.0)
    out: dict[str, tuple[int, float, float]] = {}
    for m in core.METHODS:
        if m == "rk4":
            q = core.integrate_rates(ref.coning_rates(beta, omega, t), T, "rk4", q0=q0,
                                     precision=precision)
        else:
            q = core.integrate(d, m, q0=q0, precision=precision)
        per = names.samples_per_update(m)
        tt = t[per::per][: len(q)]
        e = ref.quat_to_rotvec(ref.quat_multiply(q, ref.quat_conj(ref.coning_attitude(beta, omega, tt))))
        slope = float(np.polyfit(tt, e[:, 0], 1)[0] / np.cos(beta))
        out[m] = (len(q), float(np.linalg.norm(e[-1])), slope)
    return out


def main(args: argparse.Namespace) -> int:
    from .. import core, names
    from .. import reference as ref
    from ..errors import AttitudeError, InvalidArgument

    try:
        if not (args.beta > 0 and args.freq > 0 and args.period > 0 and args.seconds > 0):
            raise InvalidArgument("--beta, --freq, --period and --seconds must be > 0")
        omega, T = 2 * np.pi * args.freq, args.period
        n = round(args.seconds / T)
        if n < 3:
            raise InvalidArgument("--seconds must cover at least 3 periods")
        if n > 10_000_000:  # 7 arrays of n × 3 float64: ~1.7 GB beyond this
            raise InvalidArgument(f"--seconds / --period = {n} samples: at most 10,000,000 (a demo, not a run)")
        b = args.beta
        print(f"classical coning: beta = {b} rad, {args.freq} Hz, T = {T * 1e3:g} ms "
              f"(lambda = {omega * T:.3f} rad), {args.seconds:g} s, precision {args.precision}")
        print(f"{'method':<15} {'updates':>8} {'final error (rad)':>18} {'drift (rad/s)':>14} "
              f"{'theory (rad/s)':>14} {'leading term':>13}  (lambda = OmegaT, per Omega sin^2 beta)")
        for m, (nq, final, slope) in coning_drifts(b, omega, T, args.seconds, args.precision).items():
            k, p = ref.coning_leading_term(m)
            print(f"{m:<15} {nq:>8} {final:>18.3e} {slope:>14.3e} {ref.coning_drift(m, b, omega, T):>14.3e} "
                  f"{ref.coning_drift_leading(m, b, omega, T):>13.3e}  {k} lambda^{p}")
        w = np.array([0.3, -0.5, 1.0])
        dc = np.tile(w * T, (n, 1))
        print(f"\nconstant rate {w.tolist()} rad/s for {args.seconds:g} s (every increment method exact):")
        for m in core.INCREMENT_METHODS:
            q = core.integrate(dc, m, precision=args.precision)
            exact = ref.rotvec_to_quat(w * T * names.samples_per_update(m) * len(q))
            err = np.linalg.norm(ref.quat_to_rotvec(ref.quat_multiply(q[-1], ref.quat_conj(exact))))
            print(f"{m:<15} final error {err:.3e} rad")
    except AttitudeError as exc:
        print(f"attitude demo: {exc}", file=sys.stderr)
        return 2
    return 0
