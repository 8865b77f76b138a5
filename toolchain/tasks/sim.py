"""Simulation tasks: `invoke sim` runs `attitude simulate` from this tree, with the
tooling layer's acquisition sources (``--firmware s51``) registered
(``python -m toolchain.simulate``); `invoke sim-acceptance` runs the attitude
filter's simulated acceptance tests at full length (toolchain/ahrs_acceptance.py)."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

from invoke import task

ROOT = Path(__file__).resolve().parents[2]


@task(help={
    "budget": "run the error budget instead of one scenario",
    "args": "extra arguments for `attitude simulate` (quoted), e.g. --args='--method rv1' or "
            "--args='--firmware s51 --duration 8'",
})
def sim(c, budget=False, args=""):
    """Run the full-system simulation (`attitude simulate`); results in results/<run>/."""
    cmd = [sys.executable, "-m", "toolchain.simulate"]
    if budget:
        cmd.append("--budget")
    cmd += shlex.split(args)
    with c.cd(str(ROOT)):
        c.run(" ".join(shlex.quote(x) for x in cmd), pty=sys.stdout.isatty())




@task(help={
    "short": "the shortened runs of the default test suite instead of the full lengths (30 min static, "
             "360 s turntable)",
    "seed": "simulator seed (default 0, the tests')",
    "only": "comma-separated scenarios: static,turntable,bias_step,disturbance (default all)",
    "setting": "filter settings to try, NAME=VALUE[,NAME=VALUE...] (attitude_c.ahrs keywords)",
    "json": "also write the figures to this JSON file",
})
def sim_acceptance(c, short=False, seed=0, only="", setting="", json=""):
    """The attitude filter's simulated acceptance tests (issue 15) at full length; exit 1 if a target is missed."""
    cmd = [sys.executable, "-m", "toolchain.ahrs_acceptance", "--seed", str(int(seed))]
    if short:
        cmd.append("--short")
    if only:
        cmd += ["--only", only]
    for s in (x for x in setting.split(",") if x):
        cmd += ["--setting", s]
    if json:
        cmd += ["--json", json]
    with c.cd(str(ROOT)):
        c.run(" ".join(shlex.quote(x) for x in cmd), pty=sys.stdout.isatty())


@task(help={"short": "the acceptance scenarios' shortened runs", "hours": "length of the rest recording (h)",
            "nees": "instead: the consistency motions with the settings for calibrated parts (10 min at rest)",
            "seeds": "with --nees: the motions' seeds, comma-separated (default 0,1,2: the test's)"})
def allan_settings(c, short=False, hours=2.0, nees=False, seeds="0,1,2"):
    """Filter settings from a simulated rest recording's Allan terms, and the acceptance tests with them
    beside the defaults (docs/noise.md); exit 1 if a target is missed with the derived settings. With
    --nees: the NEES in-band fractions of the consistency motions (exit 1 below 90 %)."""
    cmd = [sys.executable, "-m", "toolchain.allan_settings", "--hours", str(float(hours))]
    if nees:
        cmd += ["--nees", "--seeds", str(seeds)]
    if short:
        cmd.append("--short")
    with c.cd(str(ROOT)):
        c.run(" ".join(shlex.quote(x) for x in cmd), pty=sys.stdout.isatty())


@task(help={"seeds": "recordings per sensor (3 axes each)",
            "t_white": "τ where the white line meets the flicker floor (s)",
            "t_walk": "τ where the floor meets the random walk (s)"})
def allan_sweep(c, seeds=6, t_white=0.3, t_walk=2.0):
    """The noise fit against the simulator's known terms over seeds (docs/noise.md): error spread vs reported 1σ."""
    cmd = [sys.executable, "-m", "toolchain.allan_validation", "--seeds", str(int(seeds)), "--t-white",
           str(float(t_white)), "--t-walk", str(float(t_walk))]
    with c.cd(str(ROOT)):
        c.run(" ".join(shlex.quote(x) for x in cmd), pty=sys.stdout.isatty())
