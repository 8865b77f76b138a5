"""The Python package as a user gets it: sdist -> wheel built *from the sdist*
-> a fresh virtual environment outside the checkout -> smoke test.

The fresh environment has no system site-packages and gets the wheel's
dependencies from the package index through pip (its cache makes repeated
runs cheap). Reusing this environment's packages instead would hide a
missing dependency in pyproject.toml and, worse, let the editable checkout
of attitude_c answer the imports instead of the wheel.
"""

from __future__ import annotations

import importlib.metadata
import importlib.util
import json
import os
import subprocess
import sys
import tarfile
import venv
import zipfile
from pathlib import Path

import pytest
from conftest import _missing, clean_copy

pytestmark = pytest.mark.system  # builds the sdist and wheel, installs into a fresh venv

# Every module the smoke test must import from the installed wheel: all
# modules of the package whose dotted name has no part starting with "_".
_IMPORT_ALL = r"""
import importlib, json, pkgutil, sys
import attitude_c
mods = sorted(m.name for m in pkgutil.walk_packages(attitude_c.__path__, "attitude_c.")
              if not any(p.startswith("_") for p in m.name.split(".")))
for m in mods:
    importlib.import_module(m)
import numpy as np
q32 = attitude_c.integrate(np.full((6, 3), 1e-3, dtype=np.float32), precision="f32")
print(json.dumps({"file": attitude_c.__file__, "modules": mods, "f32_dtype": str(q32.dtype),
                  "ext": [attitude_c._lib._module(p).__file__ for p in ("f64", "f32")]}))
"""


def _run(cmd: list, **kw) -> subprocess.CompletedProcess:
    proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, check=False, **kw)
    assert proc.returncode == 0, f"{' '.join(map(str, cmd))} failed ({proc.returncode}):\n" \
                                 f"{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    return proc


def _clean_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV"))}
    env["MPLBACKEND"] = "Agg"
    return env


@pytest.mark.slow
def test_sdist_wheel_fresh_venv_smoke(tmp_path: Path) -> None:
    try:  # by its metadata: a build/ output folder on sys.path would fool find_spec
        importlib.metadata.version("build")
    except importlib.metadata.PackageNotFoundError:
        _missing("needs the 'build' package: pip install -e '.[test]'")
    src = clean_copy(tmp_path / "src", ".")
    dist = tmp_path / "dist"
    # builds the sdist, then the wheel from the unpacked sdist (not from the tree)
    _run([sys.executable, "-m", "build", "--outdir", dist, src], cwd=tmp_path, env=_clean_env(),
         timeout=600)
    sdist = next(dist.glob("attitude_c-*.tar.gz"))
    wheel = next(dist.glob("attitude_c-*.whl"))

    with tarfile.open(sdist) as tf:
        names = {n.split("/", 1)[1] for n in tf.getnames() if "/" in n}
    for need in ("csrc/include/attitude/attitude.h", "csrc/cffi/bindings.h", "csrc/src/integrator.c",
                 "csrc/host/link_sim.h", "setup.py", "pyproject.toml"):
        assert need in names, f"sdist lacks {need}"
    assert not any(n.endswith(".so") for n in names)

    # one wheel for every CPython >= 3.9: the stable ABI (docs/packaging in README)
    assert "-cp39-abi3-" in wheel.name, wheel.name
    with zipfile.ZipFile(wheel) as zf:
        sos = sorted(n for n in zf.namelist() if n.endswith(".so"))
        static = {n for n in zf.namelist() if n.startswith("attitude_c/view/static/")}
    assert sos == ["attitude_c/_att_f32.abi3.so", "attitude_c/_att_f64.abi3.so"]
    # the display's page works offline: all of it is package data
    from attitude_c.view.server import ASSETS

    assert static == {f"attitude_c/view/static/{name}" for name in ASSETS}, static

    # a fresh venv outside the checkout; pip of this interpreter installs into it
    # (--python), so the venv needs no ensurepip (Debian's python3 lacks it)
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=False, system_site_packages=False).create(env_dir)
    py = env_dir / "bin" / "python"
    _run([sys.executable, "-m", "pip", "--python", py, "install", "-q", wheel], env=_clean_env(), timeout=600)

    work = tmp_path / "work"
    work.mkdir()
    out = json.loads(_run([py, "-c", _IMPORT_ALL], cwd=work, env=_clean_env(), timeout=120).stdout)
    assert Path(out["file"]).is_relative_to(env_dir), out["file"]  # the wheel, not the checkout
    assert all(Path(e).is_relative_to(env_dir) and e.endswith(".abi3.so") for e in out["ext"]), out["ext"]
    for m in ("attitude_c.core", "attitude_c.cli.simulate", "attitude_c.link.transport", "attitude_c.names",
              "attitude_c.sensor", "attitude_c.sim.chain", "attitude_c.sim.host", "attitude_c.sim.board",
              "attitude_c.tlc2543.model", "attitude_c.reference"):
        assert m in out["modules"]
    assert out["f32_dtype"] == "float32"

    run = work / "run"
    proc = _run([env_dir / "bin" / "attitude", "simulate", "--duration", "5", "--no-progress", "--out", run],
                cwd=work, env=_clean_env(), timeout=300)
    assert "heading" in proc.stdout
    summary = json.loads((run / "summary.json").read_text())
    assert summary["parameters"]["duration_s"] == 5.0
    assert {p.name for p in run.iterdir()} >= {"summary.json", "timeseries.csv", "errors.png", "attitude.png"}


