"""Sources of the display: attitude-rx's output on stdin, a recording
replayed at a chosen speed (CSV, JSON Lines, BROAD ``.mat``), a serial port
or any pyserial URL through the Python host end of the link.

Each source runs in its own daemon thread and talks to the
:class:`~attitude_c.view.stream.Hub` only through its non-blocking calls
(``samples``, ``event``, ``status``); the hub reads the source's counters
with :meth:`Source.counters`. Everything that can be wrong with a file or a
port is found when the source is made (an :class:`~attitude_c.errors.AttitudeError`
naming the file and line), before the server starts.
"""

from __future__ import annotations

import contextlib
import csv
import functools
import io
import json
import math
import os
import selectors
import threading
import time
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Callable, Literal, Union

import numpy as np
from numpy.typing import NDArray

from .. import _text
from ..errors import AttitudeError, InvalidArgument
from .estimators import AUTO, Estimator, choose, make_estimator
from .stream import GNSS_EVENT, Hub, row

__all__ = ["BlockPipeline", "LineReader", "ReplaySource", "SerialSource", "Source", "StdinSource",
           "gnss_fix", "gnss_fix_names", "load_recording", "pace"]

_RAD = math.pi / 180.0

#: The firmware's default sampling period (firmware/config.h ``FW_PERIOD_TICKS``, ticks of
#: 1/ATT_BLOCK_TICK_HZ s) -- attitude-rx's period too until a BOOT report announces one.
DEFAULT_PERIOD_TICKS = 72
#: attitude-rx's default gyro calibration (csrc/app/rx_config.c): zero-rate code and rad/s per code
#: (90 deg/s per 2048 codes).
DEFAULT_ZERO_CODE = 2048.0
DEFAULT_SCALE = math.radians(90.0) / 2048.0
#: Seconds between attempts to reopen a serial port that failed.
REOPEN_S = 1.0
#: The largest source time a line may carry (s; about 317 years): beyond it a time is a
#: mistake (a replay would wait for it for ever). Unix time stamps (1.8e9 s) pass.
MAX_TIME_S = 1e10


class Source:
    """Base of the sources: a daemon thread running :meth:`run`, counters
    behind a lock, a stop flag. Subclasses set :attr:`description`."""

    description = ""

    def __init__(self) -> None:
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._counts: dict[str, Any] = {}
        self._thread: threading.Thread | None = None

    def start(self, hub: Hub) -> None:
        hub.counters_from(self.counters)
        self._thread = threading.Thread(target=self._main, args=(hub,), daemon=True,
                                        name=f"view-source-{type(self).__name__}")
        self._thread.start()

    def _main(self, hub: Hub) -> None:
        try:
            self.run(hub)
        except Exception as exc:  # noqa: BLE001 - the page says what happened; the server stays up
            hub.status("lost", f"source failed: {type(exc).__name__}: {exc}")

    def run(self, hub: Hub) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def stop(self) -> None:
        """Ask the thread to end (sources blocked in a read end with the process)."""
        self._stop.set()

    def join(self, timeout: float | None = None) -> None:
        if self._thread is not None:
            self._thread.join(timeout)

    def counters(self) -> dict[str, Any]:
        with self._lock:
            return dict(self._counts)

    def count(self, name: str, k: float = 1) -> None:
        with self._lock:
            self._counts[name] = self._counts.get(name, 0) + k

    def set_counts(self, values: dict[str, Any]) -> None:
        with self._lock:
            self._counts.update(values)


# ---------------------------------------------------------------------------------------
# lines: attitude-rx JSON Lines and CSV, and the view's own recordings
# ---------------------------------------------------------------------------------------

Sample = tuple  # a row of attitude_c.view.COLUMNS


@dataclass
class Parsed:
    """One line, understood: a sample row, an event, counters, or nothing."""

    kind: Literal["sample", "event", "counters", "gnss", "skip"]
    t: float = float("nan")
    sample: Sample | None = None
    event: str = ""
    detail: dict[str, Any] | None = None
    counters: dict[str, Any] | None = None
    gnss: dict[str, Any] | None = None  #: a GNSS fix (:func:`gnss_fix`) the line carries


_SKIP = Parsed("skip")

# CSV columns understood, by role (first name found wins).
_CSV_TIME = ("t", "t_s", "time")
_CSV_Q = (("q0", "q1", "q2", "q3"), ("q0_est", "q1_est", "q2_est", "q3_est"))
_CSV_TRUE_Q = (("true_q0", "true_q1", "true_q2", "true_q3"), ("q0_true", "q1_true", "q2_true", "q3_true"))
_CSV_EULER_DEG = ("yaw_deg", "pitch_deg", "roll_deg")
# attitude simulate's timeseries.csv (attitude_c.sim.report.TIMESERIES_COLUMNS; before issue 27, without units)
_CSV_EULER_RAD = (("yaw_est_rad", "pitch_est_rad", "roll_est_rad"), ("yaw_est", "pitch_est", "roll_est"))
_CSV_RATE_DPS = ("rate_x_dps", "rate_y_dps", "rate_z_dps")
_CSV_BIAS_DPS = ("bias_x_dps", "bias_y_dps", "bias_z_dps")  # attitude-rx's filter lines (and "flags")


