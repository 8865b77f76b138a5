"""tasks.py: one static invoke Collection, every task documented and every argument
with its help (what `invoke --help TASK` prints)."""

from __future__ import annotations

import inspect


def test_every_task_and_argument_is_documented() -> None:
    import tasks

    names = set(tasks.ns.task_names)
    assert {"build", "test", "lint", "format", "clean", "bench", "cross-build", "fuzz", "sim",
            "firmware.build", "firmware.sim"} <= names
    for name in sorted(names):
        t = tasks.ns[name]
        assert t.__doc__ and t.__doc__.strip(), name
        params = [p for p in inspect.signature(t.body).parameters if p != "c"]
        missing = [p for p in params if not t.help.get(p) and not t.help.get(p.replace("_", "-"))]
        assert not missing, f"{name}: no help for {missing}"
