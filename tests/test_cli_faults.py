"""The ``attitude`` commands under OS faults and bad numbers (issue 17,
items 5, 6 and 7): one line and a documented exit status (docs/cli.md),
never a traceback; a closed stdout ends quietly; results complete or
absent; every numeric option validated by the one shared validator.

Faults are real where the machine allows: pseudo-terminals, closed pipes,
/dev/full, a 64 KiB tmpfs and a read-only tmpfs (mounting needs root; the
full-disk case is also run everywhere with ENOSPC raised by ``os.fsync``,
the OS boundary of attitude_c._io).
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import os
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
from conftest import ROOT

from attitude_c import _io
from attitude_c.cli import EXIT_OS, EXIT_PIPE, EXIT_USAGE, build_parser, main
from attitude_c.link.transport import PtyPair, open_port, run_receiver, run_sender

ENV = {**os.environ, "PYTHONPATH": str(ROOT)}
SIM = ["simulate", "--no-progress", "--no-plots", "--adc", "ideal", "--link", "none", "--sensors", "ideal"]


def _attitude(*argv: str, timeout: float = 60, **kw) -> subprocess.CompletedProcess:
    kw.setdefault("stdout", subprocess.PIPE)
    kw.setdefault("stderr", subprocess.PIPE)
    return subprocess.run([sys.executable, "-m", "attitude_c", *argv], text=True,
                          timeout=timeout, env=ENV, check=False, **kw)


def _one_line(proc: subprocess.CompletedProcess, rc: int, *needles: str) -> str:
    assert proc.returncode == rc, (proc.returncode, proc.stderr)
    assert "Traceback" not in proc.stderr and "Exception ignored" not in proc.stderr, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr
    for n in needles:
        assert n in lines[0], lines[0]
    return lines[0]


@contextlib.contextmanager
def _tmpfs(path: Path, opts: str) -> Iterator[Path]:
    path.mkdir()
    proc = subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(path)], capture_output=True,
                          check=False)
    if proc.returncode != 0:
        pytest.skip(f"needs root to mount a tmpfs ({proc.stderr.decode().strip()}); the fsync-ENOSPC "
                    "variant of this test runs everywhere")
    try:
        yield path
    finally:
        subprocess.run(["umount", str(path)], check=False)


# ---- item 5: closed stdout, full stdout, one-line OS errors -------------------

def _read_one_line_then_close(proc: subprocess.Popen) -> bytes:
    assert proc.stdout is not None
    line = proc.stdout.readline()
    proc.stdout.close()  # the reader goes away, as `| head -1` does
    return line


@pytest.mark.system
def test_link_tx_into_a_closed_pipe_ends_quietly() -> None:
    with PtyPair() as (p0, p1):
        stop = threading.Event()
        port_b = open_port(p1)
        rx = threading.Thread(target=run_receiver, args=(port_b,), kwargs={"stop": stop, "keep_blocks": False},
                              daemon=True)
        rx.start()
        try:
            tx = subprocess.Popen([sys.executable, "-m", "attitude_c", "link-tx", "--port", p0, "--generate",
                                   "--count", "100000"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=ENV)
            first = _read_one_line_then_close(tx)
            err = tx.communicate(timeout=60)[1].decode()
        finally:
            stop.set()
            rx.join(timeout=10)
            port_b.close()
    assert first.startswith(b"block 0 ")
    assert tx.returncode == EXIT_PIPE, err
    assert "Traceback" not in err and "BrokenPipe" not in err and "Exception ignored" not in err, err


@pytest.mark.system
def test_link_rx_into_a_closed_pipe_ends_quietly() -> None:
    with PtyPair() as (p0, p1):
        rx = subprocess.Popen([sys.executable, "-m", "attitude_c", "link-rx", "--port", p1],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=ENV)
        stop = threading.Event()
        port_a = open_port(p0)
        blocks = (bytes([k % 256, 1, 2, 3, 4, 5]) for k in range(100000))
        tx = threading.Thread(target=run_sender, args=(port_a, blocks), kwargs={"stop": stop}, daemon=True)
        tx.start()
        try:
            first = _read_one_line_then_close(rx)
            err = rx.communicate(timeout=60)[1].decode()
        finally:
            stop.set()
            tx.join(timeout=10)
            port_a.close()
    assert first.endswith(b" 01 02 03 04 05\n")  # a block (the first ones may predate the listener)
    assert rx.returncode == EXIT_PIPE, err
    assert "Traceback" not in err and "BrokenPipe" not in err and "Exception ignored" not in err, err


@pytest.mark.system
def test_stdout_on_a_full_device_is_one_line() -> None:
    with open("/dev/full", "w") as full:
        proc = _attitude("link-test", "--blocks", "50", "--json", stdout=full, stderr=subprocess.PIPE)
    _one_line(proc, EXIT_OS, "No space left on device", "standard output")


@pytest.mark.system
def test_port_that_does_not_exist_is_one_line() -> None:
    proc = _attitude("link-rx", "--port", "/dev/nonexistent-attitude-port")
    assert proc.returncode == EXIT_OS and "Traceback" not in proc.stderr


# ---- item 6: the output location checked first; results complete or absent ----

@pytest.mark.system
def test_simulate_out_is_a_file_fails_before_simulating(tmp_path: Path) -> None:
    f = tmp_path / "results"
    f.write_text("not a directory\n")
    # 10^5 simulated seconds (1.25e6 updates) take minutes: the answer comes before the run
    proc = _attitude(*SIM, "--duration", "100000", "--out", str(f), timeout=30)
    _one_line(proc, EXIT_OS, str(f), "not a directory")


@pytest.mark.system
def test_simulate_out_on_dev_full_is_one_line() -> None:
    proc = _attitude(*SIM, "--duration", "100000", "--out", "/dev/full", timeout=30)
    _one_line(proc, EXIT_OS, "/dev/full")


@pytest.mark.system
def test_simulate_unwritable_dir_fails_before_simulating(tmp_path: Path) -> None:
    if os.geteuid() == 0:  # root writes through permissions: a read-only filesystem instead
        ctx: contextlib.AbstractContextManager[Path] = _tmpfs(tmp_path / "ro", "ro,size=64k")
    else:
        d = tmp_path / "ro"
        d.mkdir(mode=0o555)
        ctx = contextlib.nullcontext(d)
    with ctx as d:
        proc = _attitude(*SIM, "--duration", "100000", "--out", str(d / "run"), timeout=30)
    _one_line(proc, EXIT_OS, str(d / "run"))


@pytest.mark.system
def test_simulate_on_a_full_filesystem_leaves_complete_files_or_none(tmp_path: Path) -> None:
    with _tmpfs(tmp_path / "small", "size=64k") as d:
        out = d / "run"
        # 60 s at 0.08 s: a ~95 kB CSV, more than the 64 KiB filesystem holds
        proc = _attitude(*SIM, "--duration", "60", "--out", str(out))
        line = _one_line(proc, EXIT_OS, "No space left on device", "timeseries.csv")
        assert "complete: none" in line and "not written: timeseries.csv, summary.json" in line
        # no truncated CSV, no temporary file; the directory made for the run removed, being empty
        assert not out.exists() and sorted(p.name for p in d.iterdir()) == []
        # a filesystem already full: refused before the run
        (d / "filler").write_bytes(b"\0" * 60_000)
        with contextlib.suppress(OSError):
            (d / "filler2").write_bytes(b"\0" * 8192)
        proc = _attitude(*SIM, "--duration", "100000", "--out", str(d / "run2"), timeout=30)
        _one_line(proc, EXIT_OS, "No space left on device", str(d / "run2"))


def test_simulate_disk_full_at_the_summary_names_complete_and_absent(tmp_path, monkeypatch, capsys) -> None:
    """Everywhere (no root needed): the disk fills while the summary is
    flushed (ENOSPC from fsync, the OS boundary of attitude_c._io)."""
    real_fsync = os.fsync
    calls = {"n": 0}

    def fsync(fd: int) -> None:
        if os.readlink(f"/proc/self/fd/{fd}").endswith(".json"):
            calls["n"] += 1
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real_fsync(fd)

    monkeypatch.setattr(_io.os, "fsync", fsync)
    out = tmp_path / "run"
    assert main([*SIM, "--duration", "4", "--method", "rv1", "--out", str(out)]) == EXIT_OS
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and calls["n"] == 1, err
    assert "complete: timeseries.csv; not written: summary.json" in err[0]
    assert sorted(p.name for p in out.iterdir()) == ["timeseries.csv"]
    text = (out / "timeseries.csv").read_text()
    assert text.endswith("\n") and len(text.splitlines()) == 1 + round(4 / 0.08)  # header + one rv1 update per 0.08 s


def test_atomic_path_removes_the_temporary_file_and_keeps_the_old_one(tmp_path: Path) -> None:
    f = tmp_path / "r.csv"
    f.write_text("old, complete\n")
    with pytest.raises(RuntimeError), _io.atomic_open(f) as fh:
        fh.write("new, half")
        raise RuntimeError("writer failed")
    assert f.read_text() == "old, complete\n"
    assert [p.name for p in tmp_path.iterdir()] == ["r.csv"]
    _io.write_text(f, "new\n")
    assert f.read_text() == "new\n"
    assert (f.stat().st_mode & 0o777) == 0o666 & ~_umask()


def _umask() -> int:
    m = os.umask(0)
    os.umask(m)
    return m


# ---- item 7: one validator for every numeric option ------------------------

def _numeric_options() -> list[tuple[str, str, str]]:
    """(command, option, converter name) of every option whose value is a number."""
    out = []
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for cmd, p in sub.choices.items():
        for a in p._actions:
            if not a.option_strings or a.type is None:
                continue
            assert a.type not in (int, float), f"{cmd} {a.option_strings[0]}: type={a.type.__name__}, " \
                "not the shared validator (attitude_c/cli/options.py)"
            name = getattr(a.type, "__name__", "")
            if name in ("number", "signed number", "integer", "triple"):
                out.append((cmd, a.option_strings[-1], name))
    return out


NUMERIC = _numeric_options()


def test_every_command_has_its_numeric_options_validated() -> None:
    cmds = {c for c, _, _ in NUMERIC}
    assert {"simulate", "link-rx", "link-tx", "link-test", "demo", "view"} <= cmds
    assert ("link-rx", "--duration", "number") in NUMERIC and ("link-rx", "--count", "integer") in NUMERIC


@pytest.mark.parametrize("cmd, option, kind", NUMERIC, ids=[f"{c} {o}" for c, o, _ in NUMERIC])
def test_numeric_option_rejects_nan_and_garbage(cmd: str, option: str, kind: str, capsys) -> None:
    bad = ["nan", "x", "inf"] if kind != "triple" else ["nan", "x", "1,2"]
    if kind in ("number", "integer"):
        bad.append("-5")  # these have a lower bound of 0 or more ("signed number": any sign, e.g. --turns)
    for value in bad:
        with pytest.raises(SystemExit) as ei:
            main([cmd, f"{option}={value}"])
        assert ei.value.code == EXIT_USAGE, (option, value)
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and option in err[0], err


@pytest.mark.parametrize("argv", [["--duration", "nan"], ["--count", "-5"], ["--duration", "-5"],
                                  ["--idle-eof", "-1"]], ids=lambda a: " ".join(a))
@pytest.mark.system
def test_link_rx_bad_limits_are_usage_errors_not_a_run(argv: list[str]) -> None:
    # before: --duration nan never ended; the others exited 0 at once
    proc = _attitude("link-rx", "--port", "loop://", *argv, timeout=20)
    _one_line(proc, EXIT_USAGE, argv[0])


def test_link_test_pair_options_use_the_validator(capsys) -> None:
    assert main(["link-test", "--blocks", "3", "--dead", "nan:1"]) == EXIT_USAGE
    assert "--dead START" in capsys.readouterr().err
    assert main(["link-test", "--blocks", "3", "--reboot", "1:nobody"]) == EXIT_USAGE
