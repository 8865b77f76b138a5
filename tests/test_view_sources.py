"""attitude view's sources: attitude-rx's lines, recordings (JSON Lines, CSV,
BROAD .mat) replayed at a speed, the serial link's records through the block
decoder and an estimator (and a real pty carrying the link protocol), and
the simulator adapter. Attitudes are checked against closed forms (constant
body rate: q(t) = q0 ⊗ q(ω t)) or the NumPy reference, never against the
code under test."""

from __future__ import annotations

import csv
import io
import json
import math
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import attitude_c
from attitude_c import reference
from attitude_c.errors import InvalidArgument
from attitude_c.link import block
from attitude_c.view import sources
from attitude_c.view.estimators import ESTIMATORS, make_estimator
from attitude_c.view.stream import Hub, Recorder

DEG = math.pi / 180


def _drain(hub: Hub, until, timeout: float = 20.0) -> None:
    """Tick the hub until ``until()`` or the timeout."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        hub.tick()
        if until():
            hub.tick()
            return
        time.sleep(0.01)
    raise AssertionError("timed out waiting for the source")


def _recording(hub: Hub) -> list[dict[str, str]]:
    path, size = hub.recorder.snapshot().result(timeout=10)
    with open(path, encoding="utf-8") as fh:
        return list(csv.DictReader(io.StringIO(fh.read(size))))


def _q(rows: list[dict[str, str]], prefix: str = "") -> np.ndarray:
    return np.array([[float(r[f"{prefix}q{i}"]) for i in range(4)] for r in rows])


def _same_attitude(a: np.ndarray, b: np.ndarray, tol: float) -> None:
    """Quaternions equal up to sign, within tol per component."""
    s = np.sign(np.sum(a * b, axis=1))[:, None]
    np.testing.assert_allclose(a * s, b, atol=tol)


# attitude-rx's JSON Lines, as printed by csrc/app/attitude_rx.c
RX_LINES = [
    '{"t":0,"report":"BOOT","version":1,"period_ticks":72,"period_s":0.02,"baud":9600,"period_used_s":0.02}',
    ('{"t":0.06,"n":2,"codes":[2100,2048,2000],"q":[0.99999,0.001,0,-0.0009],"yaw_deg":0.1,"pitch_deg":0.11,'
     '"roll_deg":-0.05,"heading_deg":359.9,"held":0}'),
    '{"t":0.08,"report":"OVERRUN","first":4,"count":1,"slip":0}',
    '{"t":0.1,"error":"code","n":5,"codes":[5000,2048,2048]}',
    ('{"t":0.12,"n":5,"codes":[2100,2048,2000],"q":[0.99998,0.002,0,-0.0018],"yaw_deg":0.2,"pitch_deg":0.22,'
     '"roll_deg":-0.1,"heading_deg":359.8,"held":2}'),
    '{"link":{"naks":3,"timeouts":1}}',
]


def test_line_reader_understands_attitude_rx_jsonl() -> None:
    r = sources.LineReader()
    out = [r.feed(ln) for ln in RX_LINES]
    assert [p.kind for p in out] == ["event", "sample", "event", "event", "sample", "counters"]
    assert out[0].event == "BOOT" and out[0].detail["period_s"] == 0.02 and out[0].t == 0
    s = out[1].sample
    assert s[0] == 0.06 and s[1] == 2 and s[2:6] == (0.99999, 0.001, 0, -0.0009)
    assert s[13:17] == pytest.approx((0.1 * DEG, 0.11 * DEG, -0.05 * DEG, 359.9 * DEG))
    assert math.isnan(s[6]) and math.isnan(s[9])  # no rates, no truth: the hub completes / leaves them
    assert out[3].event == "error" and out[3].detail == {"error": "code", "n": 5, "codes": [5000, 2048, 2048]}
    assert out[4].counters == {"held": 2} and out[5].counters == {"naks": 3, "timeouts": 1}
    for bad, why in (("{not json", "not JSON"), ('{"t":1,"q":[1,0,0]}', "list of 4"), ("[1,2]", "not a JSON object")):
        with pytest.raises((ValueError, TypeError), match=why):
            r.feed(bad)
    assert r.feed("   ").kind == "skip" and r.feed("# comment").kind == "skip"


def test_line_reader_understands_csv_headers() -> None:
    r = sources.LineReader()  # attitude-rx's CSV
    assert r.feed("t,n,code_x,code_y,code_z,q0,q1,q2,q3,yaw_deg,pitch_deg,roll_deg,heading_deg").kind == "skip"
    s = r.feed("0.06,2,2100,2048,2000,1,0,0,0,0.5,0.25,-0.125,359.5").sample
    assert s[:6] == (0.06, 2, 1, 0, 0, 0) and s[13] == pytest.approx(0.5 * DEG) and s[16] == pytest.approx(359.5 * DEG)
    from attitude_c.sim.report import TIMESERIES_COLUMNS

    old = ("t_s,yaw_true,pitch_true,roll_true,yaw_est,pitch_est,roll_est,err_yaw,err_pitch,err_roll,err_heading,"
           "err_angle,q0_est,q1_est,q2_est,q3_est,q0_true,q1_true,q2_true,q3_true")  # before units in the names
    for head in (",".join(TIMESERIES_COLUMNS), old):  # attitude simulate's timeseries.csv (angles in rad)
        r = sources.LineReader()
        r.feed(head)
        values = {"t_s": 0.24, "yaw_est_rad": 0.1, "pitch_est_rad": 0.2, "roll_est_rad": 0.3, "q0_est": 1,
                  "q1_est": 0, "q2_est": 0, "q3_est": 0, **{f"q{i}_true": 0.5 for i in range(4)}}
        values.update({k.removesuffix("_rad"): v for k, v in values.items()})
        s = r.feed(",".join(str(values.get(c, 0)) for c in head.split(","))).sample
        assert s[0] == 0.24 and s[2:6] == (1, 0, 0, 0) and s[9:13] == (0.5, 0.5, 0.5, 0.5)
        assert s[13:16] == (0.1, 0.2, 0.3)
    r = sources.LineReader()
    with pytest.raises(ValueError, match="needs a time column"):
        r.feed("a,b,c")


def test_replay_of_attitude_rx_jsonl_at_speed(tmp_path: Path) -> None:
    """Lines in, the same samples and events out, in order, paced: 40 samples
    over 0.8 s of source time at 4x take at least 0.2 s."""
    q = attitude_c.rotvec_to_quat(np.outer(np.arange(1, 41) * 0.02, [0.1, 0.2, -0.3]))
    lines = [RX_LINES[0]] + [json.dumps({"t": round((k + 1) * 0.02, 6), "n": k, "q": q[k].tolist()})
                             for k in range(40)]
    lines.insert(20, '{"t":0.38,"report":"GAVE_UP","first":19,"count":1,"slip":0}')
    f = tmp_path / "rx.jsonl"
    f.write_text("\n".join(lines) + "\n")
    src = sources.ReplaySource(f, speed=4.0)
    hub = Hub(recorder=Recorder())
    t0 = time.monotonic()
    src.start(hub)
    _drain(hub, lambda: hub.state()[0] == "ended")
    took = time.monotonic() - t0
    assert took >= 0.78 / 4, took  # the last sample is due 0.78 s of source time after the first
    rows = _recording(hub)
    assert [r["event"] or int(r["n"]) for r in rows] == ["BOOT", *range(19), "GAVE_UP", *range(19, 40)]
    samples = [r for r in rows if not r["event"]]
    _same_attitude(_q(samples), q, 1e-9)  # the CSV keeps 9 significant digits
    assert hub.state() == ("ended", "replay of rx.jsonl finished (40 samples)")
    assert hub.counters()["GAVE_UP"] == 1 and hub.counters()["BOOT"] == 1
    hub.recorder.close()


def test_replay_of_a_view_recording_round_trips(tmp_path: Path) -> None:
    """The view's own CSV (with truth and events) replays to the same recording."""
    hub = Hub(recorder=Recorder(tmp_path / "first.csv"))
    w = np.array([0.2, -0.1, 0.4])
    t = np.arange(1, 31) * 0.01
    q = attitude_c.rotvec_to_quat(t[:, None] * w)
    from attitude_c.view.stream import row

    hub.event(0.0, "BOOT", {"period_s": 0.01})
    hub.samples([row(t[k], q[k], n=k, q_true=q[k], rate=w) for k in range(30)])
    hub.tick()
    first = hub.recorder.close()
    src = sources.ReplaySource(first, speed=100.0)
    hub2 = Hub(recorder=Recorder())
    src.start(hub2)
    _drain(hub2, lambda: hub2.state()[0] == "ended")
    a = list(csv.DictReader(first.read_text(encoding="utf-8").splitlines()))
    b = _recording(hub2)
    assert len(a) == len(b) == 31
    for ra, rb in zip(a, b):
        for k in ra:
            if ra[k] and k != "detail":
                assert float(rb[k]) == pytest.approx(float(ra[k]), rel=1e-8, abs=1e-12) if k != "event" \
                    else rb[k] == ra[k], (k, ra[k], rb[k])
    hub2.recorder.close()


