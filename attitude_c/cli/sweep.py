"""``attitude sweep``: parameter sweeps and Monte Carlo studies on Dask (docs/sweep.md).

Exit codes (docs/cli.md): 0 every run finished; 1 an OS error (the spec
cannot be read, the output folder or one of its files cannot be written:
the message names the file), or the sweep finished but some runs raised
(recorded in the table's ``error`` column); 2 a bad spec or argument (also
a spec of more runs than ``--max-runs``); 3 the engine is not available
(dask/distributed/pandas missing, no scheduler at the address); 130
interrupted (rerun the same command to resume).
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

from .options import integer

EXIT_RUNS_FAILED = 1
EXIT_OS = 1  # the convention of every command (docs/cli.md): an OS error is 1
EXIT_SPEC = 2
EXIT_ENGINE = 3
EXIT_INTERRUPTED = 130


class _LogProgress:
    """Progress as plain lines on stderr when it is not a terminal (logs, batch jobs):
    every 10 % of the runs and at most every 30 s."""

    def __init__(self, t0: float) -> None:
        self.t0 = t0
        self.last = t0
        self.step = -1

    def __call__(self, done: int, total: int) -> None:
        now = time.perf_counter()
        step = done * 10 // max(total, 1)
        if step != self.step or now - self.last >= 30:
            self.step, self.last = step, now
            print(f"  {done}/{total} runs ({now - self.t0:.0f} s)", file=sys.stderr, flush=True)


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "sweep",
        help="run a parameter sweep / Monte Carlo study of the simulator or of estimators on recordings",
        description="Run every run of a sweep spec (TOML: docs/sweep.md) on Dask -- a local cluster "
        "of worker processes by default, an existing cluster with --scheduler -- and write runs.csv "
        "(one row per run: every parameter, every error figure), summary.csv (per grid point: mean "
        "and percentiles over the seeds), one plot per swept parameter and the journal runs.jsonl "
        "that makes a rerun with the same --out resume. Exit codes: 0 all runs finished, 1 an OS error "
        "or some runs raised (recorded), 2 bad spec or argument, 3 engine unavailable, 130 interrupted.",
    )
    p.add_argument("spec", metavar="SPEC", nargs="?", help="the sweep spec (TOML)")
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="address of a running Dask scheduler (tcp://host:8786); default: start a "
                   "local cluster of worker processes")
    p.add_argument("--workers", type=integer("--workers", 1), default=None, metavar="N",
                   help="worker processes of the local cluster (default: one per CPU this process may use)")
    p.add_argument("--serial", action="store_true",
                   help="no Dask: run everything in this process, one run after another")
    p.add_argument("--out", metavar="DIR", default=None,
                   help="output folder (default results/sweep-<name>); rerun with the same folder to resume")
    p.add_argument("--retry-failed", action="store_true",
                   help="also rerun the runs recorded with an error (default: kept as results)")
    p.add_argument("--dry-run", action="store_true",
                   help="check the spec, say how many runs it has and how many are done; run nothing")
    p.add_argument("--list-options", action="store_true",
                   help="list the attitude simulate options a spec can sweep, and the registered "
                   "estimators of kind = \"recordings\"")
    g = p.add_argument_group("cutting a spec down (no need to edit it)")
    g.add_argument("--set", dest="sets", action="append", type=_setting, default=None, metavar="NAME=VALUE",
                   help="pin a parameter for every run, over the spec's fixed, grid, random and case values "
                   "of NAME (an attitude simulate option, an estimator setting, or trial); VALUE as in the "
                   "spec (TOML: 0.01, true, [30, 20, 25]; a bare word is a string: rv3); repeatable")
    g.add_argument("--seeds", type=_seeds, default=None, metavar="N|A,B,...",
                   help="replace the spec's seeds: a count N (seeds 0 .. N-1) or a list of seeds "
                   "(3,17,42; one seed: 7,)")
    g.add_argument("--limit", type=integer("--limit", 1), default=None, metavar="N",
                   help="run only the first N runs of the spec, in its order")
    g.add_argument("--max-runs", type=integer("--max-runs", 1), default=None, metavar="N",
                   help="refuse a spec that expands to more than N runs, counted before anything is expanded "
                   "(default: attitude_c.sim.sweeps.MAX_RUNS, 100000); raise it for a bigger study")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG files")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _setting(text: str) -> tuple[str, Any]:
    """NAME=VALUE of --set: the value read as TOML (a number, a boolean, a string in quotes,
    an array), else as the bare string."""
    import datetime

    name, sep, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not sep or not name or not value:
        raise argparse.ArgumentTypeError(f"--set expects NAME=VALUE, got {text!r}")
    from ..sim.sweeps import SpecError, _toml_loads

    try:
        v = _toml_loads(f"v = {value}")["v"]
    except SpecError:
        return name, value
    if isinstance(v, (datetime.date, datetime.time, dict)):  # TOML's dates and tables are no parameter
        return name, value
    return name, v


def _seeds(text: str) -> int | list[int]:
    """--seeds: a count N, or a comma-separated list (one seed: "7,")."""
    parts = text.replace(" ", "").split(",")
    try:
        nums = [int(x) for x in parts if x != ""]
    except ValueError:
        nums = []
    if not nums or any(n < 0 for n in nums) or "," not in text and nums[0] < 1:
        raise argparse.ArgumentTypeError(f"--seeds: give a count >= 1 or a list of integers >= 0 "
                                         f"(3,17,42; one seed: 7,), got {text!r}")
    return nums if "," in text else nums[0]


def _list_options() -> int:
    from ..sim.sweeps import ESTIMATORS, simulate_options

    print("kind = \"simulate\": options (spec name, command-line option, choices)")
    for name, o in simulate_options().items():
        ch = f"  {{{', '.join(map(str, o.choices))}}}" if o.choices else ""
        what = {"switch": " (switch: true/false)", "repeat": " (repeatable: a list of values)"}.get(o.kind, "")
        print(f"  {name:16s} {o.flag}{what}{ch}")
    print("kind = \"recordings\": estimators")
    for name in sorted(ESTIMATORS):
        print(f"  {name}")
    return 0


def run(args: argparse.Namespace) -> int:
    from ..errors import AttitudeError
    from . import fail

    prog = "attitude sweep"
    if args.list_options:
        return _list_options()
    if not args.spec:
        return fail(prog, "give a SPEC file (or --list-options)", EXIT_SPEC)
    if args.serial and (args.scheduler or args.workers):
        return fail(prog, "--serial runs in this process: drop --scheduler/--workers", EXIT_SPEC)
    if args.scheduler and args.workers:
        return fail(prog, "--workers sizes the local cluster: an existing scheduler has its own workers", EXIT_SPEC)
    from ..sim import sweeps
    from . import os_error_line

    try:
        spec = sweeps.load_spec(args.spec, sets=dict(args.sets or ()), seeds=args.seeds, limit=args.limit,
                                max_runs=args.max_runs or sweeps.MAX_RUNS)
    except OSError as exc:
        return fail(prog, os_error_line(exc), EXIT_OS)
    except (AttitudeError, ValueError, TypeError) as exc:
        return fail(prog, f"{args.spec}: {exc}", EXIT_SPEC)
    except ImportError as exc:
        return fail(prog, str(exc), EXIT_ENGINE)
    from pathlib import Path

    out = Path(args.out) if args.out else Path("results") / f"sweep-{spec.name}"
    done = sweeps.read_journal(out / sweeps.JOURNAL) if (out / sweeps.JOURNAL).exists() else {}
    have = sum(1 for r in spec.runs if r.key in done)
    print(f"sweep {spec.name} ({spec.kind}): {len(spec.runs)} runs, swept: {', '.join(spec.axes) or 'seeds only'}"
          f"; {have} already done in {out}/", file=sys.stderr)
    if args.dry_run:
        return 0
    client: Any = "serial" if args.serial else args.scheduler
    t0 = time.perf_counter()
    progress: Any = False
    if not args.no_progress:
        progress = True if sys.stderr.isatty() else _LogProgress(t0)
    try:
        df = sweeps.sweep(spec, client, out=out, workers=args.workers, progress=progress,
                          retry_failed=args.retry_failed, plots=not args.no_plots)
    except KeyboardInterrupt:
        got = sweeps.read_journal(out / sweeps.JOURNAL)
        n = sum(1 for r in spec.runs if r.key in got)
        print(f"{prog}: interrupted: {n} of {len(spec.runs)} runs are recorded in {out}/; "
              "rerun the same command to resume", file=sys.stderr)
        return EXIT_INTERRUPTED
    except ImportError as exc:
        return fail(prog, str(exc), EXIT_ENGINE)
    except (AttitudeError, ValueError) as exc:  # e.g. another sweep holds the folder
        return fail(prog, str(exc), EXIT_SPEC)
    except ConnectionError as exc:
        return fail(prog, str(exc), EXIT_ENGINE)
    except OSError as exc:  # the sweep names the file (sweeps._named)
        return fail(prog, os_error_line(exc) if exc.filename else f"{out}: {exc.strerror or exc}", EXIT_OS)
    a = df.attrs
    print(f"ran {a['executed']} run(s), reused {a['reused']}, on {a['engine']} in "
          f"{time.perf_counter() - t0:.1f} s; {a['failed']} failed; wrote {out}/ (runs.csv, summary.csv"
          f"{', plots' if not args.no_plots else ''})")
    if not args.no_plots and not a["plots"] and spec.axes:
        print(f"{prog}: no plot: figure {spec.figure!r} is not a column of runs.csv with values "
              "([sweep] figure)", file=sys.stderr)
    if a["failed"]:
        first = df.loc[df["error"] != "", "error"].iloc[0]
        print(f"{prog}: {a['failed']} run(s) raised (error column of runs.csv), e.g. {first}", file=sys.stderr)
        return EXIT_RUNS_FAILED
    return 0
