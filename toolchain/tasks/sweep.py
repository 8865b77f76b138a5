"""Sweep task: `invoke sweep` runs `attitude sweep` from this tree (long studies:
docs/sweep.md). Rerunning the same command resumes an interrupted sweep."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

from invoke import task

ROOT = Path(__file__).resolve().parents[2]


@task(help={
    "spec": "the sweep spec (TOML; default: examples/error-budget.toml, the error budget over seeds, "
            "methods and sample periods)",
    "scheduler": "address of a running Dask scheduler (tcp://host:8786); default: a local cluster",
    "workers": "worker processes of the local cluster (default: one per CPU)",
    "out": "output folder (default results/sweep-<name>); the same folder resumes",
    "serial": "no Dask: every run in this process",
    "retry_failed": "also rerun the runs recorded with an error",
    "dry_run": "check the spec and count the runs (done and to do); run nothing",
    "no_plots": "skip the PNG files",
})
def sweep(c, spec="examples/error-budget.toml", scheduler="", workers=0, out="", serial=False,
          retry_failed=False, dry_run=False, no_plots=False):
    """Run a parameter sweep / Monte Carlo study (`attitude sweep`) on Dask; rerun to resume."""
    cmd = [sys.executable, "-m", "attitude_c", "sweep", spec]
    if scheduler:
        cmd += ["--scheduler", scheduler]
    if workers:
        cmd += ["--workers", str(workers)]
    if out:
        cmd += ["--out", out]
    for flag, on in (("--serial", serial), ("--retry-failed", retry_failed), ("--dry-run", dry_run),
                     ("--no-plots", no_plots)):
        if on:
            cmd.append(flag)
    with c.cd(str(ROOT)):
        c.run(" ".join(shlex.quote(x) for x in cmd), pty=sys.stdout.isatty())