def test_replay_errors_name_the_file_and_line(tmp_path: Path) -> None:
    with pytest.raises(InvalidArgument, match="no such file"):
        sources.ReplaySource(tmp_path / "nope.jsonl")
    bad = tmp_path / "bad.jsonl"
    bad.write_text(RX_LINES[1] + "\n{oops\n")
    with pytest.raises(InvalidArgument, match=r"bad\.jsonl' line 2: not JSON"):
        sources.ReplaySource(bad)
    empty = tmp_path / "empty.csv"
    empty.write_text("t,n,q0,q1,q2,q3\n")
    with pytest.raises(InvalidArgument, match="no attitude sample"):
        sources.ReplaySource(empty)
    with pytest.raises(InvalidArgument, match="speed must be"):
        sources.ReplaySource(bad, speed=0)


def _constant_rate_trial(path: Path, w: np.ndarray, q0: np.ndarray, n: int, rate: float) -> np.ndarray:
    """A BROAD-format .mat file of a constant body rate ``w`` (rad/s) from ``q0``:
    the optical reference is the closed form q0 ⊗ q(w t) (NaN in rows 50..59, as
    where BROAD's cameras lose the markers). Returns the closed form at every sample."""
    from scipy.io import savemat

    t = np.arange(n) / rate
    truth = attitude_c.quat_multiply(q0, attitude_c.rotvec_to_quat(t[:, None] * w))
    opt = truth.copy()
    opt[50:60] = np.nan
    savemat(path, {"imu_gyr": np.tile(w, (n, 1)), "imu_acc": np.tile([0, 0, 9.81], (n, 1)),
                   "imu_mag": np.tile([20.0, 0, -40.0], (n, 1)), "opt_quat": opt, "opt_pos": np.zeros((n, 3)),
                   "movement": np.ones((n, 1)), "sampling_rate": np.array([[rate]])})
    return truth


