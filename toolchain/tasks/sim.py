"""Simulation task: `invoke sim` runs `attitude simulate` from this tree, with the
tooling layer's acquisition sources (``--firmware s51``) registered
(``python -m toolchain.simulate``)."""

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


