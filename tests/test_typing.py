"""The public API's fixed string choices are Literal types: a type checker
(mypy) catches a wrong method or precision before anything runs."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

from conftest import ROOT, _missing

import pytest

pytestmark = pytest.mark.system  # runs mypy

SNIPPET = '''\
import numpy as np
import attitude_c as ac
from attitude_c.link.transport import run_sender
from attitude_c.sim import SimConfig

x = np.zeros((3, 3))
ac.integrate(x, method="rv4")                          # line 7: bad
ac.integrate(x, precision="f16")                       # line 8: bad
ac.Integrator("rv3", precision="f16")                  # line 9: bad
SimConfig(sensors="perfect")                           # line 10: bad
run_sender(None, [], impl="rust")                      # line 11: bad
ac.Integrator("rv3", precision="fixed")                # fine: one contract for every precision
ac.integrate(x, method="rv3-reuse", precision="f32")   # fine
ac.Integrator("rk4", precision="f64")                  # fine
SimConfig(method="rv1", precision="fixed", sensors="ideal", link="none")  # fine
'''


def test_mypy_rejects_unknown_choices(tmp_path: Path) -> None:
    if importlib.util.find_spec("mypy") is None:
        _missing("needs mypy: pip install -e '.[test]'")
    src = tmp_path / "user_code.py"
    src.write_text(SNIPPET)
    proc = subprocess.run([sys.executable, "-m", "mypy", "--follow-imports=silent", "--no-error-summary",
                           "--cache-dir", str(tmp_path / "cache"), str(src)],
                          cwd=ROOT, capture_output=True, text=True, timeout=300, check=False)
    bad_lines = sorted({int(ln.split(":")[1]) for ln in proc.stdout.splitlines() if ": error:" in ln})
    assert bad_lines == [7, 8, 9, 10, 11], proc.stdout + proc.stderr
    assert "rv4" in proc.stdout and "f16" in proc.stdout