@pytest.mark.parametrize("method", ["rv3", "rv3-reuse", "rk4"])
def test_replay_of_a_broad_trial_runs_the_estimator(tmp_path: Path, method: str) -> None:
    """A BROAD trial through the integrator started at the first reference
    attitude; with a constant rate every method is exact, so the estimate is
    the closed form; the reference is recorded as the truth (none where NaN)."""
    w = np.array([0.4, -0.25, 0.7])
    q0 = attitude_c.euler_to_quat([0.3, -0.2, 0.1])
    f = tmp_path / "01_constant_rate.mat"
    rate = 100.0
    truth = _constant_rate_trial(f, w, q0, 200, rate)
    src = sources.ReplaySource(f, speed=50.0, estimator="integrator", method=method)
    assert src.description == f"replay of 01_constant_rate.mat (BROAD trial, integrator {method}) at 50x"
    hub = Hub(recorder=Recorder())
    src.start(hub)
    _drain(hub, lambda: hub.state()[0] == "ended")
    rows = _recording(hub)
    n = np.array([int(r["n"]) for r in rows])
    # the attitude after sample k is the closed form at t = (k + 1) / rate (rk4: its steps of 2 samples
    # end at odd k and are exact for a constant rate too). The CSV's 9 significant digits bound the error.
    expect_n = {"rv3": np.arange(2, 200, 3), "rv3-reuse": np.arange(200), "rk4": np.arange(2, 200, 2)}[method]
    t_end = (expect_n + 1) / rate if method != "rk4" else expect_n / rate
    np.testing.assert_array_equal(n, expect_n)
    closed = attitude_c.quat_multiply(q0, attitude_c.rotvec_to_quat(t_end[:, None] * w))
    _same_attitude(_q(rows), closed, 5e-9)
    tq = _q([r if r["true_q0"] else {f"true_q{i}": "nan" for i in range(4)} for r in rows], "true_")
    has = ~((n >= 50) & (n < 60))
    _same_attitude(tq[has], truth[n[has]], 1e-9)
    assert np.isnan(tq[~has]).all()
    hub.recorder.close()