def _filter_counters(bias_dps: list[float] | None, flags: Any) -> dict[str, Any]:
    """attitude-rx's filter fields of the newest sample as counters the page shows: the gyro-bias
    estimate (°/s, 4 decimals) and the flags by name (a list of names, or the ATT_AHRS_F_* bits;
    "none" when no flag is set)."""
    out: dict[str, Any] = {}
    if bias_dps is not None:
        out.update({k: round(float(v), 4) for k, v in zip(_CSV_BIAS_DPS, bias_dps)})
    if isinstance(flags, int) and not isinstance(flags, bool):
        flags = _flag_names(flags)
    if isinstance(flags, list):
        out["filter_flags"] = " ".join(str(f) for f in flags) or "none"
    return out


def _flag_names(bits: int) -> list[str]:
    """The names of the attitude filter's flag bits (ATT_AHRS_F_*, attitude/ahrs.h), as attitude-rx's
    JSON Lines print them."""
    from ..names import C

    pre = "ATT_AHRS_F_"
    return [k[len(pre):].lower() for k, v in sorted(C.items(), key=lambda kv: kv[1])
            if k.startswith(pre) and bits & v]


@functools.cache
def gnss_fix_names() -> dict[int, str]:
    """The fix types (``att_gnss_fix_type``, attitude/gnss.h: UBX NAV-PVT's fixType) by code, as
    attitude-rx's ``"gnss"`` objects name them: the lower-case suffix of ``ATT_GNSS_FIX_*``."""
    from ..names import C

    pre = "ATT_GNSS_FIX_"
    return {v: k[len(pre):].lower() for k, v in sorted(C.items(), key=lambda kv: kv[1]) if k.startswith(pre)}


#: The longest ``source`` name a ``"gnss"`` object may carry (characters).
GNSS_SOURCE_MAX = 32


def _real(x: Any, name: str, lo: float = -math.inf, hi: float = math.inf) -> float | None:
    """A JSON number in [lo, hi], or None for null (a bool is not a number)."""
    if x is None:
        return None
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not (math.isfinite(x) and lo <= x <= hi):
        raise ValueError(f"gnss {name} {x!r}: must be null or a finite number in [{lo:g}, {hi:g}]")
    return float(x)


def gnss_fix(d: Any) -> dict[str, Any]:
    """attitude-rx's ``"gnss"`` object, checked: ``fix`` (a name of :func:`gnss_fix_names`) and ``valid``
    (true/false) required; ``speed`` (m/s, >= 0), ``track_deg`` ([0, 360]), ``vel_enu`` (3 numbers
    or nulls: m/s), ``sats`` (an integer >= 0), ``pdop`` (>= 0), ``age_s`` (>= 0) and ``source`` (a
    short name) null or absent when unknown; other keys are ignored. Raises ValueError (TypeError
    for an object that is not one, or a ``valid`` that is not a bool) naming the field."""
    if not isinstance(d, dict):
        raise TypeError("gnss must be a JSON object")
    fixes = gnss_fix_names().values()
    if d.get("fix") not in fixes:
        raise ValueError(f"gnss fix {d.get('fix')!r}: must be one of {', '.join(fixes)}")
    if not isinstance(d.get("valid"), bool):
        raise TypeError(f"gnss valid {d.get('valid')!r}: must be true or false")
    vel = d.get("vel_enu")
    if vel is not None and not (isinstance(vel, list) and len(vel) == 3):
        raise ValueError(f"gnss vel_enu {vel!r}: must be null or a list of 3 numbers (null where unknown)")
    sats = d.get("sats")
    if sats is not None and (isinstance(sats, bool) or not isinstance(sats, int) or not 0 <= sats <= 255):
        raise ValueError(f"gnss sats {sats!r}: must be null or an integer in [0, 255]")
    src = d.get("source")
    if src is not None and not (isinstance(src, str) and 0 < len(src) <= GNSS_SOURCE_MAX):
        raise ValueError(f"gnss source {_text.clip(repr(src), 40)}: must be null or a name of at most "
                         f"{GNSS_SOURCE_MAX} characters")
    return {"fix": d["fix"], "valid": d["valid"], "speed": _real(d.get("speed"), "speed", 0.0),
            "track_deg": _real(d.get("track_deg"), "track_deg", 0.0, 360.0),
            "vel_enu": None if vel is None else [_real(v, "vel_enu") for v in vel], "sats": sats,
            "pdop": _real(d.get("pdop"), "pdop", 0.0), "age_s": _real(d.get("age_s"), "age_s", 0.0, MAX_TIME_S),
            "source": src}


