"""attitude view's GNSS panel, the Python side (issue 30): attitude-rx's ``"gnss"`` objects checked
field by field, carried through stdin and replays to the hub, sent to the page (hello, frames, the
ground-speed chart column), recorded and replayed back; a bad object is a broken line (counted, the
stream goes on); the simulator's receiver gives the same objects, of its trajectory's velocity."""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest

from attitude_c.errors import InvalidArgument
from attitude_c.view import sources
from attitude_c.view.stream import CHART_COLUMNS, GNSS_EVENT, Hub, Recorder

GOOD = {"fix": "3d", "valid": True, "speed": 12.5, "track_deg": 271.25, "vel_enu": [-12.4969, 0.2727, None],
        "sats": 11, "pdop": 1.4, "age_s": 0.12, "source": "gpsd"}


class FakeClock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def _line(t: float, n: int, gnss: object = None, flags: list[str] | None = None) -> str:
    d: dict[str, object] = {"t": t, "n": n, "q": [1, 0, 0, 0], "yaw_deg": 0, "pitch_deg": 0, "roll_deg": 0,
                            "heading_deg": 0, "held": 0}
    if flags is not None:
        d.update(bias_dps=[0, 0, 0], flags=flags)
    if gnss is not None:
        d["gnss"] = gnss
    return json.dumps(d)


def _frames(hub: Hub) -> list[dict]:
    out = []
    while True:
        msg = hub.tick()
        if msg is None:
            return out
        out.append(json.loads(msg))


def test_a_good_object_is_kept_with_nulls_for_what_is_missing() -> None:
    assert sources.gnss_fix(GOOD) == GOOD
    assert sources.gnss_fix({"fix": "none", "valid": False, "extra": 1}) == {
        "fix": "none", "valid": False, "speed": None, "track_deg": None, "vel_enu": None, "sats": None,
        "pdop": None, "age_s": None, "source": None}
    names = sources.gnss_fix_names()  # from the compiled library: the contract's six
    assert names == {0: "none", 1: "dr", 2: "2d", 3: "3d", 4: "gnss_dr", 5: "time"}
    for fix in names.values():
        assert sources.gnss_fix({**GOOD, "fix": fix})["fix"] == fix
    assert sources.gnss_fix({**GOOD, "track_deg": 0, "speed": 0, "sats": 0})["track_deg"] == 0.0


@pytest.mark.parametrize("field,value", [
    ("fix", "3D"), ("fix", None), ("valid", 1), ("valid", "true"), ("speed", -0.1), ("speed", "5"),
    ("speed", True), ("track_deg", 360.5), ("track_deg", -1), ("vel_enu", [1, 2]), ("vel_enu", [1, "x", 2]),
    ("vel_enu", 3.0), ("sats", 7.5), ("sats", -1), ("sats", 256), ("sats", False), ("pdop", -1), ("age_s", -0.01),
    ("age_s", 1e11), ("source", ""), ("source", "x" * 33), ("source", 5),
])
def test_a_bad_field_is_named(field: str, value: object) -> None:
    with pytest.raises((ValueError, TypeError), match=f"gnss {field}"):
        sources.gnss_fix({**GOOD, field: value})


def test_not_an_object() -> None:
    with pytest.raises(TypeError, match="gnss must be a JSON object"):
        sources.gnss_fix([1, 2])


def test_line_reader_gives_the_fix_with_its_sample() -> None:
    r = sources.LineReader()
    p = r.feed(_line(0.5, 25, GOOD, ["gnss_aided"]))
    assert p.kind == "sample" and p.sample is not None and p.gnss == GOOD
    assert p.counters is not None and p.counters["filter_flags"] == "gnss_aided"
    assert r.feed(_line(0.52, 26)).gnss is None
    assert r.feed(_line(0.54, 27, None)).gnss is None  # "gnss": absent
    with pytest.raises(ValueError, match="gnss speed"):  # the line is broken, as with a bad q
        r.feed(_line(0.56, 28, {**GOOD, "speed": -3}))
    with pytest.raises(ValueError, match="gnss"):
        r.feed('{"t":0.58,"n":29,"q":[1,0,0,0],"gnss":{"fix":"3d","valid":true,"speed":NaN}}')


def test_stdin_counts_a_bad_object_and_goes_on_and_the_page_gets_the_fix() -> None:
    """Three lines with fixes, the second broken: its sample is refused and counted (bad_lines, an
    error event naming the field), the stream goes on; the hello and the frames carry the newest
    fix (its line's time and the count received); the chart point carries its ground speed."""
    second = {**GOOD, "sats": "eleven"}
    third = {**GOOD, "speed": 13.0, "track_deg": 272.0, "age_s": 0.05}
    lines = [_line(0.02, 1), _line(0.04, 2, GOOD), _line(0.06, 3, second), _line(0.08, 4, third), _line(0.1, 5)]
    src = sources.StdinSource(io.BytesIO(("\n".join(lines) + "\n").encode()))
    hub = Hub(recorder=Recorder(), clock=FakeClock())
    src.start(hub)
    src.join(10)
    frames = _frames(hub)
    assert src.counters()["bad_lines"] == 1
    errors = [e for f in frames for e in f.get("events", []) if e["kind"] == "error"]
    assert len(errors) == 1 and "line 3: gnss sats 'eleven'" in errors[0]["detail"]["error"]
    gnss = [f["gnss"] for f in frames if "gnss" in f]
    assert gnss == [{"t": 0.08, **third, "count": 2}]  # one tick took every line: the newest fix
    assert all(e["kind"] != GNSS_EVENT for f in frames for e in f.get("events", []))  # not a report
    point = next(f["point"] for f in frames if "point" in f)
    assert point[CHART_COLUMNS.index("gnss_speed")] == 13.0
    hello = json.loads(hub.hello())
    assert hello["gnss"]["speed"] == 13.0 and hello["columns"][-1] == "gnss_speed"
    hub.recorder.close()


