"""The project's own files install everything its tests, benchmarks and tasks import.

Every import under tests/, bench/ and toolchain/ (which the tests import) and in
tasks.py is the standard library, the project's own code, or a distribution that
pyproject.toml declares: in [project] dependencies or in an extra that ``[test]``
pulls in. scripts/setup.sh (the README's test command) installs an extra that
holds all of them, and the developer's one-line install, ``pip install -e ".[dev]"``,
holds every extra. What is declared is read from pyproject.toml, self-references
(``attitude-c[bench]``) followed, so a package installed by hand on this machine
cannot hide a missing declaration.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

from conftest import ROOT

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

#: Import names whose distribution has another name (the rest are their own name).
DISTRIBUTION_OF = {"pywt": "PyWavelets", "serial": "pyserial", "yaml": "PyYAML", "PIL": "Pillow",
                   "mpl_toolkits": "matplotlib", "_pytest": "pytest"}


def _norm(name: str) -> str:
    """A distribution name as pip compares them (PEP 503)."""
    return re.sub(r"[-_.]+", "-", name).lower()


def _requirement(spec: str) -> tuple[str, set[str]]:
    """(normalized name, extras) of a requirement string such as ``attitude-c[view,sweep]``."""
    m = re.match(r"\s*([A-Za-z0-9][A-Za-z0-9._-]*)\s*(?:\[([^\]]*)\])?", spec)
    assert m, f"pyproject.toml: cannot read the requirement {spec!r}"
    return _norm(m.group(1)), {_norm(e.strip()) for e in (m.group(2) or "").split(",") if e.strip()}


def declared(*extras: str) -> set[str]:
    """Distributions `pip install ".[extras]"` installs directly: the dependencies and the
    extras' requirements, following the project's references to its own extras."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    me, table = _norm(project["name"]), project["optional-dependencies"]
    out: set[str] = set()
    todo, seen = list(project["dependencies"]), set()
    todo += [f"{me}[{','.join(extras)}]"] if extras else []
    while todo:
        name, more = _requirement(todo.pop())
        if name != me:
            out.add(name)
        for e in more - seen:
            assert e in table, f"pyproject.toml names the extra [{e}], which it does not define"
            seen.add(e)
            todo += table[e]
    return out


def _local_names() -> set[str]:
    """Top-level names the project's own files provide (packages, root and test modules)."""
    pkgs = {p.parent.name for p in ROOT.glob("*/__init__.py")}
    return pkgs | {p.stem for p in ROOT.glob("*.py")} | {p.stem for p in (ROOT / "tests").glob("*.py")} | {"tests"}


def _imports(f: Path) -> list[tuple[int, str]]:
    """(line, top-level name) of every absolute import in a file, also inside functions."""
    out = []
    for node in ast.walk(ast.parse(f.read_text(), str(f))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name.split(".")[0]) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            out.append((node.lineno, node.module.split(".")[0]))
    return out


def _checked_files() -> list[Path]:
    files = {*ROOT.glob("tests/**/*.py"), *ROOT.glob("bench/*.py"), *ROOT.glob("toolchain/**/*.py"),
             ROOT / "tasks.py"}
    return sorted(files)


def test_every_import_of_the_tests_and_benchmarks_is_declared() -> None:
    have, local = declared("test"), _local_names()
    missing = []
    for f in _checked_files():
        for line, top in _imports(f):
            if top in sys.stdlib_module_names or top in local:
                continue
            dist = _norm(DISTRIBUTION_OF.get(top, top))
            if dist not in have:
                missing.append(f"{f.relative_to(ROOT)}:{line}: import {top} (distribution {dist})")
    assert not missing, ("not installed by pyproject.toml's [test] extra (add it there, or map the "
                         "import name to its distribution in DISTRIBUTION_OF):\n" + "\n".join(missing))


def test_the_checker_reads_self_references_and_names() -> None:
    """The checker itself: extras referenced through the project's own name are followed,
    and a name is compared as pip compares it."""
    assert _requirement("attitude-c[view, sweep]") == ("attitude-c", {"view", "sweep"})
    assert _requirement("PyWavelets>=1.4") == ("pywavelets", set())
    assert _requirement("tomli>=1.1; python_version < '3.11'") == ("tomli", set())
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert declared() == {_requirement(r)[0] for r in project["dependencies"]}
    view = {_requirement(r)[0] for r in project["optional-dependencies"]["view"]}
    assert view <= declared("test") and not view <= declared()


def _setup_extra() -> str:
    """The extra scripts/setup.sh installs the package with."""
    m = re.findall(r"pip install\b[^\n]*?-e\s+[\"']?\.\[([a-z,-]+)\]", (ROOT / "scripts/setup.sh").read_text())
    assert len(m) == 1, f"scripts/setup.sh: expected one `pip install ... -e \".[EXTRA]\"`, found {m}"
    return m[0]


def test_setup_and_the_dev_extra_install_everything() -> None:
    """scripts/setup.sh (CI's install step) installs the dev extra; it holds every other
    extra and the developer's tools (invoke for the embedded path, ruff and mypy for
    `invoke lint`)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    dev = declared("dev")
    assert _setup_extra() == "dev"
    for extra in project["optional-dependencies"]:
        assert declared(extra) <= dev, f"[dev] lacks {sorted(declared(extra) - dev)} of [{extra}]"
    assert {"invoke", "ruff", "mypy", "pytest"} <= dev


def test_docs_name_the_dev_install() -> None:
    """The embedded path needs invoke, which `pip install .` does not bring: the README and
    docs/cross-build.md name the one install that gives a developer everything."""
    cmd = re.compile(r"pip install (?:-e )?[\"']?\.\[dev\]")
    for doc in ("README.md", "docs/cross-build.md"):
        assert cmd.search((ROOT / doc).read_text()), f"{doc} does not say `pip install -e \".[dev]\"`"