def _vec(d: dict[str, Any], key: str, k: int, scale: float = 1.0) -> list[float] | None:
    v = d.get(key)
    if v is None:
        return None
    if not isinstance(v, list) or len(v) != k:
        raise ValueError(f"{key!r} must be a list of {k} numbers")
    return [float(x) * scale for x in v]


class LineReader:
    """Turns the lines of attitude-rx's output (``--format jsonl`` or CSV with
    its header) or of a view recording (CSV, :data:`~attitude_c.view.CSV_HEADER`)
    into samples and events.

    JSON Lines: a record with ``q`` is a sample (``t``, ``n``, ``q``, and
    ``yaw_deg``, ``pitch_deg``, ``roll_deg``, ``heading_deg`` when present;
    ``rate_dps`` [x, y, z] and ``true_q`` are used if a producer adds them);
    ``{"report": NAME, ...}`` is a report and ``{"error": ...}`` an error
    (events); ``{"link": {...}}`` or ``{"stats": {...}}`` records give
    counters (their numeric fields). attitude-rx's cumulative ``held``
    becomes a counter, and so do its filter's ``bias_dps`` and ``flags`` of
    the newest sample (``bias_x_dps`` .. ``bias_z_dps``, ``filter_flags``;
    CSV: the bias columns and ``flags``). Anything else is counted and ignored.
    """

    def __init__(self) -> None:
        self._cols: dict[str, int] | None = None
        self._roles: dict[str, Any] = {}

    def feed(self, line: str) -> Parsed:
        """Parse one line. Raises ValueError (with a reason, one short line) for a broken line."""
        s = line.strip()
        if not s or s.startswith("#"):
            return _SKIP
        try:
            if s.startswith(("{", "[")):
                return self._json(s)
            return self._csv(s)
        except (ValueError, TypeError, KeyError, IndexError, OverflowError, csv.Error) as exc:
            text = str(exc) if not isinstance(exc, KeyError) else f"no {exc} field"
            raise ValueError(_text.clip(text, 160)) from None

    def _json(self, s: str) -> Parsed:
        try:
            d = json.loads(s)
        except json.JSONDecodeError as exc:
            raise ValueError(f"not JSON: {exc.msg}") from None
        except RecursionError:
            raise ValueError("not JSON this reader takes: nested too deep") from None
        if not isinstance(d, dict):
            raise TypeError("not a JSON object")
        if "q" in d:
            t = _time(d["t"])
            q = _vec(d, "q", 4)
            eul = None
            if all(k in d for k in _CSV_EULER_DEG):
                eul = [float(d[k]) * _RAD for k in _CSV_EULER_DEG]
            h = d.get("heading_deg")
            n = d.get("n")
            smp = row(t, q, n=None if n is None else float(n), rate=_vec(d, "rate_dps", 3, _RAD),
                      q_true=_vec(d, "true_q", 4), euler=eul, heading=None if h is None else float(h) * _RAD)
            p = Parsed("sample", t, sample=smp, gnss=gnss_fix(d["gnss"]) if d.get("gnss") is not None else None)
            counters = {"held": d["held"]} if "held" in d else {}
            counters.update(_filter_counters(_vec(d, "bias_dps", 3), d.get("flags")))
            p.counters = counters or None
            return p
        t = _time(d.get("t"), required=False)
        if "report" in d:
            detail = {k: v for k, v in d.items() if k not in ("t", "report")}
            return Parsed("event", t, event=str(d["report"]), detail=detail)
        if "error" in d:
            detail = {k: v for k, v in d.items() if k != "t"}
            return Parsed("event", t, event="error", detail=detail)
        for key in ("link", "stats"):
            if isinstance(d.get(key), dict):
                c = {k: v for k, v in d[key].items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
                return Parsed("counters", t, counters=c)
        return Parsed("counters", t, counters={"other_records": 1})

    def _csv(self, s: str) -> Parsed:
        fields = next(csv.reader([s]), [])
        if self._cols is None:
            self._header(fields)
            return _SKIP
        r = self._roles
        cols = self._cols

        def num(name: str) -> float:
            i = cols[name]
            v = fields[i].strip() if i < len(fields) else ""
            return float(v) if v else float("nan")

        t = _time(num(r["t"]))
        ev = r.get("event")
        if ev is not None and cols[ev] < len(fields) and fields[cols[ev]].strip():
            det = fields[cols[r["detail"]]].strip() if r.get("detail") and cols[r["detail"]] < len(fields) else ""
            detail = json.loads(det) if det else {}
            if fields[cols[ev]].strip() == GNSS_EVENT:  # a fix the view recorded (attitude_c.view.stream)
                return Parsed("gnss", t, gnss=gnss_fix(detail))
            return Parsed("event", t, event=fields[cols[ev]].strip(), detail=detail)
        q = [num(c) for c in r["q"]] if r.get("q") else None
        eul = None
        if r.get("euler_deg"):
            eul = [num(c) * _RAD for c in r["euler_deg"]]
        elif r.get("euler_rad"):
            eul = [num(c) for c in r["euler_rad"]]
        rate = [num(c) * _RAD for c in r["rate"]] if r.get("rate") else None
        tq = [num(c) for c in r["true_q"]] if r.get("true_q") else None
        h = num(r["heading"]) * _RAD if r.get("heading") else None
        n = num(r["n"]) if r.get("n") else None
        p = Parsed("sample", t, sample=row(t, q, n=n, rate=rate, q_true=tq, euler=eul, heading=h))
        if r.get("bias"):
            bits = num("flags") if "flags" in cols else math.nan
            p.counters = _filter_counters([num(c) for c in r["bias"]], int(bits) if math.isfinite(bits) else None)
        return p

    def _header(self, fields: list[str]) -> None:
        names = [f.strip() for f in fields]
        cols = {n: i for i, n in enumerate(names)}
        r: dict[str, Any] = {}
        r["t"] = next((c for c in _CSV_TIME if c in cols), None)
        r["q"] = next((g for g in _CSV_Q if all(c in cols for c in g)), None)
        r["true_q"] = next((g for g in _CSV_TRUE_Q if all(c in cols for c in g)), None)
        r["euler_deg"] = _CSV_EULER_DEG if all(c in cols for c in _CSV_EULER_DEG) else None
        r["euler_rad"] = next((g for g in _CSV_EULER_RAD if all(c in cols for c in g)), None)
        r["rate"] = _CSV_RATE_DPS if all(c in cols for c in _CSV_RATE_DPS) else None
        r["bias"] = _CSV_BIAS_DPS if all(c in cols for c in _CSV_BIAS_DPS) else None
        r["heading"] = "heading_deg" if "heading_deg" in cols else None
        r["n"] = "n" if "n" in cols else None
        r["event"] = "event" if "event" in cols else None
        r["detail"] = "detail" if "detail" in cols else None
        if r["t"] is None or not (r["q"] or r["euler_deg"] or r["euler_rad"]):
            raise ValueError("not a header this reader knows: it needs a time column (t) and the attitude "
                             "(q0..q3, or yaw_deg, pitch_deg, roll_deg): attitude-rx's CSV, a view "
                             "recording or attitude simulate's timeseries.csv")
        self._cols, self._roles = cols, r


def _time(v: Any, required: bool = True) -> float:
    """A line's source time: a finite number of seconds within ±:data:`MAX_TIME_S` (NaN when
    absent and not ``required``)."""
    t = float("nan") if v is None else float(v)
    if math.isnan(t) and not required:
        return t
    if not (math.isfinite(t) and abs(t) <= MAX_TIME_S):
        raise ValueError(f"time {v!r}: must be a finite number of seconds within ±{MAX_TIME_S:g}")
    return t


def _apply(p: Parsed, hub: Hub, src: Source) -> None:
    if p.kind == "sample" and p.sample is not None:
        hub.samples([p.sample])
        if p.counters:
            src.set_counts(p.counters)
        if p.gnss is not None:
            hub.gnss(p.t, p.gnss)
    elif p.kind == "gnss" and p.gnss is not None:
        hub.gnss(p.t, p.gnss)
    elif p.kind == "event":
        hub.event(p.t, p.event, p.detail)
    elif p.kind == "counters" and p.counters:
        if "other_records" in p.counters:
            src.count("other_records")
        else:
            src.set_counts(p.counters)


class _StoppableFd(io.RawIOBase):
    """A descriptor read only when it has data, or not at all once :meth:`wake` was
    called: the reading thread then sees the end of the input and returns. The
    source's thread never blocks inside a buffered object of the interpreter's
    (sys.stdin), which a daemon thread would hold locked at exit (CPython aborts
    with "_enter_buffered_busy" when it flushes standard input at shutdown)."""

    def __init__(self, fd: int) -> None:
        super().__init__()
        self._fd = fd
        self._wake_lock = threading.Lock()  # wake() (any thread) never writes to a closed, reused descriptor
        self._wake_r, self._wake_w = os.pipe()
        self._sel = selectors.DefaultSelector()
        self._sel.register(fd, selectors.EVENT_READ)
        self._sel.register(self._wake_r, selectors.EVENT_READ)

    def readable(self) -> bool:
        return True

    def readinto(self, buf: Any) -> int:
        ready = {key.fd for key, _ in self._sel.select()}
        if self._wake_r in ready:
            return 0
        data = os.read(self._fd, len(buf))
        buf[:len(data)] = data
        return len(data)

    def wake(self) -> None:
        with self._wake_lock, contextlib.suppress(OSError):
            if self._wake_w >= 0:
                os.write(self._wake_w, b"x")

    def close(self) -> None:
        with self._wake_lock:
            if self._wake_w >= 0:
                self._sel.close()
                os.close(self._wake_r)
                os.close(self._wake_w)
                self._wake_r = self._wake_w = -1
        super().close()


class StdinSource(Source):
    """attitude-rx's output on a stream (``attitude-rx --format jsonl | attitude view --stdin``).

    A broken line (not JSON or CSV this reader knows, longer than
    :data:`attitude_c._text.MAX_LINE`, not UTF-8) is counted (``bad_lines``)
    and shown as an error event, never fatal. End of input makes the source
    *lost* ("input ended"). A stream with a descriptor is read through it
    (:meth:`stop` then ends the thread even while the input is idle)."""

    def __init__(self, stream: IO[bytes] | IO[str], name: str = "stdin") -> None:
        super().__init__()
        self.stream = stream
        self.description = f"{name} (attitude-rx JSON Lines or CSV)"
        self.name = name
        self._fd: _StoppableFd | None = None
        with contextlib.suppress(AttributeError, OSError, ValueError):
            self._fd = _StoppableFd(stream.fileno())

    def stop(self) -> None:
        super().stop()
        if self._fd is not None:
            self._fd.wake()

    def _lines(self) -> Iterator[tuple[int, str, str | None]]:
        if self._fd is not None:
            yield from _text.lines(io.BufferedReader(self._fd, 1 << 16))
        elif isinstance(self.stream, io.TextIOBase):
            for k, line in enumerate(self.stream, 1):
                yield k, line, None
        else:
            yield from _text.lines(self.stream)  # type: ignore[arg-type]

    def run(self, hub: Hub) -> None:
        reader = LineReader()
        hub.status("running", f"reading {self.name}")
        last_t = 0.0
        try:
            for lineno, line, problem in self._lines():
                if self._stop.is_set():
                    return
                self.count("lines")
                try:
                    if problem is not None:
                        raise ValueError(problem)
                    p = reader.feed(line)
                except ValueError as exc:
                    self.count("bad_lines")
                    hub.event(last_t, "error", {"error": f"{self.name} line {lineno}: {exc}",
                                                "line": _text.clip(line.strip(), 200)})
                    continue
                if math.isfinite(p.t):
                    last_t = p.t
                _apply(p, hub, self)
        finally:
            if self._fd is not None:
                self._fd.close()
        if not self._stop.is_set():
            hub.status("lost", f"input ended ({self.name} closed)")


# ---------------------------------------------------------------------------------------
# replay
# ---------------------------------------------------------------------------------------

#: An item of a replay: (source time, what, payload) -- a sample row, an
#: event (kind, detail), a GNSS fix (:func:`gnss_fix`'s dict) or counters.
Item = tuple[float, str, Any]


def pace(hub: Hub, items: Iterable[Item], speed: float, stop: threading.Event,
         on_counters: Callable[[dict[str, Any]], None] | None = None,
         clock: Callable[[], float] = time.monotonic) -> int:
    """Hand ``items`` to the hub at ``speed`` times their source time (a time
    going backwards continues from where it was). Returns the number of
    samples handed over; stops early (returning) when ``stop`` is set."""
    w0 = clock()
    t0: float | None = None
    last_t = -math.inf
    batch: list[Sample] = []
    n = 0
    for t, what, payload in items:
        if t0 is None:
            t0 = t
        if t < last_t:  # the recording's clock started again: keep going from here
            t0 -= last_t - t
        last_t = t
        due = w0 + (t - t0) / speed
        now = clock()
        if due > now:
            if batch:
                hub.samples(batch)
                batch = []
            while due > now:
                if stop.wait(min(due - now, 0.05)):
                    return n
                now = clock()
        if stop.is_set():
            return n
        if what == "sample":
            batch.append(payload)
            n += 1
            if len(batch) >= 256:
                hub.samples(batch)
                batch = []
            continue
        if batch:
            hub.samples(batch)
            batch = []
        if what == "event":
            hub.event(t, payload[0], payload[1])
        elif what == "gnss":
            hub.gnss(t, payload)
        elif what == "counters" and on_counters is not None:
            on_counters(payload)
    if batch:
        hub.samples(batch)
    return n


@dataclass
class Recording:
    """A recording checked for replay: its lines (read again, streaming, by
    :meth:`items` when it plays: memory does not grow with the file), or BROAD's
    arrays."""

    name: str
    kind: Literal["lines", "broad"]
    samples: int
    path: Path | None = None
    trial: Any = None  # attitude_c.broad.Trial for kind "broad"

    def items(self, on_bad: Callable[[int, str], None] | None = None) -> Iterator[Item]:
        """The items of a recording of lines, in order (``on_bad(line, why)`` for a line
        that cannot be read now; default: raise :class:`InvalidArgument`)."""
        assert self.path is not None
        yield from _line_items(self.path, on_bad or _refuse(self.path))


def _refuse(path: Path) -> Callable[[int, str], None]:
    def bad(lineno: int, why: str) -> None:
        raise InvalidArgument(f"recording {str(path)!r} line {lineno}: {why}")
    return bad


def _line_items(path: Path, on_bad: Callable[[int, str], None]) -> Iterator[Item]:
    reader = LineReader()
    last_t = 0.0
    with open(path, "rb") as fh:
        for lineno, line, problem in _text.lines(fh):
            try:
                if problem is not None:
                    raise ValueError(problem)
                x = reader.feed(line)
            except ValueError as exc:
                on_bad(lineno, str(exc))
                continue
            t = x.t if math.isfinite(x.t) else last_t
            if x.kind == "sample":
                yield t, "sample", x.sample
            elif x.kind == "event":
                yield t, "event", (x.event, x.detail)
            elif x.kind == "counters" and x.counters:
                yield t, "counters", x.counters
            if x.gnss is not None:  # a sample's fix, after it; or a recorded fix
                yield t, "gnss", x.gnss
            last_t = t


def load_recording(path: str | Path) -> Recording:
    """Check a recording: attitude-rx's JSON Lines or CSV, a view recording
    (CSV), ``attitude simulate``'s ``timeseries.csv``, or a BROAD trial
    (``.mat``). Every line is read once, streaming (the replay reads them
    again). Raises :class:`InvalidArgument` naming the file (and line)."""
    p = Path(path)
    if not p.is_file():
        raise InvalidArgument(f"recording {str(p)!r}: no such file")
    if p.suffix.lower() == ".mat":
        from .. import broad

        trial = broad.load_trial(p)
        return Recording(p.name, "broad", trial.n, p, trial)
    try:
        _text.probe_text(p)
        rec = Recording(p.name, "lines", 0, p)
        samples = sum(1 for _, what, _ in rec.items() if what == "sample")
    except OSError as exc:
        raise InvalidArgument(f"recording {str(p)!r}: cannot read it ({exc.strerror or exc})") from None
    if samples == 0:
        raise InvalidArgument(f"recording {str(p)!r}: no attitude sample in it")
    rec.samples = samples
    return rec


def _broad_items(trial: Any, estimator: Estimator) -> Iterator[Item]:
    """BROAD samples through the estimator, with the optical reference as the truth."""
    dt = trial.dt
    gyr, acc, mag, quat = trial.gyr, trial.acc, trial.mag, trial.quat
    for k in range(trial.n):
        q = estimator.update(gyr[k], dt, acc[k], mag[k])
        if q is None:
            continue
        tq = quat[k] if np.isfinite(quat[k]).all() else None
        yield ((k + 1) * dt, "sample", row((k + 1) * dt, q, n=k, rate=gyr[k], q_true=tq))


def _has_data(a: NDArray[np.float64]) -> bool:
    """A sensor's columns hold at least one finite sample."""
    return bool(np.isfinite(a).all(axis=1).any())


class ReplaySource(Source):
    """A recording replayed at ``speed`` times real time. BROAD trials run
    through an estimator (``estimator``, ``method``) started at the first
    valid optical reference attitude, with the reference drawn as the truth.

    ``estimator="auto"`` (the default) runs the attitude filter when the trial has
    accelerometer and magnetometer data, else the integrator
    (:func:`~attitude_c.view.estimators.choose`); a ``method`` given asks for the
    integrator (default ``rv3``); ``settings``: the attitude filter's settings
    (``attitude view --ahrs-setting``). The description says which runs, and why."""

    def __init__(self, path: str | Path, speed: float = 1.0, estimator: str = AUTO,
                 method: str | None = None, settings: Mapping[str, Any] | None = None) -> None:
        super().__init__()
        if not (math.isfinite(speed) and speed > 0):
            raise InvalidArgument(f"speed must be a finite number > 0, got {speed!r}")
        self.speed = speed
        self.rec = load_recording(path)
        self.estimator: Estimator | None = None
        what = "recording"
        if self.rec.kind == "broad":
            trial = self.rec.trial
            ok = np.isfinite(trial.quat).all(axis=1)
            q0 = trial.quat[int(np.flatnonzero(ok)[0])] if ok.any() else None
            name, why = choose(estimator, has_acc=_has_data(trial.acc), has_mag=_has_data(trial.mag),
                               method_given=method is not None)
            self.estimator = make_estimator(name, has_acc=True, method=method or "rv3", q0=q0, rate=trial.rate,
                                            settings=settings)
            what = f"BROAD trial, {self.estimator.label}" + (f"; {why}" if why else "")
        elif settings:
            raise InvalidArgument(f"filter settings: {self.rec.name} runs through no filter (a BROAD trial does)")
        self.description = f"replay of {self.rec.name} ({what}) at {speed:g}x"

    def run(self, hub: Hub) -> None:
        through = f" through {self.estimator.label}" if self.estimator else ""
        hub.status("running", f"replaying {self.rec.name} at {self.speed:g}x{through}")
        if self.rec.kind == "broad":
            assert self.estimator is not None
            items: Iterable[Item] = _broad_items(self.rec.trial, self.estimator)
        else:
            items = self.rec.items(lambda lineno, why: self._bad_line(hub, lineno, why))
        n = pace(hub, items, self.speed, self._stop, on_counters=self.set_counts)
        self.set_counts({"replayed": n})
        if not self._stop.is_set():
            hub.status("ended", f"replay of {self.rec.name} finished ({n} samples)")

    def _bad_line(self, hub: Hub, lineno: int, why: str) -> None:
        """A line that changed since the check: counted, shown, and the replay goes on."""
        self.count("bad_lines")
        hub.event(float("nan"), "error", {"error": f"{self.rec.name} line {lineno}: {why}"})


# ---------------------------------------------------------------------------------------
# serial port: the Python host end, the block decoder, an estimator
# ---------------------------------------------------------------------------------------

Triple = Union[float, tuple[float, float, float]]


def _triple(v: Triple, name: str) -> NDArray[np.float64]:
    a = np.broadcast_to(np.asarray(v, dtype=np.float64), (3,)).copy()
    if not np.isfinite(a).all():
        raise InvalidArgument(f"{name} must be finite, got {v!r}")
    return a


class BlockPipeline:
    """Records of accepted link blocks -> numbered samples -> body rates -> estimator.

    The Python counterpart of attitude-rx's attitude thread, on libattitude's
    block decoder and sequence tracker (:mod:`attitude_c.link.block`): the
    period comes from BOOT unless ``period_fixed``; codes become rates through
    the library's one converter (:class:`attitude_c.sensor.Sensor`: ``(code -
    zero) * scale``, sums of an OVERSAMPLE stream included); a lost sample (a loss report, a code out of
    range) is held at the last good rate so the time base stays the
    firmware's. ``count(name, k)`` receives the counters.
    """

    def __init__(self, hub: Hub, estimator: Estimator, count: Callable[[str, float], None], *,
                 period: float, period_fixed: bool, zero: Triple = DEFAULT_ZERO_CODE,
                 scale: Triple = DEFAULT_SCALE) -> None:
        from ..link import block

        self.block = block
        self.fmt = block.fmt()
        self.tracker = block.SeqTracker()
        self.hub = hub
        self.estimator = estimator
        self.count = count
        self.period = float(period)
        self.period_fixed = period_fixed
        self.zero = _triple(zero, "zero")
        self.scale = _triple(scale, "scale")
        from ..sensor import Sensor

        self.sensor = Sensor(self.zero, self.scale)
        if not (math.isfinite(self.period) and self.period > 0):
            raise InvalidArgument(f"period must be a finite number > 0 s, got {period!r}")
        self.t = 0.0
        self.rate: NDArray[np.float64] | None = None

    def feed_block(self, blk: bytes) -> None:
        size = self.fmt.size
        for k in range(0, len(blk) - size + 1, size):
            self.feed_record(blk[k:k + size])

    def feed_record(self, raw: bytes) -> None:
        # the receiver's one call: decode with the stream's limit and place (att_block_seq_decode)
        rec, span, st = self.tracker.decode(raw)
        from ..names import C
        if span is None or rec is None:  # unknown kind or a field out of range: no place in the numbering
            self.count("block_errors", 1)
            self.hub.event(self.t, "error", {"error": self.fmt.errors.get(st, str(st)), "raw": raw.hex()})
            return
        if st == C["ATT_BLOCK_E_SEQ"]:
            self.count("slips", 1)
            if span.slip < 0:
                self.count("duplicates", -span.slip)  # samples the numbering had counted twice
        if rec.kind == "sample":
            self.count("samples", 1)
            if st == C["ATT_BLOCK_E_CODE"]:
                self.count("code_errors", 1)
                self.hub.event(self.t, "error", {"error": self.tracker.error(st), "n": span.first,
                                                 "codes": list(rec.codes)})
                self._hold(span.first, 1)
                return
            rate = self.sensor.convert([rec.codes], self.tracker.oversample)[0].astype(np.float64)
            self.rate = rate
            self._integrate(span.first, rate)
            return
        detail = rec.as_dict()
        name = detail.pop("report")
        if rec.kind == "boot" and not self.period_fixed:
            self.period = rec.period_s
        if rec.is_loss:
            detail.update(first=span.first, count=span.count, slip=span.slip)
        self.hub.event(self.t, name, detail)
        if rec.is_loss:
            self._hold(span.first, span.count)

    def _hold(self, first: int, count: int) -> None:
        self.count("missing", count)
        if self.rate is None:  # nothing to hold before the first good sample: time passes
            self.t += count * self.period
            return
        self.count("held", count)
        for k in range(count):
            self._integrate(first + k, self.rate)

    def _integrate(self, n: int, rate: NDArray[np.float64]) -> None:
        q = self.estimator.update(rate, self.period)
        self.t += self.period
        if q is not None:
            self.hub.samples([row(self.t, q, n=n, rate=rate)])


class SerialSource(Source):
    """A serial port or pyserial URL running libattitude's receiver B
    (``impl`` "c" or "python"), the block decoder and an estimator.

    The port is opened here (an error raises before the server starts). A
    port that fails later makes the source *lost* and is reopened every
    :data:`REOPEN_S` seconds."""

    def __init__(self, url: str, *, baud: int = 9600, block_size: int = 6, impl: str = "c",
                 gap_timeout_ms: int = 20, estimator: str = AUTO, method: str | None = None,
                 period: float | None = None, zero: Triple = DEFAULT_ZERO_CODE,
                 scale: Triple = DEFAULT_SCALE) -> None:
        super().__init__()
        from ..link import block
        from ..link.cends import make_receiver
        from ..link.transport import open_port

        size = block.fmt().size
        if block_size <= 0 or block_size % size:
            raise InvalidArgument(f"block_size must be a multiple of {size} (records of the block format), "
                                  f"got {block_size}")
        self.url, self.baud, self.block_size, self.impl = url, baud, block_size, impl
        self.gap_timeout_ms = gap_timeout_ms
        self._make_rx = lambda: make_receiver(impl, block_size=block_size, gap_timeout=gap_timeout_ms)  # type: ignore[arg-type]
        self._rx = self._make_rx()  # checks block size and timeout
        name, _ = choose(estimator, has_acc=False, has_mag=False)  # the link carries the gyros only
        self.estimator = make_estimator(name, has_acc=False, method=method or "rv3")
        self.period_fixed = period is not None
        self.period = period if period is not None else DEFAULT_PERIOD_TICKS / block.fmt().tick_hz
        self.zero, self.scale = zero, scale
        self.port: Any = open_port(url, baud)
        self._rx_totals: dict[str, int] = {}
        self.description = (f"serial {url} ({baud} 8N1, block {block_size}, receiver {impl}, "
                            f"{self.estimator.label})")

    def counters(self) -> dict[str, Any]:
        out = super().counters()
        stats = self._rx.stats.as_dict()
        for k, v in stats.items():
            out[k] = v + self._rx_totals.get(k, 0)
        out["blocks"] = out.pop("blocks_accepted", 0)
        return out

    def run(self, hub: Hub) -> None:
        from ..link.transport import open_port, run_receiver

        pipe = BlockPipeline(hub, self.estimator, self.count, period=self.period,
                             period_fixed=self.period_fixed, zero=self.zero, scale=self.scale)
        hub.status("running", f"listening on {self.url}")
        try:
            while not self._stop.is_set():
                rep = run_receiver(self.port, receiver=self._rx, impl=self.impl,  # type: ignore[arg-type]
                                   block_size=self.block_size, on_block=pipe.feed_block, stop=self._stop,
                                   keep_blocks=False)
                if rep.ended_by == "stop":
                    break
                hub.status("lost", f"port {self.url} failed: {rep.error}; reopening every {REOPEN_S:g} s")
                self._close_port()
                while not self._stop.wait(REOPEN_S):
                    try:
                        self.port = open_port(self.url, self.baud)
                    except AttitudeError:
                        continue
                    for k, v in self._rx.stats.as_dict().items():
                        self._rx_totals[k] = self._rx_totals.get(k, 0) + v
                    self._rx = self._make_rx()
                    self.count("reopens", 1)
                    hub.event(pipe.t, "note", {"note": f"port {self.url} reopened"})
                    hub.status("running", f"listening on {self.url}")
                    break
        finally:
            self._close_port()

    def _close_port(self) -> None:
        with contextlib.suppress(OSError):  # closing a failed port may fail again (SerialException is one)
            if self.port is not None:
                self.port.close()