def test_chart_speed_is_null_without_a_valid_fix() -> None:
    hub = Hub(recorder=Recorder(), clock=FakeClock())
    from attitude_c.view.stream import row

    hub.samples([row(0.1, [1, 0, 0, 0])])
    p1 = json.loads(hub.tick() or "{}")["point"]
    hub.samples([row(0.2, [1, 0, 0, 0])])
    hub.gnss(0.2, sources.gnss_fix({**GOOD, "valid": False}))
    p2 = json.loads(hub.tick() or "{}")["point"]
    hub.samples([row(0.3, [1, 0, 0, 0])])
    hub.gnss(0.3, sources.gnss_fix(GOOD))
    p3 = json.loads(hub.tick() or "{}")["point"]
    k = CHART_COLUMNS.index("gnss_speed")
    assert (p1[k], p2[k], p3[k]) == (None, None, 12.5)
    hub.recorder.close()


def test_a_fix_alone_makes_a_frame() -> None:
    """A fix with no sample in the tick is still sent (not swallowed as 'nothing new')."""
    hub = Hub(recorder=Recorder(), clock=FakeClock())
    hub.tick()
    hub.gnss(1.0, sources.gnss_fix(GOOD))
    assert json.loads(hub.tick() or "{}")["gnss"]["count"] == 1
    hub.recorder.close()


def test_the_recording_keeps_the_fixes_and_replays_them(tmp_path: Path) -> None:
    """JSON Lines with fixes replayed: the view's recording holds each fix as a "gnss" row after its
    sample; that recording replayed gives the same rows again."""
    fixes = [{**GOOD, "speed": 10.0 + k, "track_deg": 90.0 + k} for k in range(3)]
    lines = [_line(0.1 * (k + 1), k, fixes[k // 2] if k % 2 == 0 else None) for k in range(6)]
    f = tmp_path / "rx.jsonl"
    f.write_text("\n".join(lines) + "\n")
    first = _replay(f, tmp_path / "first.csv")
    rows = list(csv.DictReader(first.read_text(encoding="utf-8").splitlines()))
    kinds = [r["event"] or "sample" for r in rows]
    assert kinds == ["sample", "gnss", "sample", "sample", "gnss", "sample", "sample", "gnss", "sample"]
    assert [json.loads(r["detail"]) for r in rows if r["event"] == GNSS_EVENT] == fixes
    assert [float(r["t"]) for r in rows if r["event"] == GNSS_EVENT] == [0.1, 0.3, 0.5]
    second = _replay(first, tmp_path / "second.csv")
    again = list(csv.DictReader(second.read_text(encoding="utf-8").splitlines()))
    assert [(r["t"], r["event"], r["detail"]) for r in again] == [(r["t"], r["event"], r["detail"]) for r in rows]


def _replay(path: Path, out: Path) -> Path:
    src = sources.ReplaySource(path, speed=1000.0)
    hub = Hub(recorder=Recorder(out), clock=FakeClock())
    src.start(hub)
    src.join(20)
    hub.tick()
    kept = hub.recorder.close()
    assert kept == out
    return out


def test_a_replay_with_a_bad_object_is_refused_naming_the_line(tmp_path: Path) -> None:
    f = tmp_path / "rx.jsonl"
    f.write_text(_line(0.1, 0, GOOD) + "\n" + _line(0.2, 1, {**GOOD, "fix": "4d"}) + "\n")
    with pytest.raises(InvalidArgument, match=r"rx.jsonl' line 2: gnss fix '4d'"):
        sources.load_recording(f)


def test_the_simulators_receiver_gives_the_same_objects() -> None:
    """A car braking with the ideal receiver (no noise, no latency, 10 Hz) and an outage: one object per
    fix, on the first update at or after its delivery; the speed and track those of the trajectory's
    velocity at the fix's time (the ideal receiver adds nothing); the outage's fixes "none", not valid."""
    from attitude_c.sim import simulate
    from attitude_c.view.simsource import SimulatorSource, parse_simulate_options

    cfg = parse_simulate_options(["--trajectory", "car-brake", "--duration", "2", "--period", "0.01", "--method",
                                  "rv3-reuse", "--calibration", "1", "--gnss", "ideal", "--gnss-outage", "1,1.5"])
    src = SimulatorSource(cfg)
    items = list(src.items(simulate(cfg)))
    got = [(t, sources.gnss_fix(g)) for t, what, g in items if what == "gnss"]  # each passes the page's check
    assert len(got) == 21  # 10 Hz over [0, 2] s
    upd = np.array([t for t, what, _ in items if what == "sample"])
    for tm, (t, g) in zip(np.arange(21) * 0.1, got):  # the fixes' times as the receiver makes them (k / rate)
        assert t == upd[np.searchsorted(upd, tm)]  # the first update at or after the fix
        assert g["age_s"] == pytest.approx(t - tm, abs=1e-12)
        if 1.0 <= tm < 1.5 - 1e-9:
            assert (g["fix"], g["valid"], g["speed"], g["sats"]) == ("none", False, None, 0)
            continue
        v = cfg.trajectory.velocity(np.array([tm]))[0]
        assert g["fix"] == "3d" and g["valid"] and g["vel_enu"] == pytest.approx(v.tolist(), abs=1e-12)
        assert g["speed"] == pytest.approx(math.hypot(v[0], v[1]), abs=1e-12)
        if g["speed"] > 0.1:  # the track of a vehicle at rest is the noise's
            assert g["track_deg"] == pytest.approx(math.degrees(math.atan2(v[0], v[1])) % 360.0, abs=1e-9)
