"""attitude_c.sim.report writes each result file once: one temporary file beside it,
one rename onto it (attitude_c._io); a writer failing half-way leaves no partial
file and no temporary file, and an earlier run's file as it was."""

from __future__ import annotations

import errno
import os
from pathlib import Path
from typing import Any

import pytest

from attitude_c import _io
from attitude_c.sim import AdcModel, SimConfig, simulate
from attitude_c.sim import report as R


@pytest.fixture(scope="module")
def res() -> Any:
    # the vectorized ADC and no link: a run in a fraction of a second
    return simulate(SimConfig(adc=AdcModel(backend="ideal"), link="none", duration=2.0))


@pytest.mark.system
def test_one_rename_per_result_file(res: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    renames: list[tuple[Path, Path]] = []
    real = os.replace

    def replace(src: Any, dst: Any) -> None:
        renames.append((Path(src), Path(dst)))
        real(src, dst)

    monkeypatch.setattr(_io.os, "replace", replace)
    files = R.write_run(res, tmp_path, plots=True)
    assert sorted(dst for _, dst in renames) == sorted(files.values())  # each file renamed once
    for src, dst in renames:  # from its own temporary name, in the same directory
        assert src.parent == dst.parent and src.name.startswith(f".{dst.stem}.tmp-"), (src, dst)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in files.values())
    renames.clear()
    R.plot_errors(res, tmp_path / "e.png")  # the public writers are atomic on their own too
    R.write_csv(res, tmp_path / "t.csv")
    assert [dst.name for _, dst in renames] == ["e.png", "t.csv"]


@pytest.mark.parametrize("failing", ["_write_csv", "_draw_attitude"])
def test_a_failed_write_leaves_no_partial_file(res: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                               failing: str) -> None:
    real = getattr(R, failing)

    def half(res_: Any, path: Path, *a: Any) -> None:
        real(res_, path, *a)  # the whole file written to the temporary path, then the disk "fills"
        with open(path, "r+b") as fh:
            fh.truncate(os.path.getsize(path) // 2)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    out = tmp_path / "run"
    out.mkdir()
    (out / "attitude.png").write_bytes(b"an earlier run's complete file")
    monkeypatch.setattr(R, failing, half)
    with pytest.raises(_io.ResultsIncomplete) as e:
        R.write_run(res, out, plots=True)
    left = sorted(p.name for p in out.iterdir())
    assert not [n for n in left if n.startswith(".")], left  # no temporary file
    bad = "timeseries.csv" if failing == "_write_csv" else "attitude.png"
    assert e.value.failed == out / bad
    # the files before the failing one complete, the failing one and those after absent
    # (the earlier run's attitude.png left as it was)
    done = [] if bad == "timeseries.csv" else ["timeseries.csv", "errors.png"]
    assert [p.name for p in e.value.complete] == done
    assert left == sorted([*done, "attitude.png"])
    assert (out / "attitude.png").read_bytes() == b"an earlier run's complete file"
    if done:
        assert (out / "timeseries.csv").read_text().endswith("\n")
