"""attitude sweep (attitude_c.sim.sweeps): specs, engines, resume, failures.

The same small sweep runs serially (no Dask), on a local cluster of 2 worker
processes and through a scheduler started here on loopback (`dask
scheduler` + 2 `dask worker` processes): the tables must be identical, bit
for bit, because every run is a pure function of its parameters (seeded from
the spec). Resumption, a worker killed mid-run and failing runs are checked
against the same serial reference.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import numpy as np
import pytest
from conftest import _missing

from attitude_c.cli import main
from attitude_c.sim import options, sweeps


def _need_dask() -> None:
    for m in ("dask", "distributed", "pandas"):
        try:
            __import__(m)
        except ImportError:
            _missing(f"needs {m}: pip install -e '.[sweep]'")


# 5 runs of ~0.1 s each (0.5 s on a loaded 2-core box): methods x 2 seeds, and one run that raises at run time
# (the fixed-point integrator has no rk4: SimConfig.validate lets it through, the
# integrator refuses it)
SPEC = """
[sweep]
name = "small"
seeds = 2
[fixed]
duration = 12
period = 0.04
calibration = 1
[grid]
method = ["rv1", "rv3"]
[[cases]]
label = "full"
[[cases]]
label = "fixed-rk4"
precision = "fixed"
method = "rk4"
[[exclude]]
case = "fixed-rk4"
seed = 1
"""


def _write(tmp: Path, text: str, name: str = "spec.toml") -> Path:
    p = tmp / name
    p.write_text(text)
    return p


def _same(a, b) -> None:
    import pandas as pd

    cols = [c for c in a.columns if c != "elapsed_s"]  # wall time: the only field scheduling may change
    pd.testing.assert_frame_equal(a[cols].reset_index(drop=True), b[cols].reset_index(drop=True),
                                  check_exact=True)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    _need_dask()
    d = tmp_path_factory.mktemp("ref")
    spec = _write(d, SPEC)
    df = sweeps.sweep(spec, "serial", out=d / "out", plots=False)
    return spec, df


@pytest.fixture(scope="module")
def scheduler(tmp_path_factory):
    """`dask scheduler` + 2 `dask worker` processes on loopback, started and ended here."""
    _need_dask()
    from distributed import Client

    d = tmp_path_factory.mktemp("dask")
    sf = d / "scheduler.json"
    procs: list[subprocess.Popen] = []
    log = open(d / "dask.log", "w")  # noqa: SIM115 - closed at teardown

    def start(*args: str) -> None:
        procs.append(subprocess.Popen([sys.executable, "-m", "dask", *args], cwd=d, stdout=log,
                                      stderr=subprocess.STDOUT, start_new_session=True))

    try:
        start("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file", str(sf))
        deadline = time.monotonic() + 60
        addr = None
        while addr is None and time.monotonic() < deadline:
            try:
                addr = json.loads(sf.read_text())["address"]
            except (OSError, ValueError, KeyError):  # not there yet, or being written
                time.sleep(0.1)
        assert addr, (d / "dask.log").read_text()
        for i in range(2):
            start("worker", "--scheduler-file", str(sf), "--nthreads", "1", "--no-dashboard", "--name", f"w{i}")
        with Client(addr, timeout="30s") as c:
            c.wait_for_workers(2, timeout=60)
        yield addr
    finally:
        for p in reversed(procs):  # each in its own session: its group is ours to end
            try:
                os.killpg(p.pid, signal.SIGTERM)
                p.wait(15)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait(5)
            except ProcessLookupError:
                pass
        log.close()


#: The run the tests below hold in flight (:func:`_holding`): one that finishes without error.
HELD = {"case": "full", "method": "rv3", "seed": 1}


class _Held:
    """A run of a sweep held in flight on the loopback cluster (:func:`_holding`)."""

    def __init__(self, client, tag: str) -> None:
        from distributed import Event, Queue

        self._started = Queue(f"started-{tag}", client=client)
        self._release = Event(f"release-{tag}", client=client)

    def started(self) -> int:
        """Wait until a worker is running the held run; its worker process's pid."""
        return int(self._started.get(timeout=120))  # a failure guard: the run is waited for, not a time

    def release(self) -> None:
        """Let the held run (and every later attempt at it) go on."""
        self._release.set()