def test_invoke_build_isolates_only_when_needed() -> None:
    """`invoke build` reuses this interpreter's build tools only when they
    meet pyproject's [build-system] requires (setuptools >= 77 for the SPDX
    license field); otherwise pip builds in an isolated environment."""
    from toolchain.tasks.core import build_requirements_met

    assert build_requirements_met(["pip", "cffi>=1.0"])
    assert not build_requirements_met(["setuptools>=9999"])
    assert not build_requirements_met(["surely-not-installed-attitude-pkg"])
    assert not build_requirements_met(["cffi<2; python_version>'3'"])  # not understood: isolate
    from importlib import metadata

    have = metadata.version("setuptools")
    assert build_requirements_met([f"setuptools>={have}"])


#: Distributions the package's dependencies install, by their import name
#: (pyproject.toml [project] dependencies), and what only one function imports
#: on demand with a message naming what to install (scipy: attitude_c.broad's .mat reader).
_DEPENDENCIES = {"cffi", "numpy", "serial", "matplotlib", "tqdm"}
def _extras_imports() -> set[str]:
    """The optional dependencies the package itself uses (pyproject's extras but test, dev and
    bench, which serve the tests and benchmarks), by import name: each is imported where it is
    needed, with a message saying what to install."""
    import re

    from conftest import ROOT

    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover - the sweep extra installs tomli there
        import tomli as tomllib

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    return {re.split(r"[<>=;\[ ]", req, maxsplit=1)[0].lower() for name, reqs in extras.items()
            if name not in {"test", "dev", "bench"} for req in reqs}


_ON_DEMAND = _extras_imports()


def test_the_package_imports_nothing_outside_itself() -> None:
    """attitude_c imports the standard library, its dependencies and itself, also inside
    functions (the wheel test above imports every module, but not every function's
    imports); and no file of the project edits sys.path."""
    import ast

    from conftest import ROOT

    bad = []
    for f in sorted((ROOT / "attitude_c").rglob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module else [])
            for n in names:
                top = n.split(".")[0]
                if top not in sys.stdlib_module_names and top not in _DEPENDENCIES | _ON_DEMAND | {"attitude_c"}:
                    bad.append(f"{f.relative_to(ROOT)}:{node.lineno}: import {n}")
    assert not bad, "\n".join(bad)
    import re

    edit = re.compile(r"\bsys\.path\s*(\.\s*(insert|append|extend|remove)\s*\(|\+?=|\[)")
    files = [ROOT / "tasks.py", ROOT / "setup.py"] + [f for d in ("attitude_c", "tests", "toolchain", "bench")
                                                      for f in sorted((ROOT / d).rglob("*.py"))]
    edits = [f"{f.relative_to(ROOT)}:{i}" for f in files for i, line in enumerate(f.read_text().splitlines(), 1)
             if edit.search(line)]
    assert not edits, edits
