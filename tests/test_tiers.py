"""The test tiers (tests/conftest.py): the guard that keeps the `system` mark true, and the
fast tier's selection (`invoke test --fast`)."""

from __future__ import annotations

import multiprocessing
import os
import subprocess
import sys
from types import SimpleNamespace

import pytest
from conftest import _ProcessGuard, is_system, pytest_collection_modifyitems


class _Item(SimpleNamespace):
    def get_closest_marker(self, name: str) -> object:
        return name if name in self.marks else None


def _starts(how: str) -> None:
    if how == "subprocess":
        subprocess.run([sys.executable, "-c", "pass"], check=True)
    elif how == "fork":
        os.fork()
    elif how == "system":
        os.system("true")
    else:  # a spawned interpreter, as multiprocessing and Dask's nannies start one
        p = multiprocessing.get_context("spawn").Process(target=print)
        p.start()
        p.join()


@pytest.mark.parametrize("how", ["subprocess", "fork", "system", "spawn"])
def test_the_guard_refuses_every_way_of_starting_a_process(how: str) -> None:
    item = _Item(nodeid="tests/x.py::test_y", marks=())
    before = (subprocess._fork_exec, os.fork, os.system)  # type: ignore[attr-defined]
    with pytest.raises(RuntimeError, match=r"tests/x.py::test_y starts a process but is not marked system"):
        with _ProcessGuard(item):
            _starts(how)
    assert (subprocess._fork_exec, os.fork, os.system) == before  # type: ignore[attr-defined]  # put back


def test_this_unmarked_test_runs_under_the_guard() -> None:
    """The guard is on for the body of every test without the mark (the hook in conftest)."""
    with pytest.raises(RuntimeError, match="test_this_unmarked_test_runs_under_the_guard starts a process"):
        subprocess.run(["true"], check=False)


@pytest.mark.system
def test_a_system_test_may_start_processes() -> None:
    assert subprocess.run([sys.executable, "-c", "print(6 * 7)"], capture_output=True, text=True,
                          check=True).stdout.strip() == "42"


def test_the_fast_tier_deselects_system_and_toolchain_marks() -> None:
    items = [_Item(nodeid=str(m), marks=m) for m in [(), ("system",), ("qemu",), ("s51",), ("slow",), ("parametrize",)]]
    gone: list[object] = []
    config = SimpleNamespace(getoption=lambda name: name == "--fast",
                             hook=SimpleNamespace(pytest_deselected=lambda items: gone.extend(items)))
    kept = list(items)
    pytest_collection_modifyitems(config, kept)  # type: ignore[arg-type]
    assert [it.marks for it in kept] == [(), ("parametrize",)]
    assert all(is_system(it) for it in gone) and len(gone) == 4  # type: ignore[arg-type]