@contextlib.contextmanager
def _holding(client, **match):
    """Inside: the run whose parameters include ``match`` waits, on whichever worker of
    the loopback cluster runs it, until ``release()``; each attempt at it first puts its
    worker process's pid on the ``started`` queue. A test then acts while that run is in
    flight (kills its worker, or the client) instead of at a moment it hopes to catch.

    Installed on every worker with ``Client.run`` (functions defined here so that they
    pickle by value: the workers cannot import this module): ``sweeps._run_simulate``,
    which ``run_chunk`` looks up at each run, is wrapped; released and removed on exit
    (a worker its nanny restarted starts without it)."""
    tag = uuid.uuid4().hex

    def install(tag: str, match: dict) -> None:
        import os

        from distributed import Event, Queue

        from attitude_c.sim import sweeps as sw

        run = sw._run_simulate

        def held(params):
            if all(params.get(k) == v for k, v in match.items()):
                Queue(f"started-{tag}").put(os.getpid())
                Event(f"release-{tag}").wait()
            return run(params)

        held.unheld = run
        sw._run_simulate = held

    def remove() -> None:
        from attitude_c.sim import sweeps as sw

        sw._run_simulate = getattr(sw._run_simulate, "unheld", sw._run_simulate)

    hold = _Held(client, tag)
    client.run(install, tag, match)
    try:
        yield hold
    finally:
        hold.release()  # a held run left waiting would keep its worker's only thread
        client.run(remove)


# ---------------------------------------------------------------------------
# specs
# ---------------------------------------------------------------------------

def test_expansion_keys_and_draws(tmp_path):
    spec = _write(tmp_path, """
[sweep]
seeds = [3, 4]
[fixed]
duration = 2
[grid]
method = ["rv1", "rv2", "rk4"]
[random]
draws = 3
seed = 7
ber = {log_uniform = [1e-5, 1e-3]}
oversample = {int = [1, 16]}
[[exclude]]
method = "rk4"
""")
    s = sweeps.load_spec(spec)
    assert len(s.runs) == 2 * 3 * 2  # methods (rk4 excluded) x draws x seeds
    assert len({r.key for r in s.runs}) == len(s.runs)
    assert s.axes == ["method", "ber", "oversample"] and s.random_axes == ["ber", "oversample"]
    assert [r.params["seed"] for r in s.runs[:2]] == [3, 4]
    again = sweeps.load_spec(spec)  # the draws come from the spec alone
    assert [r.params for r in again.runs] == [r.params for r in s.runs]
    bers = {r.params["ber"] for r in s.runs}
    assert len(bers) == 3 and all(1e-5 <= b <= 1e-3 for b in bers)
    assert all(isinstance(r.params["oversample"], int) and 1 <= r.params["oversample"] <= 16 for r in s.runs)
    # a run's key is its parameters: where the spec sets them and in which form does not matter
    a = sweeps.load_spec({"fixed": {"period": 0.04, "cone-angle": "10"}, "grid": {"method": ["rv3"]}})
    b = sweeps.load_spec({"grid": {"method": ["rv3"], "period": [0.04]}, "fixed": {"cone_angle": 10}})
    assert [r.key for r in a.runs] == [r.key for r in b.runs]
    c = sweeps.load_spec({"grid": {"method": ["rv3"], "period": [0.08]}})
    assert c.runs[0].key != b.runs[0].key
    # a repeatable option: a string is one occurrence, a list of strings several; the run's
    # (canonical) parameters parse back to the same values on the worker
    d = sweeps.load_spec({"fixed": {"mag": "hmr3000", "duration": 20},
                          "grid": {"disturbance": ["5,8,20,0,0", ["5,8,20,0,0", "12,14,0,10,0,1,nav"]]}})
    assert [len(r.params["disturbance"]) for r in d.runs] == [1, 2]
    assert options.parse(d.runs[1].params)["disturbance"] == [
        (5.0, 8.0, (20.0, 0.0, 0.0), 0.0, "body"), (12.0, 14.0, (0.0, 10.0, 0.0), 1.0, "nav")]


CUT = """
[sweep]
seeds = 3
[fixed]
duration = 4
calibration = 1
adc = "ideal"
[grid]
method = ["rv1", "rv3"]
period = [0.02, 0.04]
[random]
draws = 2
ber = {log_uniform = [1e-6, 1e-4]}
attempts = {int = [2, 9]}
"""


