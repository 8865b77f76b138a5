"""The import graph of attitude_c: no cycles, and nothing imports the command line from below.

Read statically (ast) from the package's sources, so that every import counts, run or not:
module-level imports and those inside functions (a lazy import is still an arrow), but not
those under ``if TYPE_CHECKING:`` (never executed). Importing ``a.b.c`` also runs the
packages ``a.b`` (their ``__init__``): an arrow to each, except to the importer's own
ancestors, which are already being imported. ``attitude_c.__main__`` (``python -m
attitude_c``) is the command's entry point: it is the one module outside ``attitude_c.cli``
that may import it.
"""

from __future__ import annotations

import ast
from pathlib import Path

import attitude_c

PACKAGE = Path(attitude_c.__file__).parent
ENTRY_POINTS = {"attitude_c.__main__"}


def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING"
            or isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _imports(tree: ast.AST) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement, module level or in a function, but under ``if TYPE_CHECKING``."""
    out: list[ast.Import | ast.ImportFrom] = []

    def walk(node: ast.AST) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child.test):
                for n in child.orelse:
                    walk(n)
                continue
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                out.append(child)
            walk(child)
    walk(tree)
    return out


def _targets(node: ast.Import | ast.ImportFrom, me: str, is_pkg: bool, modules: set[str]) -> set[str]:
    """The package modules one import statement runs."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        if node.level:
            base = me.split(".") if is_pkg else me.split(".")[:-1]
            base = base[:len(base) - (node.level - 1)]
            stem = ".".join(base + ([node.module] if node.module else []))
        else:
            stem = node.module or ""
        names = [stem] + [f"{stem}.{a.name}" for a in node.names]  # "from p import m": m may be a module
    out = set()
    for name in names:
        parts = name.split(".")
        for i in range(1, len(parts) + 1):
            prefix = ".".join(parts[:i])
            if prefix in modules and not me.startswith(prefix + ".") and prefix != me:
                out.add(prefix)
    return out


def import_graph(root: Path = PACKAGE) -> dict[str, set[str]]:
    """Module -> the package modules it imports (see the module's doc for what counts)."""
    files = {_module_name(p, root): p for p in sorted(root.rglob("*.py")) if "_build" not in p.parts}
    modules = set(files)
    graph: dict[str, set[str]] = {}
    for me, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        graph[me] = set()
        for node in _imports(tree):
            graph[me] |= _targets(node, me, path.name == "__init__.py", modules)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def upward_into_cli(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """(importer, imported) for every arrow into attitude_c.cli from outside it."""
    def in_cli(m: str) -> bool:
        return m == "attitude_c.cli" or m.startswith("attitude_c.cli.")
    return sorted((a, b) for a, targets in graph.items() for b in targets
                  if in_cli(b) and not in_cli(a) and a not in ENTRY_POINTS)


def test_the_graph_is_read_from_every_module() -> None:
    g = import_graph()
    # known arrows of each kind the reader must see: module level, relative, function level, a package
    assert "attitude_c.errors" in g["attitude_c.core"]
    assert "attitude_c.sim.configure" in g["attitude_c.sim.chain"]  # inside SimConfig.from_dict
    assert "attitude_c.sim" in g["attitude_c.cli.simulate"]  # importing sim.options runs sim/__init__
    assert "attitude_c.sim.chain" not in g["attitude_c.sim.sources"]  # under TYPE_CHECKING only
    assert len(g) > 60


def test_no_import_cycles() -> None:
    assert cycles(import_graph()) == []


def test_nothing_imports_the_command_line_from_below() -> None:
    assert upward_into_cli(import_graph()) == []


def test_the_checks_see_a_cycle_and_an_upward_arrow() -> None:
    g = {"attitude_c.a": {"attitude_c.b"}, "attitude_c.b": {"attitude_c.c"}, "attitude_c.c": {"attitude_c.a"},
         "attitude_c.d": {"attitude_c.cli.simulate"}, "attitude_c.cli.simulate": set()}
    assert cycles(g) == [["attitude_c.a", "attitude_c.b", "attitude_c.c"]]
    assert upward_into_cli(g) == [("attitude_c.d", "attitude_c.cli.simulate")]