def test_replay_of_a_nine_axis_trial_runs_the_filter_by_default(tmp_path: Path) -> None:
    """--estimator auto (the default): a trial with accelerometer and magnetometer
    data runs the attitude filter -- the recording equals attitude_c.ahrs over the same
    samples from the same start -- and the description says so and why; an explicit
    choice and an integrator method are honoured; a trial whose magnetometer holds no
    data runs the integrator."""
    from attitude_c.ahrs_filter import ahrs
    from attitude_c.view.estimators import AhrsEstimator, IntegratorEstimator

    w = np.array([0.2, -0.1, 0.3])
    q0 = attitude_c.euler_to_quat([0.3, -0.2, 0.1])
    f = tmp_path / "02_nine_axis.mat"
    rate = 100.0
    _constant_rate_trial(f, w, q0, 120, rate)
    src = sources.ReplaySource(f, speed=50.0)
    assert isinstance(src.estimator, AhrsEstimator)
    assert src.description == ("replay of 02_nine_axis.mat (BROAD trial, ahrs (rv3-reuse); auto: the source has "
                               "accelerometer and magnetometer data) at 50x")
    hub = Hub(recorder=Recorder())
    src.start(hub)
    _drain(hub, lambda: hub.state()[0] == "ended")
    rows = _recording(hub)
    trial = src.rec.trial
    expect = ahrs(trial.gyr, trial.acc, trial.mag, rate=rate, q0=q0)
    assert [int(r["n"]) for r in rows] == list(range(120))  # one attitude per sample
    # the same C filter on the same samples, one by one vs in one batch: rounding of the CSV's 9 digits only
    _same_attitude(_q(rows), expect, 5e-9)
    hub.recorder.close()
    assert isinstance(sources.ReplaySource(f, estimator="integrator").estimator, IntegratorEstimator)
    by_method = sources.ReplaySource(f, method="rv3-reuse")
    assert by_method.estimator.label == "integrator rv3-reuse"
    assert "auto: an integrator method was given" in by_method.description
    from scipy.io import loadmat, savemat

    d = loadmat(f)
    d["imu_mag"][:] = np.nan  # a six-axis recording
    g = tmp_path / "03_six_axis.mat"
    savemat(g, {k: v for k, v in d.items() if not k.startswith("__")})
    six = sources.ReplaySource(g)
    assert six.estimator.label == "integrator rv3"
    assert "auto: the source has no accelerometer and magnetometer data" in six.description


def test_replay_of_a_shipped_broad_trial_matches_the_reference() -> None:
    """A real BROAD trial (../shared/data/broad) through rv3: the recording equals
    the NumPy reference integrator on the same gyro data from the same start."""
    from attitude_c import broad

    folder = broad.default_dir()
    if folder is None:
        pytest.skip("BROAD data not found beside the checkout (../shared/data/broad)")
    f = broad.find_trials(folder)[0]
    src = sources.ReplaySource(f, speed=1000.0, method="rv3")
    trial = src.rec.trial
    hub = Hub(recorder=Recorder())
    src.start(hub)
    _drain(hub, lambda: hub.state()[0] == "ended", timeout=300)
    rows = _recording(hub)
    ok = np.isfinite(trial.quat).all(axis=1)
    q_ref = reference.integrate(trial.gyr * trial.dt, method="rv3", q0=trial.quat[np.flatnonzero(ok)[0]])
    assert len(rows) == len(q_ref) == trial.n // 3
    # C integrator vs NumPy reference on ~1e5 real samples: rounding only (~1e-12), then 9 digits in the CSV
    _same_attitude(_q(rows), q_ref, 5e-9)
    hub.recorder.close()


