"""``attitude ahrs`` under what users feed it (issue 29, items 9-10): binary and
huge files refused early in one short line, no result file left behind by a run
that fails, no stray NumPy warning, every message naming the file. In-process
(``attitude_c.cli.main``); each case failed on the code before issue 29."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import broad_mat, peak_memory

from attitude_c.cli import main

N = 200


def _run(capsys, *argv: str) -> tuple[int, list[str]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rc = main(["ahrs", *argv, "--no-plots"])
    assert not caught, [str(w.message) for w in caught]  # nothing but our own line on stderr
    return rc, capsys.readouterr().err.strip().splitlines()


def _mat(path: Path, **kw) -> Path:
    return broad_mat(path, N, **kw)


@pytest.mark.parametrize("case,kw,says", [
    ("reference all NaN", {"opt_quat": np.full((N, 4), np.nan)}, "no movement sample has a valid reference"),
    ("reference all zero", {"opt_quat": np.zeros((N, 4))}, "no movement sample has a valid reference"),
    ("movement/quaternion lengths", {"movement": np.ones((N - 5, 1))}, f"movement has {N - 5} values"),
    ("sampling rate 0", {"sampling_rate": np.array([[0.0]])}, "sampling_rate must be one finite number > 0"),
    ("complex gyro", {"imu_gyr": np.full((N, 3), 0.01 + 1j)}, "imu_gyr holds complex128 values"),
])
def test_a_run_that_fails_leaves_no_result_file(tmp_path: Path, capsys, case: str, kw: dict, says: str) -> None:
    """Exit 2, one line naming the file, and no attitude.csv (it was written before
    the reference was scored, and left behind)."""
    pytest.importorskip("scipy", reason="needs SciPy: pip install -e '.[test]'")
    f = _mat(tmp_path / "trial.mat", **kw)
    out = tmp_path / "out"
    rc, err = _run(capsys, str(f), "--out", str(out))
    assert rc == 2 and len(err) == 1 and says in err[0] and "trial.mat" in err[0], err
    assert not out.exists() or list(out.iterdir()) == []


def test_a_header_only_csv_is_one_line_without_numpy_warnings(tmp_path: Path, capsys) -> None:
    f = tmp_path / "empty.csv"
    f.write_text("t,gx,gy,gz,ax,ay,az\n")
    rc, err = _run(capsys, str(f), "--out", str(tmp_path / "out"))
    assert rc == 2 and err == [f"attitude ahrs: error: {f}: no data rows below the header"]


def test_a_sparse_file_is_refused_at_once_in_one_short_line(tmp_path: Path, capsys) -> None:
    """A 1 GB sparse file took 5.1 GB and ended in a MemoryError with a 400 KB line;
    64 MiB here: read whole it costs far more than the bound below."""
    f = tmp_path / "sparse.csv"
    with open(f, "wb") as fh:
        fh.truncate(64 << 20)
    (rc, err), peak = peak_memory(lambda: _run(capsys, str(f), "--out", str(tmp_path / "out")))
    assert rc == 2 and err == [f"attitude ahrs: error: {f}: not a text file (a NUL byte at offset 0)"]
    assert peak < 4 << 20, peak  # the probe reads 1 KiB; the rest is the interpreter's own


def test_a_huge_line_is_refused_without_holding_it(tmp_path: Path, capsys) -> None:
    f = tmp_path / "long.csv"
    with open(f, "w") as fh:
        fh.write("t,gx,gy,gz,ax,ay,az\n0,0,0,0,0,0,9.81\n")
        fh.write("1" * (8 << 20) + "\n")
    (rc, err), peak = peak_memory(lambda: _run(capsys, str(f), "--out", str(tmp_path / "out")))
    assert rc == 2 and err == [f"attitude ahrs: error: {f}: line 3: longer than 1,048,576 bytes"], err
    assert peak < 6 << 20, peak  # one bounded piece (1 MiB) at a time, never the 8 MiB line


def test_a_long_header_is_cut_in_the_message(tmp_path: Path, capsys) -> None:
    f = tmp_path / "wide.csv"
    f.write_text(",".join(f"column{k}" for k in range(20_000)) + "\n1\n")
    rc, err = _run(capsys, str(f), "--out", str(tmp_path / "out"))
    assert rc == 2 and len(err) == 1 and len(err[0]) < 500, err[0][:600]
    assert err[0].startswith(f"attitude ahrs: error: {f}: the header lacks column(s) gx, gy, gz, ax, ay, az")


def test_messages_about_the_content_name_the_file(tmp_path: Path, capsys) -> None:
    rows = "".join(f"{k * 0.01},0,0,0,0,0,1.0\n" for k in range(100))  # the accelerometer in g
    f = tmp_path / "g.csv"
    f.write_text("t,gx,gy,gz,ax,ay,az\n" + rows)
    rc, err = _run(capsys, str(f), "--out", str(tmp_path / "out"))
    assert rc == 2 and err[0].startswith(f"attitude ahrs: error: {f}: the accelerometer looks like g"), err
