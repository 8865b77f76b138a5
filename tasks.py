"""Project tasks (pyinvoke). `invoke --list` shows them.

Task bodies live in toolchain/tasks/*.py, one module per area; toolchain
settings live in toolchain/*.toml, not in code.
"""

from invoke import Collection

from toolchain.tasks import core

ns = Collection()
for t in (core.build, core.test, core.lint, core.format, core.clean, core.bench):
    ns.add_task(t)

# Areas that add their own tasks (top-level tasks and/or a namespace).
import importlib

for _name in ("cross", "link", "sim", "firmware", "view"):
    try:
        _mod = importlib.import_module(f"toolchain.tasks.{_name}")
    except ModuleNotFoundError as _exc:
        if _exc.name != f"toolchain.tasks.{_name}":
            raise
        continue
    for _t in getattr(_mod, "TOP_LEVEL", ()):
        ns.add_task(_t)
    if getattr(_mod, "NAMESPACE", False):
        ns.add_collection(Collection.from_module(_mod, name=_name))