def test_estimator_registry() -> None:
    assert "integrator" in ESTIMATORS and not ESTIMATORS["integrator"].needs_acc
    with pytest.raises(InvalidArgument, match="estimator must be one of"):
        make_estimator("kalman-magic", has_acc=True)
    from attitude_c.view import estimators

    estimators.register(estimators.EstimatorSpec("needs-acc", "test", True, estimators.IntegratorEstimator))
    try:
        with pytest.raises(InvalidArgument, match="needs accelerometer samples"):
            make_estimator("needs-acc", has_acc=False)
        assert make_estimator("needs-acc", has_acc=True, method="rv1").label == "integrator rv1"
    finally:
        del ESTIMATORS["needs-acc"]


# ---- the serial link's records -----------------------------------------------------------

K = math.radians(90.0) / 2048.0  # attitude-rx's default rad/s per code
CODES = (2048 + 300, 2048 - 120, 2048 + 45)
W = (np.array(CODES) - 2048.0) * K  # the constant body rate these codes stand for


def send_boot_and_samples(path: str, n: int) -> None:
    """The Python sender A on ``path``: BOOT (20 ms) then ``n`` samples of CODES, every one accepted."""
    from attitude_c.link.transport import open_port, run_sender

    blocks = [block.encode_boot(72, 9600)] + [block.encode_sample(CODES)] * n
    pa = open_port(path)
    try:
        # long timeouts: a loaded machine must not turn scheduling delays into resends
        reports, _ = run_sender(pa, blocks, impl="python", syn_timeout_ms=2000, answer_timeout_ms=2000)
    finally:
        pa.close()
    assert all(r.outcome == "accepted" for r in reports)


def _closed(t: np.ndarray) -> np.ndarray:
    return attitude_c.rotvec_to_quat(np.asarray(t)[:, None] * W)


def test_block_pipeline_numbers_holds_and_integrates() -> None:
    """BOOT (period 36 ticks = 10 ms), samples, a GAVE_UP for 2 samples (held
    at the last rate, so with a constant rate the closed form still holds), a
    code out of range (held), and a loss report that slips back (duplicates)."""
    hub = Hub(recorder=Recorder())
    counts: dict[str, float] = {}

    def count(name: str, k: float) -> None:
        counts[name] = counts.get(name, 0) + k

    est = make_estimator("integrator", has_acc=False, method="rv3-reuse")
    pipe = sources.BlockPipeline(hub, est, count, period=0.02, period_fixed=False)
    recs = [block.encode_boot(36, 9600)] + [block.encode_sample(CODES)] * 5
    recs += [block.encode_loss("gave_up", 5, 2)] + [block.encode_sample(CODES)] * 3
    recs += [b"\x19" + block.encode_sample(CODES)[1:]]  # X's high byte 0x19: code 6444 > 4095
    recs += [block.encode_sample(CODES)] * 2
    recs += [b"\xfe\x7f\x00\x00\x00\x00"]  # a kind the format does not define
    pipe.feed_block(b"".join(recs[:2]))  # a 12-byte block: two records
    for r in recs[2:]:
        pipe.feed_record(r)
    # a loss report saying samples 10..10 were lost, when 13 were already counted: a slip back
    pipe.feed_record(block.encode_loss("overrun", 10, 1))
    hub.tick()
    rows = _recording(hub)
    smp = [r for r in rows if not r["event"]]
    n = [int(r["n"]) for r in smp]
    assert n[:13] == list(range(13))
    t = np.array([float(r["t"]) for r in smp[:13]])
    np.testing.assert_allclose(t, (np.arange(13) + 1) * 0.01, rtol=1e-9)  # BOOT's period
    _same_attitude(_q(smp[:13]), _closed(t), 5e-9)
    ev = [(r["event"], json.loads(r["detail"]) if r["detail"] else {}) for r in rows if r["event"]]
    assert ev[0][0] == "BOOT" and ev[0][1]["period_s"] == 0.01
    assert ev[1] == ("GAVE_UP", {"first": 5, "count": 2, "slip": 0})
    assert ev[2][0] == "error" and ev[2][1]["n"] == 10 and ev[2][1]["codes"][0] > 4095
    assert ev[3][0] == "error" and "kind" in ev[3][1]["error"]
    assert ev[4][0] == "OVERRUN" and ev[4][1]["slip"] < 0
    # held: GAVE_UP's 2, the bad code's 1, and the slipped OVERRUN's own sample (held as attitude-rx does)
    assert counts["samples"] == 11 and counts["held"] == counts["missing"] == 2 + 1 + ev[4][1]["count"]
    assert counts["code_errors"] == 1 and counts["block_errors"] == 1 and counts["slips"] == 1
    assert counts["duplicates"] == -ev[4][1]["slip"]
    hub.recorder.close()