def test_set_seeds_and_limit_cut_a_spec_down_without_editing_it(tmp_path, capsys):
    """--set pins a parameter over the grid and the draws (the other draws unchanged),
    --seeds replaces the seed list, --limit keeps the first runs in spec order; each
    goes through the spec's own checks, and an error names the key."""
    spec = _write(tmp_path, CUT)
    full = sweeps.load_spec(spec)
    assert len(full.runs) == 2 * 2 * 2 * 3 and full.axes == ["method", "period", "attempts", "ber"]
    cut = sweeps.load_spec(spec, sets={"period": 0.01, "ber": 0.0})
    assert len(cut.runs) == 2 * 2 * 3 and cut.axes == ["method", "attempts"] and cut.random_axes == ["attempts"]
    assert {(r.params["period"], r.params["ber"]) for r in cut.runs} == {(0.01, 0.0)}
    # the draws of the parameters left are those of the whole spec (every draw is still made)
    assert [r.params["attempts"] for r in cut.runs] == [r.params["attempts"] for r in full.runs
                                                        if r.params["period"] == 0.02]
    assert [r.params["seed"] for r in sweeps.load_spec(spec, seeds=[7]).runs] == [7] * 8
    assert {r.params["seed"] for r in sweeps.load_spec(spec, seeds=2).runs} == {0, 1}
    assert sweeps.load_spec(spec, limit=3).axes == []  # the first point's first draw over the 3 seeds
    first = sweeps.load_spec(spec, limit=4)
    assert [r.key for r in first.runs] == [r.key for r in full.runs[:4]]
    assert first.axes == ["attempts", "ber"]  # ... and the second draw's first seed
    for argv, line in [
        (["--set", "perod=1"], "--set perod: not an option of attitude simulate"),
        (["--set", "period=-1"], "--set period: --period: must be a finite number > 0, got -1"),
        (["--set", "method=rv9"], "--set method: --method: invalid choice: 'rv9'"),
        (["--set", "seed=3"], "--set seed: the sweep sets the seed"),
        (["--set", "sensors=ideal"], "needs the sensor chain"),  # with the spec's ber: the combination check
        (["--set", "period"], "argument --set: --set expects NAME=VALUE, got 'period'"),
        (["--seeds", "0"], "argument --seeds: give a count >= 1 or a list of integers >= 0"),
        (["--seeds", "1,x"], "argument --seeds: give a count >= 1"),
        (["--limit", "0"], "argument --limit: must be"),
    ]:
        try:
            rc = main(["sweep", str(spec), "--dry-run", *argv])
        except SystemExit as exc:  # argparse's own usage errors
            rc = exc.code
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 2 and len(err) == 1 and line in err[0], (argv, err)
    # the command: the cut spec runs, and the spec.toml left in the folder says how it was cut
    out = tmp_path / "out"
    assert main(["sweep", str(spec), "--serial", "--no-plots", "--no-progress", "--out", str(out),
                 "--set", "duration=2", "--set", "method=rv3", "--seeds", "5,", "--limit", "3"]) == 0
    import pandas as pd

    df = pd.read_csv(out / "runs.csv")
    assert len(df) == 3 and (df["duration"] == 2).all() and (df["method"] == "rv3").all()
    assert (df["seed"] == 5).all() and (df["error"].isna()).all()
    assert (out / "spec.toml").read_text().endswith(
        '# run with: --set duration=2 --set method="rv3" --seeds [5] --limit 3\n')


def _plot_table(spec):
    """A table of the spec's runs with a known figure per run (no simulation): 1e-3 x the
    run's index + 1, so every point's median over the seeds is known."""
    import pandas as pd

    rows = [{**r.params, "err_attitude_angle_rms": 1e-3 * (i + 1), "total_deg": 0.1 * (i + 1)}
            for i, r in enumerate(spec.runs)]
    return pd.DataFrame(rows)


