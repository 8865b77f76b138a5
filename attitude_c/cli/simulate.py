"""``attitude simulate``: the paper's whole system end to end in simulation."""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import sys
import time
from pathlib import Path
from typing import Any, Callable

from ..core import METHODS as _METHODS
from ..sim.options import DEFAULT_DURATION_S, PAPER_PERIOD_S, RUN, add_arguments, from_namespace
from . import options

__all__ = ["DEFAULT_DURATION_S", "PAPER_PERIOD_S", "build_config", "register", "run"]

_ber = options.probability("BER", below=0.5)


def _methods(text: str) -> tuple[str, ...]:
    ms = tuple(m.strip() for m in text.split(",") if m.strip())
    bad = [m for m in ms if m not in _METHODS]
    if bad or not ms:
        raise argparse.ArgumentTypeError(f"unknown method(s) {bad or text!r}; choose from "
                                         f"{', '.join(_METHODS)}")
    return ms


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "simulate",
        help="run the paper's system end to end in simulation (errors, plots, budget)",
        description="Simulate the whole attitude measurement system of the paper: a known "
        "trajectory, gyros, the TLC2543 ADC (C driver + device model), the acquisition board, "
        "the serial link (C sender/receiver, optional bit errors) and the integrator; compare "
        "the computed attitude with the truth. Writes errors.png (paper Fig. 8 style), "
        "attitude.png, timeseries.csv and summary.json into the output directory and prints a "
        "table. With --budget, switches the error sources on one at a time for every method.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    g = add_arguments(p)[RUN]  # the simulator's options (attitude_c/sim/options.py), then how a run is kept
    g.add_argument("--out", metavar="DIR", default=None,
                   help="output directory (default results/<run>/)")
    g.add_argument("--budget", action="store_true",
                   help="error budget: sources on one at a time, for every method")
    g.add_argument("--methods", type=_methods, default=_METHODS, metavar="M1,M2",
                   help="methods of the budget")
    g.add_argument("--budget-ber", type=_ber, default=1e-3, metavar="BER",
                   help="BER of the budget's link stage")
    g.add_argument("--no-plots", action="store_true", help="skip the PNG files")
    g.add_argument("--no-progress", action="store_true", help="no progress bar")
    g.add_argument("--json", action="store_true", help="print the JSON summary instead of the table")
    p.set_defaults(func=run)


class _Progress:
    """tqdm bar per stage, shown only for stages with enough work."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.bars: dict[str, Any] = {}

    def __call__(self, stage: str, done: int, total: int) -> None:
        if not self.enabled or total < 2000 and stage != "budget":
            return
        bar = self.bars.get(stage)
        if bar is None:
            from tqdm import tqdm

            bar = tqdm(total=total, desc=stage, unit="it", leave=False, file=sys.stderr,
                       dynamic_ncols=True, mininterval=0.3)
            self.bars[stage] = bar
        bar.update(done - bar.n)
        if done >= total:
            bar.close()

    def close(self) -> None:
        for b in self.bars.values():
            b.close()


def build_config(args: argparse.Namespace) -> Any:
    """The run's configuration (SimConfig) from the parsed command line."""
    from ..sim import SimConfig
    from ..sim.configure import build

    if args.budget and args.board == "aided9":
        raise ValueError("--board aided9 runs the modeled TLC2543 board: drop --firmware, --adc ad7927, --budget")
    if args.budget and args.estimator == "ahrs":
        raise ValueError("--budget compares the integrator's methods: drop --estimator ahrs")
    return SimConfig(**build(from_namespace(args)))


def run(args: argparse.Namespace) -> int:
    from ..errors import AttitudeError
    from . import EXIT_OS, EXIT_USAGE, fail, os_error_line

    try:
        return _run(args)
    except OSError as exc:  # the output location, a full disk (ResultsIncomplete says which files)
        return fail("attitude simulate", os_error_line(exc), EXIT_OS)
    except (AttitudeError, ValueError, TypeError) as exc:
        return fail("attitude simulate", str(exc), EXIT_USAGE)


def _run(args: argparse.Namespace) -> int:
    from .._io import check_output_dir, write_results
    from ..sim import format_budget, format_table, plot_budget, run_budget, simulate, write_run
    from ..sim.chain import WALL_DECIMALS
    from ..sim.report import to_jsonable

    cfg = build_config(args)
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    name = f"{stamp}-{'budget' if args.budget else cfg.method if cfg.estimator == 'integrator' else 'ahrs'}-{cfg.trajectory.name}-s{cfg.seed}"
    out = Path(args.out) if args.out else Path("results") / name
    made = not out.exists()
    check_output_dir(out)  # before the run: a wrong --out costs nothing
    prog = _Progress(enabled=not args.no_progress)
    t0 = time.perf_counter()
    ok = False
    try:
        if args.budget:
            b = run_budget(cfg, methods=args.methods, ber=args.budget_ber, progress=prog)
            d = b.to_dict()
            d["elapsed_s"] = round(time.perf_counter() - t0, WALL_DECIMALS)
            steps: list[tuple[Path, Callable[[Path], object]]] = [
                (out / "budget.json", lambda p: p.write_text(json.dumps(to_jsonable(d), indent=2) + "\n")),
                (out / "budget.md", lambda p: p.write_text(format_budget(b, markdown=True) + "\n"))]
            if not args.no_plots:
                steps.append((out / "budget.png", lambda p: plot_budget(b, p)))
            prog.close()
            write_results(steps)
            if args.json:
                print(json.dumps(to_jsonable(d), indent=2))
            else:
                print("error budget: RMS attitude-angle error (rad) after each stage "
                      "(contribution of the stage's source)")
                print(format_budget(b))
                print(f"wrote {out}/ (budget.json, budget.md{', budget.png' if not args.no_plots else ''})"
                      f" in {time.perf_counter() - t0:.1f} s")
            ok = True
            return 0
        res = simulate(cfg, progress=prog)
        files = write_run(res, out, plots=not args.no_plots)
        ok = True
    finally:
        prog.close()
        if not ok and made:
            with contextlib.suppress(OSError):  # the directory made for this run, if left empty
                out.rmdir()
    if args.json:
        print(json.dumps(to_jsonable(res.summary), indent=2))
    else:
        print(format_table(res.summary))
        print(f"wrote {out}/ ({', '.join(p.name for p in files.values())})")
    return 0
