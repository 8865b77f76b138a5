"""`attitude sweep` bounds what a spec expands to, and its OS errors follow docs/cli.md (issue 29 item 12).

Each case failed on the main of 2026-11-28: `seeds = 1000000` over a 2-value grid took 2.6 GB
in 40 s of --dry-run with no output; `draws = 10**12` ended in numpy's ArrayMemoryError
traceback; TOML nested 100,000 deep in 3,002 lines of RecursionError; a read-only --out and
a full disk exited 2 (docs/cli.md: an OS error is 1 for every command), the full disk's
message naming the folder, not the file.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest
from conftest import _missing

from attitude_c import _io
from attitude_c.cli import EXIT_OS, EXIT_USAGE, main
from attitude_c.sim import sweeps


def _need_pandas() -> None:
    try:
        import pandas  # noqa: F401
    except ImportError:
        _missing("needs pandas: pip install -e '.[sweep]'")

SMALL = "[fixed]\nduration = 1\nsensors = \"ideal\"\n[grid]\nmethod = [\"rv1\", \"rv3\"]\n"


def _spec(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "s.toml"
    p.write_text(text)
    return p


def _err_line(capsys: pytest.CaptureFixture[str], after_the_count: bool = False) -> str:
    """The one error line (after the line saying how many runs the spec has, once it is read)."""
    err = capsys.readouterr().err.strip().splitlines()
    if after_the_count:
        assert len(err) == 2 and " runs, swept: " in err[0], err
        err = err[1:]
    assert len(err) == 1 and err[0].startswith("attitude sweep: error: "), err
    return err[0]


@pytest.mark.parametrize("text, count, factors", [
    ("[sweep]\nseeds = 1000000\n[grid]\nmethod = [\"rv1\", \"rv3\"]\n", "2,000,000",
     "2 method values × 1,000,000 seeds"),
    ("[random]\ndraws = 1000000000000\nber = {uniform = [0, 0.01]}\n", "1,000,000,000,000",
     "1,000,000,000,000 draws"),
])
def test_a_spec_of_too_many_runs_is_refused_with_its_count(tmp_path, capsys, text, count, factors) -> None:
    assert main(["sweep", str(_spec(tmp_path, text)), "--dry-run"]) == EXIT_USAGE
    line = _err_line(capsys)
    assert f"expands to {count} runs ({factors}), more than the limit of 100,000" in line
    assert "--max-runs" in line


def test_the_limit_is_counted_before_expanding_and_can_be_raised(tmp_path, capsys) -> None:
    spec = _spec(tmp_path, SMALL + "[sweep]\nseeds = 3\n")  # 2 × 3 = 6 runs
    with pytest.raises(sweeps.SpecError, match="expands to 6 runs"):
        sweeps.load_spec(spec, max_runs=5)
    assert len(sweeps.load_spec(spec, max_runs=6).runs) == 6
    # the count is of the spec, cut by --set and --seeds, before exclusions
    assert len(sweeps.load_spec(spec, max_runs=3, sets={"method": "rv3"}).runs) == 3
    assert main(["sweep", str(spec), "--dry-run", "--max-runs", "5", "--seeds", "2"]) == 0
    assert "4 runs" in capsys.readouterr().err
    assert main(["sweep", str(spec), "--dry-run", "--max-runs", "5"]) == EXIT_USAGE
    assert "expands to 6 runs" in _err_line(capsys)
    with pytest.raises(sweeps.SpecError, match="max_runs must be an integer >= 1"):
        sweeps.load_spec(spec, max_runs=0)


def test_toml_nested_too_deep_is_one_line(tmp_path, capsys) -> None:
    deep = "[fixed]\nv = " + "[" * 100_000 + "]" * 100_000 + "\n"
    assert main(["sweep", str(_spec(tmp_path, deep)), "--dry-run"]) == EXIT_USAGE
    assert "not valid TOML: arrays or tables nested too deep" in _err_line(capsys)
    # the same text as a --set value: the bare string, then refused as no option value
    assert main(["sweep", str(_spec(tmp_path, SMALL)), "--dry-run", "--set", "period=" + "[" * 5000]) == EXIT_USAGE
    assert "--set period" in _err_line(capsys)


def test_a_missing_spec_is_an_os_error(tmp_path, capsys) -> None:
    missing = tmp_path / "missing.toml"
    assert main(["sweep", str(missing), "--dry-run"]) == EXIT_OS
    assert f"{missing}: No such file or directory" in _err_line(capsys)


def test_a_full_disk_exits_1_naming_the_file(tmp_path, monkeypatch, capsys) -> None:
    """The disk fills as the first file of the sweep is flushed (ENOSPC from fsync,
    the OS boundary of attitude_c._io): before any run."""
    _need_pandas()
    real_fsync = os.fsync

    def fsync(fd: int) -> None:
        if os.readlink(f"/proc/self/fd/{fd}").endswith(".toml"):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real_fsync(fd)

    monkeypatch.setattr(_io.os, "fsync", fsync)
    out = tmp_path / "out"
    assert main(["sweep", str(_spec(tmp_path, SMALL)), "--serial", "--no-progress", "--out", str(out)]) == EXIT_OS
    assert f"attitude sweep: error: {out / 'spec.toml'}: No space left on device" == _err_line(capsys, True)
    assert not (out / "spec.toml").exists() and not (out / sweeps.JOURNAL).exists()


def test_an_unwritable_out_exits_1_naming_it(tmp_path, monkeypatch, capsys) -> None:
    """A read-only --out (as root, which writes through permissions, the filesystem's
    EROFS is raised at the OS boundary instead of mounting one)."""
    _need_pandas()
    ro = tmp_path / "ro"
    ro.mkdir(mode=0o555)
    if os.geteuid() == 0:
        real_mkdir = Path.mkdir

        def mkdir(self: Path, *a: object, **kw: object) -> None:
            if ro in self.parents:
                raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(self))
            real_mkdir(self, *a, **kw)  # type: ignore[arg-type]

        monkeypatch.setattr(Path, "mkdir", mkdir)
    out = ro / "run"
    assert main(["sweep", str(_spec(tmp_path, SMALL)), "--serial", "--no-progress", "--out", str(out)]) == EXIT_OS
    line = _err_line(capsys, True)
    assert line.startswith(f"attitude sweep: error: {out}: ") and ("Read-only" in line or "Permission" in line), line