def test_plots_label_units_and_join_no_categories(tmp_path):
    """A sweep's plot: axes labelled with their units; over a category (method) markers
    and 5–95 % bars at the medians and no line between the categories; over a number
    (period) a line through the medians."""
    _need_dask()
    import matplotlib.pyplot as plt

    spec = sweeps.load_spec(_write(tmp_path, CUT), sets={"ber": 0.0, "attempts": 5})
    df = _plot_table(spec)
    fig = sweeps.plot_axis(df, spec, "method")
    try:
        axes = [ax for ax in fig.axes if ax.get_visible()]
        assert len(axes) == 1  # one other swept parameter (period): one line each, no panels
        ax = axes[0]
        assert ax.get_xlabel() == "method" and ax.get_ylabel() == "err_attitude_angle_rms (rad)"
        assert ax.lines and all(ln.get_linestyle() == "None" for ln in ax.lines)  # markers and caps only
        assert not ax.collections or all(type(c).__name__ == "LineCollection" for c in ax.collections)  # bars
        for period in (0.02, 0.04):
            med = df[df["period"] == period].groupby("method", sort=False)["err_attitude_angle_rms"].median()
            (bars,) = [c for c in ax.containers if c.get_label() == f"period={period}"]
            np.testing.assert_allclose(bars.lines[0].get_ydata(), med.to_numpy(), rtol=1e-12)
    finally:
        plt.close(fig)
    fig = sweeps.plot_axis(df, spec, "period")
    try:
        ax = fig.axes[0]
        assert ax.get_xlabel() == "period (s)"
        assert any(ln.get_linestyle() == "-" for ln in ax.lines)  # a number: the medians joined
    finally:
        plt.close(fig)
    assert sweeps.unit_of(spec, "cone_angle") == "°" and sweeps.unit_of(spec, "cone_frequency") == "Hz"
    assert sweeps.unit_of(spec, "turntable_rate") == "°/s" and sweeps.unit_of(spec, "ber") is None
    assert sweeps.unit_of(spec, "field") is None  # µT and degrees: no one unit
    assert sweeps.unit_of(spec, "link_time_s") == "s" and sweeps.unit_of(spec, "updates") is None
    rec = sweeps.Spec(name="r", kind="recordings", runs=[], axes=[], random_axes=[], over=[], figure="total_deg")
    assert sweeps.unit_of(rec, "total_deg") == "°" and sweeps.unit_of(rec, "estimator_bias_rad_s_2") == "rad/s"


def test_every_simulate_option_is_sweepable_with_no_change_here(monkeypatch, capsys):
    """The option set is the simulator's option table (attitude_c/sim/options.py), which
    `attitude simulate`'s parser is made from: an option added there is on the command
    line and can be swept as it is."""
    opts = sweeps.simulate_options()
    assert {"method", "period", "ber", "gyro", "oversample", "cone_angle", "trajectory_file"} <= set(opts)
    assert main(["sweep", "--list-options"]) == 0
    listed = capsys.readouterr().out
    assert "cone_angle       --cone-angle" in listed and "  integrator" in listed
    assert not {"out", "seed", "budget", "json", "no_plots"} & set(opts)  # the sweep sets the seed; how, not what
    new = options.Option("acc_noise", "a new option", options.SYSTEM, 0.0, options.real("--acc-noise"))
    monkeypatch.setattr(options, "OPTIONS", (*options.OPTIONS, new))
    s = sweeps.load_spec({"fixed": {"duration": 1}, "grid": {"acc-noise": [0.1, 0.2]}})
    assert [r.params["acc_noise"] for r in s.runs] == [0.1, 0.2]
    assert options.parse(s.runs[1].params)["acc_noise"] == 0.2
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    assert "--acc-noise" in capsys.readouterr().out