def test_block_pipeline_keeps_a_given_period_and_waits_for_a_first_rate() -> None:
    hub = Hub(recorder=Recorder())
    counts: dict[str, float] = {}
    pipe = sources.BlockPipeline(hub, make_estimator("integrator", has_acc=False, method="rv1"),
                                 lambda k, v: counts.__setitem__(k, counts.get(k, 0) + v),
                                 period=0.05, period_fixed=True)
    pipe.feed_record(block.encode_boot(72, 9600))  # says 20 ms; --period 50 ms wins
    pipe.feed_record(block.encode_loss("overrun", 0, 2))  # before any sample: time passes, nothing held
    pipe.feed_record(block.encode_sample(CODES))
    hub.tick()
    smp = [r for r in _recording(hub) if not r["event"]]
    assert [(r["n"], float(r["t"])) for r in smp] == [("2", pytest.approx(0.15))]
    assert counts["missing"] == 2 and "held" not in counts
    _same_attitude(_q(smp), _closed([0.05]), 5e-9)  # one period of integration
    hub.recorder.close()
    with pytest.raises(InvalidArgument, match="period must be"):
        sources.BlockPipeline(hub, make_estimator("integrator", has_acc=False), lambda k, v: None,
                              period=0.0, period_fixed=True)


@pytest.mark.parametrize("impl", ["c", "python"])
def test_serial_source_over_a_pty(impl: str) -> None:
    """The link protocol on a real pseudo-terminal pair: the Python sender A sends
    BOOT and 60 samples; SerialSource (receiver B, decoder, rv3) delivers the
    closed-form attitude and the link's counters."""
    from attitude_c.link.transport import PtyPair

    with PtyPair() as (p0, p1):
        src = sources.SerialSource(p1, impl=impl, method="rv3", gap_timeout_ms=400)
        hub = Hub(recorder=Recorder())
        src.start(hub)
        send_boot_and_samples(p0, 60)
        _drain(hub, lambda: hub.samples_in >= 20)
        src.stop()
        src.join(5)
        hub.tick()
    rows = _recording(hub)
    smp = [r for r in rows if not r["event"]]
    assert rows[0]["event"] == "BOOT" and [int(r["n"]) for r in smp] == list(range(2, 60, 3))
    t = np.array([float(r["t"]) for r in smp])
    np.testing.assert_allclose(t, (np.arange(2, 60, 3) + 1) * 0.02, rtol=1e-9)
    _same_attitude(_q(smp), _closed(t), 5e-9)
    c = hub.counters()
    assert c["blocks"] == 61 and c["naks"] == 0 and c["samples"] == 60 and c["BOOT"] == 1
    assert src.description.startswith(f"serial {p1} (9600 8N1, block 6, receiver {impl}, integrator rv3")
    hub.recorder.close()


def test_serial_source_errors() -> None:
    from attitude_c.errors import LinkError

    with pytest.raises(LinkError):
        sources.SerialSource("/dev/nonexistent-attitude-port")
    with pytest.raises(InvalidArgument, match="multiple of 6"):
        sources.SerialSource("loop://", block_size=8)


# ---- the simulator ------------------------------------------------------------------------