@pytest.mark.parametrize("text, words", [
    ("[grid]\nperod = [0.1]\n", "perod: not an option"),
    ("[grid]\nperiod = [-1]\n", "must be a finite number > 0"),
    ("[grid\n", "not valid TOML"),
    ("[grid]\nseed = [1, 2]\n", "the sweep sets the seed"),
    ("[random]\ndraws = 2\nber = {gauss = [0, 1]}\n", "give one distribution"),
    ("[fixed]\nsensors = \"ideal\"\nber = 1e-3\n", "needs the sensor chain"),
    ("[sweep]\nkind = \"recordings\"\n[grid]\nestimator = [\"nope\"]\n", "'nope' is not registered"),
    ("[sweep]\nkind = \"recordings\"\n[grid]\nmetod = [\"rv1\"]\n", "has no setting 'metod'"),
    ("[sweep]\nseeds = 0\n", "seeds must be"),
    ("[swep]\n", "unknown section"),
])
def test_spec_errors_are_one_line_and_exit_2(tmp_path, capsys, text, words):
    rc = main(["sweep", str(_write(tmp_path, text)), "--dry-run"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and words in err[0] and err[0].startswith("attitude sweep: error: "), err
    assert main(["sweep", str(tmp_path / "missing.toml")]) == 1  # an OS error (docs/cli.md)
    assert "missing.toml: No such file or directory" in capsys.readouterr().err


@pytest.mark.parametrize("argv, code, line", [
    ([], 2, "give a SPEC file (or --list-options)"),
    (["SPEC", "--serial", "--workers", "2"], 2, "--serial runs in this process: drop --scheduler/--workers"),
    (["SPEC", "--scheduler", "tcp://x:1", "--workers", "2"], 2,
     "--workers sizes the local cluster: an existing scheduler has its own workers"),
])
def test_argument_errors_are_one_line(tmp_path, capsys, argv, code, line):
    spec = str(_write(tmp_path, "[grid]\nperiod = [0.1]\n"))
    assert main(["sweep", *(spec if a == "SPEC" else a for a in argv)]) == code
    assert capsys.readouterr().err == f"attitude sweep: error: {line}\n"


@pytest.mark.parametrize("exc, code, line", [
    (ImportError("needs dask: pip install dask"), 3, "error: needs dask: pip install dask"),
    (ValueError("another sweep holds the folder"), 2, "error: another sweep holds the folder"),
    (ConnectionError("no scheduler at tcp://x:1"), 3, "error: no scheduler at tcp://x:1"),
    # an OS error is 1, as for every command (docs/cli.md; it was 2 until issue 29 item 12)
    (PermissionError(13, "Permission denied", "/x/runs.csv"), 1, "error: /x/runs.csv: Permission denied"),
    (PermissionError(13, "Permission denied"), 1, "error: OUT: Permission denied"),
    (KeyboardInterrupt(), 130,
     "interrupted: 0 of 1 runs are recorded in OUT/; rerun the same command to resume"),
])
def test_engine_errors_are_one_line_with_their_exit_code(tmp_path, capsys, monkeypatch, exc, code, line):
    # what sweeps.sweep may raise, and the one line and exit code each becomes (docs/sweep.md)
    def raise_it(*_a, **_k):
        raise exc

    monkeypatch.setattr(sweeps, "sweep", raise_it)
    out = tmp_path / "out"
    rc = main(["sweep", str(_write(tmp_path, "[grid]\nperiod = [0.1]\n")), "--serial", "--out", str(out)])
    err = capsys.readouterr().err.splitlines()
    assert rc == code
    assert err[1:] == [f"attitude sweep: {line.replace('OUT', str(out))}"], err


def test_a_spec_that_needs_a_missing_package_exits_3(tmp_path, capsys, monkeypatch):
    def raise_it(*_a, **_k):
        raise ImportError("needs pandas: pip install pandas")

    monkeypatch.setattr(sweeps, "load_spec", raise_it)
    assert main(["sweep", str(_write(tmp_path, "[grid]\nperiod = [0.1]\n"))]) == 3
    assert capsys.readouterr().err == "attitude sweep: error: needs pandas: pip install pandas\n"


# ---------------------------------------------------------------------------
# engines: the same table everywhere
# ---------------------------------------------------------------------------

def test_serial_reference_records_the_failing_run(reference):
    _spec, df = reference
    assert len(df) == 5
    bad = df[df["case"] == "fixed-rk4"]
    assert len(bad) == 1 and "does not implement method 'rk4'" in bad["error"].iloc[0]
    assert bad["err_attitude_angle_rms"].isna().all()
    ok = df[df["case"] == "full"]
    assert (ok["error"] == "").all() and (ok["err_attitude_angle_rms"] > 0).all()
    # seeds change the noise; methods see the same noise (common random numbers)
    rv1 = ok[ok["method"] == "rv1"]["err_attitude_angle_rms"].to_numpy()
    assert rv1[0] != rv1[1]
    out = Path(df.attrs["out"])
    assert df.attrs["failed"] == 1 and df.attrs["executed"] == 5
    import pandas as pd

    summ = pd.read_csv(out / "summary.csv")
    assert summ.columns[-9:].tolist() == ["runs", "n", "mean", "std", "min", "p5", "p50", "p95", "max"]
    fig = summ[summ["figure"] == "err_attitude_angle_rms"]
    assert len(fig) == 3 and fig["runs"].tolist() == [2, 2, 1]  # rv1, rv3 over 2 seeds; the failing run
    got = fig[fig["n"] > 0]
    assert got[["mean", "p5", "p50", "p95"]].notna().all().all()
    rv3 = ok[ok["method"] == "rv3"]["err_attitude_angle_rms"]
    row = got[got["method"] == "rv3"].iloc[0]
    assert row["mean"] == pytest.approx(rv3.mean(), rel=1e-12) and row["min"] <= row["p50"] <= row["max"]


@pytest.mark.system
def test_local_cluster_of_2_processes_gives_the_same_table(reference, tmp_path):
    spec, ref = reference
    df = sweeps.sweep(spec, None, workers=2, out=tmp_path / "out")
    assert df.attrs["engine"].startswith("local cluster, 2 worker")
    _same(df, ref)
    assert {p.name for p in (tmp_path / "out").iterdir()} >= {
        "runs.csv", "summary.csv", "spec.toml", "runs.jsonl", "err_attitude_angle_rms-vs-method.png",
        "err_attitude_angle_rms-vs-case.png"}
    import pandas as pd

    _same(pd.read_csv(tmp_path / "out" / "runs.csv", keep_default_na=False, na_values=[""]).fillna({"error": ""}),
          ref.fillna({"error": ""}))


@pytest.mark.system
def test_external_scheduler_gives_the_same_table(reference, scheduler, tmp_path, capsys):
    spec, ref = reference
    rc = main(["sweep", str(spec), "--scheduler", scheduler, "--out", str(tmp_path / "out"), "--no-plots"])
    err = capsys.readouterr().err
    assert rc == 1 and "1 run(s) raised" in err, err  # finished, one run recorded as failed; else all it said
    import pandas as pd

    df = pd.read_csv(tmp_path / "out" / "runs.csv", keep_default_na=False, na_values=[""])
    _same(df.fillna({"error": ""}), ref.fillna({"error": ""}))


@pytest.mark.system
def test_worker_killed_mid_run_is_retried_by_the_engine(reference, scheduler, tmp_path):
    from distributed import Client

    spec, ref = reference
    result: dict = {}

    def run() -> None:
        try:
            result["df"] = sweeps.sweep(spec, scheduler, out=tmp_path / "o", plots=False)
        except BaseException as exc:  # noqa: BLE001 - raised again below, in the test's thread
            result["exc"] = exc

    with Client(scheduler, timeout="30s") as watch:
        with _holding(watch, **HELD) as held:
            t = threading.Thread(target=run)
            t.start()
            try:
                pid = held.started()  # the run is in flight on that worker process, and stays so
                os.kill(pid, signal.SIGKILL)  # the worker process, mid-run (its nanny restarts it)
            finally:
                held.release()  # the engine's retry of the lost run goes through
                t.join()
        watch.wait_for_workers(2, timeout=60)  # the nanny brought it back
    if "exc" in result:
        raise result["exc"]
    df = result["df"]
    # the lost run was run again, elsewhere, to the same result: its first attempt could
    # record nothing (killed while held), so its row is the retry's
    _same(df, ref)
    assert df.attrs["failed"] == 1  # only the run that raises by design


# ---------------------------------------------------------------------------
# resume
# ---------------------------------------------------------------------------

@pytest.mark.system
def test_interrupted_sweep_resumes_running_only_the_missing_runs(reference, scheduler, tmp_path):
    """The command is killed (SIGKILL: no clean-up at all) mid-sweep on the loopback
    cluster -- one run held in flight, so the sweep cannot be over, and at least one
    recorded -- then run again serially: only the runs it has no record of run."""
    from distributed import Client

    spec, ref = reference
    out = tmp_path / "out"
    journal = out / sweeps.JOURNAL
    env = {**os.environ, "MPLBACKEND": "Agg"}
    with Client(scheduler, timeout="30s") as watch, _holding(watch, **HELD) as held:
        p = subprocess.Popen([sys.executable, "-m", "attitude_c", "sweep", str(spec), "--scheduler", scheduler,
                              "--out", str(out), "--no-plots", "--no-progress"], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, env=env, start_new_session=True)
        try:
            held.started()  # the held run is in flight: the sweep cannot finish
            deadline = time.monotonic() + 120  # a failure guard: the other runs do finish
            while p.poll() is None and time.monotonic() < deadline and not (
                    journal.exists() and journal.read_bytes().count(b"\n") >= 1):
                time.sleep(0.02)
        finally:
            with contextlib.suppress(ProcessLookupError):  # gone already only if it failed
                os.killpg(p.pid, signal.SIGKILL)  # the command, mid-sweep
            p.wait()
    done = journal.read_bytes().count(b"\n") if journal.exists() else 0
    assert 1 <= done < len(ref), f"{done} runs recorded before the kill: the test needs some, not all; " \
        f"{p.stderr.read().decode()}"
    with open(journal, "ab") as f:  # a line torn by the kill
        f.write(b'{"key": "abc", "params": {"dur')
    df = sweeps.sweep(spec, "serial", out=out, plots=False)
    assert df.attrs["reused"] == done and df.attrs["executed"] == len(ref) - done
    _same(df, ref)
    keys = [json.loads(line)["key"] for line in journal.read_text().splitlines()]
    assert sorted(keys) == sorted(ref["key"])  # every run recorded once: none ran twice
    again = sweeps.sweep(spec, "serial", out=out, plots=False)
    assert again.attrs["executed"] == 0
    with open(out / ".sweep.lock", "a") as held:  # another sweep writing the folder
        import fcntl

        fcntl.flock(held.fileno(), fcntl.LOCK_EX)
        with pytest.raises(sweeps.InvalidArgument, match="another sweep is running"):
            sweeps.sweep(spec, "serial", out=out, plots=False)
    retried = sweeps.sweep(spec, "serial", out=out, plots=False, retry_failed=True)
    assert retried.attrs["executed"] == 1  # the failed run, on request
    _same(retried, ref)


# ---------------------------------------------------------------------------
# recordings: an estimator over BROAD-format trials
# ---------------------------------------------------------------------------

def _synthetic_trial(folder: Path, name: str, rate_dps=(0.0, 0.0, 30.0), n=900, hz=100.0) -> None:
    """A BROAD-format .mat: constant body rate from a tilted start, the exact attitude as reference."""
    from scipy.io import savemat

    w = np.radians(rate_dps)
    t = np.arange(n) / hz
    q0 = np.array([math.cos(0.2), math.sin(0.2), 0.0, 0.0])
    ang = np.linalg.norm(w) * t
    ax = w / np.linalg.norm(w)
    dq = np.c_[np.cos(ang / 2), np.sin(ang / 2)[:, None] * ax]
    w0, v0 = q0[0], q0[1:]
    q = np.c_[w0 * dq[:, 0] - dq[:, 1:] @ v0,
              w0 * dq[:, 1:] + dq[:, :1] * v0 + np.cross(v0, dq[:, 1:])]  # q0 ⊗ dq(t): body-frame rate
    quat = q.copy()
    quat[:5] = np.nan  # markers lost at the start: the integrator starts at the first valid sample
    savemat(folder / f"{name}.mat", {"imu_gyr": np.tile(w, (n, 1)), "imu_acc": np.zeros((n, 3)),
                                     "imu_mag": np.zeros((n, 3)), "opt_quat": quat,
                                     "movement": np.ones((n, 1)), "sampling_rate": np.array([[hz]])})


def test_recordings_kind_with_the_integrator_and_a_registered_estimator(tmp_path):
    _need_dask()
    pytest.importorskip("scipy", reason="scipy is a test dependency: pip install -e '.[test]'")
    data = tmp_path / "data"
    data.mkdir()
    _synthetic_trial(data, "const_z", (0.0, 0.0, 30.0))
    _synthetic_trial(data, "const_xyz", (10.0, -20.0, 15.0))

    def reference_itself(trial, fail: bool = False):
        if fail:
            raise RuntimeError("asked to fail")
        return trial.quat  # (N, 4), one per sample: the error is exactly zero where defined

    sweeps.register_estimator("test-reference", reference_itself)
    try:
        spec = _write(tmp_path, """
[sweep]
kind = "recordings"
data = "data"
[grid]
method = ["rv1", "rv3", "rk4"]
precision = ["f64", "f32"]
[[exclude]]
method = "rk4"
precision = "f32"
""")
        one = sweeps.load_spec(spec, sets={"trial": "const_z", "method": "rv3"})  # --set: one trial, one method
        assert [(r.params["trial"], r.params["method"], r.params["precision"]) for r in one.runs] == [
            ("const_z", "rv3", "f64"), ("const_z", "rv3", "f32")]
        df = sweeps.sweep(spec, "serial", out=tmp_path / "out", plots=False)
        assert len(df) == 2 * 5 and (df["error"] == "").all()
        # constant rate: every method is exact up to rounding; the trapezoid of a constant rate is exact
        f64 = df[df["precision"] == "f64"]
        # float64 rounding of <= 900 updates is ~1e-13 rad, but BROAD's metric (2 acos|e_w|) resolves
        # angles only to 2 sqrt(2 * 2^-52) = 4.2e-8 rad = 2.4e-6 deg (tests/test_broad.py): that is the bound
        assert (f64["total_deg"] < 2.5e-6).all(), f64[["trial", "method", "total_deg"]]
        f32 = df[df["precision"] == "f32"]
        # float32: ~6e-8 rad per update (2^-24) over <= 900 updates, growing at most linearly: < 6e-5 rad = 3e-3 deg
        assert (f32["total_deg"] < 3e-3).all(), f32[["trial", "method", "total_deg"]]
        assert (df["samples"] > 0).all()

        est = sweeps.sweep({"sweep": {"kind": "recordings", "data": str(data), "trials": ["const_z"]},
                            "grid": {"estimator": ["test-reference"], "fail": [False, True]}},
                           "serial", out=tmp_path / "out2", plots=False)
        assert est["total_deg"].iloc[0] == 0.0
        assert "RuntimeError: asked to fail" in est["error"].iloc[1]
    finally:
        sweeps.ESTIMATORS.pop("test-reference", None)


def test_recordings_on_a_shipped_broad_trial(tmp_path):
    _need_dask()
    pytest.importorskip("scipy", reason="scipy is a test dependency: pip install -e '.[test]'")
    from attitude_c import broad

    if broad.default_dir() is None:
        _missing("needs the BROAD subset in ../shared/data/broad")
    df = sweeps.sweep({"sweep": {"kind": "recordings", "trials": ["01_undisturbed_slow_rotation_A"]},
                       "grid": {"method": ["rv3"]}}, "serial", out=tmp_path / "out", plots=False)
    assert (df["error"] == "").all()
    assert np.isfinite(df[["total_deg", "heading_deg", "inclination_deg"]].to_numpy()).all()


def test_recordings_the_attitude_filter_on_a_shipped_broad_trial(tmp_path):
    """The filter is registered: a settings grid over a BROAD trial, settings checked by name."""
    _need_dask()
    pytest.importorskip("scipy", reason="scipy is a test dependency: pip install -e '.[test]'")
    from attitude_c import broad

    if broad.default_dir() is None:
        _missing("needs the BROAD subset in ../shared/data/broad")
    trial = "01_undisturbed_slow_rotation_A"
    df = sweeps.sweep({"sweep": {"kind": "recordings", "trials": [trial]},
                       "grid": {"estimator": ["ahrs"], "acc_noise": [0.025, 0.1]}},
                      "serial", out=tmp_path / "out", plots=False)
    assert (df["error"] == "").all() and len(df) == 2
    # the sweep's figure is BROAD's metric of the filter's own batch call (same data, same settings)
    t = broad.load_trial(broad.default_dir() / f"{trial}.mat")
    from attitude_c.ahrs_filter import ahrs

    for acc_noise, total in zip(df["acc_noise"], df["total_deg"]):
        q = ahrs(t.gyr, t.acc, t.mag, rate=t.rate, acc_noise=acc_noise)
        ref = broad.errors(q, t.quat, t.movement).total
        assert total == pytest.approx(ref, rel=1e-12)
        assert total < 5.0  # the filter, not a drifting integrator (~31° on BROAD, issue 14)
    with pytest.raises(sweeps.SpecError, match="has no setting 'acc_nois'"):
        sweeps.sweep({"sweep": {"kind": "recordings", "trials": [trial]},
                      "grid": {"estimator": ["ahrs"], "acc_nois": [0.1]}}, "serial",
                     out=tmp_path / "out2", plots=False)