def test_simulator_source_plays_every_update_with_its_truth() -> None:
    from attitude_c.sim import simulate
    from attitude_c.view.simsource import SimulatorSource, parse_simulate_options

    opts = ["--duration", "1", "--period", "0.01", "--method", "rv3", "--calibration", "1", "--seed", "3"]
    src = SimulatorSource(parse_simulate_options(opts), speed=20.0)
    assert src.description.startswith("simulator: paper trajectory, 1 s, period 0.01 s, rv3 (f64)")
    hub = Hub(recorder=Recorder())
    src.start(hub)
    _drain(hub, lambda: hub.state()[0] == "ended", timeout=60)
    every = _recording(hub)
    assert every[0]["event"] == "note" and "33 attitude updates" in json.loads(every[0]["detail"])["note"]
    rows = every[1:]
    res = simulate(parse_simulate_options(opts))  # the same seed: the same run
    assert len(rows) == len(res.t) == 33
    assert [int(r["n"]) for r in rows] == list(range(2, 100, 3))  # rv3: after samples 2, 5, 8, ...
    np.testing.assert_allclose([float(r["t"]) for r in rows], res.t, rtol=1e-9)
    _same_attitude(_q(rows), res.q_est, 5e-9)
    _same_attitude(_q(rows, "true_"), res.q_true, 5e-9)
    # the rate of each update's newest sample: its increment over the period
    rates = np.array([[float(r[f"rate_{a}_dps"]) for a in "xyz"] for r in rows])
    np.testing.assert_allclose(rates, res.increments[2::3] / 0.01 / DEG, rtol=1e-7, atol=1e-9)
    c = hub.counters()
    assert c["blocks"] == 100 and c["duplicates"] == 0 and c["lost"] == 0
    hub.recorder.close()


def test_simulate_options_are_simulates_own() -> None:
    from attitude_c.view.simsource import parse_simulate_options

    cfg = parse_simulate_options(["--trajectory", "coning", "--period", "0.005", "--ber", "1e-4"])
    assert cfg.trajectory.name == "coning" and cfg.period == 0.005 and cfg.ber == 1e-4
    with pytest.raises(SystemExit) as e:
        parse_simulate_options(["--period", "-1"])
    assert e.value.code == 2
    with pytest.raises(InvalidArgument, match="--budget: not for the display"):
        parse_simulate_options(["--budget"])


def test_pace_stops_when_asked() -> None:
    from attitude_c.view.stream import row

    hub = Hub(recorder=Recorder())
    stop = threading.Event()
    items = [(k * 1.0, "sample", row(k * 1.0, [1, 0, 0, 0])) for k in range(100)]  # 100 s of source time
    th = threading.Thread(target=lambda: sources.pace(hub, items, 1.0, stop))
    th.start()
    time.sleep(0.2)
    stop.set()
    th.join(2)
    assert not th.is_alive()
    hub.tick()
    assert hub.samples_in == 1  # the first sample is due at once, the second 1 s later
    hub.recorder.close()


def test_line_reader_shows_the_filters_bias_and_flags() -> None:
    """attitude-rx's filter lines (--estimator ahrs): the gyro-bias estimate (°/s) and the flags of
    the newest sample become the counters the page lists (JSON names; CSV: the ATT_AHRS_F_* bits)."""
    from attitude_c.names import C

    r = sources.LineReader()
    p = r.feed('{"t":0.02,"n":1,"codes":[2048,2048,2048],"q":[1,0,0,0],"held":0,"rate_dps":[0,0,0],'
               '"bias_dps":[0.012345,-0.5,0],"flags":["rest","mag_disturbed"],"acc_ms2":[0,0,9.8]}')
    assert p.kind == "sample"
    assert p.counters == {"held": 0, "bias_x_dps": 0.0123, "bias_y_dps": -0.5, "bias_z_dps": 0.0,
                          "filter_flags": "rest mag_disturbed"}
    p = r.feed('{"t":0.04,"n":2,"q":[1,0,0,0],"held":0,"bias_dps":[0,0,0],"flags":[]}')
    assert p.counters["filter_flags"] == "none"
    r = sources.LineReader()
    r.feed("t,n,code_x,code_y,code_z,q0,q1,q2,q3,yaw_deg,pitch_deg,roll_deg,heading_deg,"
           "bias_x_dps,bias_y_dps,bias_z_dps,flags")
    bits = C["ATT_AHRS_F_REST"] | C["ATT_AHRS_F_ACC_REJECTED"]
    p = r.feed(f"0.06,2,2100,2048,2000,1,0,0,0,0,0,0,0,0.25,0,-0.125,{bits}")
    assert p.counters == {"bias_x_dps": 0.25, "bias_y_dps": 0.0, "bias_z_dps": -0.125,
                          "filter_flags": "rest acc_rejected"}
