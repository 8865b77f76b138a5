"""Stream handling of the display: samples in, every sample recorded,
display frames out at the display rate to any number of clients.

Sources run in their own threads and hand samples to the :class:`Hub` with
:meth:`Hub.samples` (rows of :data:`COLUMNS`, SI units, NaN where unknown),
reports and errors with :meth:`Hub.event`, their condition with
:meth:`Hub.status`. These calls only append to a queue: they never wait for
the event loop, the disk or a browser, so a source is never slowed.

On the event loop, :meth:`Hub.tick` (``display_rate`` times a second)
takes everything queued, in order, completes each sample in one vectorized
pass (Euler angles and heading from the quaternion, body rates from
successive attitudes where the source has none, the truth's angles), hands
the batch to the :class:`Recorder` (a CSV file written by its own thread:
every sample, in order) and builds one display frame: the newest sample,
the min/max envelope of each charted channel over the tick (decimation that
keeps peaks), the counters and the stream's state. The frame is serialized
once and offered to every :class:`Client`'s bounded queue; a client whose
queue is full loses its oldest frame (a slow browser drops display frames,
never samples). The last ``history_s`` seconds of chart points are kept (a
bounded ring) for tabs that connect later.
"""

from __future__ import annotations

import asyncio
import collections
import concurrent.futures
import csv
import io
import itertools
import json
import math
import os
import shutil
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import core
from ..errors import InvalidArgument

__all__ = ["CHART_COLUMNS", "COLUMNS", "CSV_HEADER", "GNSS_EVENT", "Client", "Hub", "Recorder", "SourceState", "row"]

#: One sample as sources hand it over: time (s, the source's clock), sample
#: number (NaN if the source has none), attitude quaternion (scalar first,
#: body -> ENU), body rates (rad/s), the true attitude (simulator, BROAD's
#: optical reference), Euler angles [yaw, pitch, roll] and heading (rad).
#: NaN means "not given": angles are then computed from q, rates from
#: successive attitudes, and a NaN truth means "none".
COLUMNS: tuple[str, ...] = ("t", "n", "q0", "q1", "q2", "q3", "rate_x", "rate_y", "rate_z",
                            "true_q0", "true_q1", "true_q2", "true_q3", "yaw", "pitch", "roll", "heading")
_T, _N, _Q, _RATE, _TQ, _EUL, _HEAD = 0, 1, slice(2, 6), slice(6, 9), slice(9, 13), slice(13, 16), 16
WIDTH = len(COLUMNS)

#: The recording's columns (degrees for angles, deg/s for rates; reports and
#: errors are rows of their own with ``event`` set and ``detail`` as JSON).
CSV_HEADER: tuple[str, ...] = (
    "t", "n", "q0", "q1", "q2", "q3", "yaw_deg", "pitch_deg", "roll_deg", "heading_deg",
    "rate_x_dps", "rate_y_dps", "rate_z_dps", "true_q0", "true_q1", "true_q2", "true_q3",
    "true_yaw_deg", "true_pitch_deg", "true_roll_deg", "true_heading_deg", "event", "detail")

#: A chart point (one per display frame with data): display time, then for
#: yaw, pitch, roll (deg) and rate x, y, z (deg/s) the newest value and the
#: min and max over the frame's samples, then the truth's yaw, pitch, roll,
#: the heading and true heading (deg), and the ground speed of the newest GNSS
#: fix (m/s; null without a valid fix with a speed).
CHART_COLUMNS: tuple[str, ...] = (
    "t", "yaw", "yaw_min", "yaw_max", "pitch", "pitch_min", "pitch_max", "roll", "roll_min", "roll_max",
    "rate_x", "rate_x_min", "rate_x_max", "rate_y", "rate_y_min", "rate_y_max",
    "rate_z", "rate_z_min", "rate_z_max", "true_yaw", "true_pitch", "true_roll", "heading", "true_heading",
    "gnss_speed")

#: The recording's event kind of a GNSS fix (its ``detail``: the fix as
#: :func:`attitude_c.view.sources.gnss_fix` checked it); not a report: not listed
#: among the events nor counted.
GNSS_EVENT = "gnss"

#: What a source says of itself: getting ready, delivering, finished (a
#: replay or a simulation that ran to its end), or gone (EOF, port failure).
SourceState = Literal["starting", "running", "ended", "lost"]
_SOURCE_STATES = ("starting", "running", "ended", "lost")

#: Event kinds that are notes, not counted as reports or errors.
_NOTE = "note"

#: The longest history a hub keeps (s): the page's longest chart window (10 min).
HISTORY_MAX_S = 600.0
#: The display rate's range (frames/s): at least one frame a second (the stall and
#: rate figures need it), at most 100 (more than a screen refreshes).
DISPLAY_RATE_MIN, DISPLAY_RATE_MAX = 1.0, 100.0
#: Chart points per history message: a tab that connects gets the history in
#: messages of this many points (about 150 bytes each: ~75 kB a message), each sent
#: when the previous one was taken by the socket, so a tab that does not read
#: holds one such message in the server, never the whole history.
HISTORY_CHUNK = 500
#: Serialized size (bytes) above which an event's detail is replaced by its start.
DETAIL_MAX = 2048

_DEG = 180.0 / math.pi


def row(t: float, q: ArrayLike | None = None, *, n: float | None = None, rate: ArrayLike | None = None,
        q_true: ArrayLike | None = None, euler: ArrayLike | None = None,
        heading: float | None = None) -> tuple[float, ...]:
    """One sample in the layout of :data:`COLUMNS` (rad, rad/s; None: not given)."""
    out = [float("nan")] * WIDTH
    out[_T] = float(t)
    if n is not None:
        out[_N] = float(n)
    for sl, v, k in ((_Q, q, 4), (_RATE, rate, 3), (_TQ, q_true, 4), (_EUL, euler, 3)):
        if v is not None:
            vals = [float(x) for x in np.asarray(v, dtype=float).reshape(-1)]
            if len(vals) != k:
                raise InvalidArgument(f"row: {COLUMNS[sl.start]}..: expected {k} values, got {len(vals)}")
            out[sl] = vals
    if heading is not None:
        out[_HEAD] = float(heading)
    return tuple(out)


def _as_rows(rows: ArrayLike | Sequence[Sequence[float]]) -> NDArray[np.float64]:
    a = np.array(rows, dtype=np.float64, copy=True)
    if a.ndim == 1:
        a = a.reshape(1, -1)
    if a.ndim != 2 or a.shape[1] != WIDTH:
        raise InvalidArgument(f"rows must have shape (k, {WIDTH}) (attitude_c.view.COLUMNS), got {a.shape}")
    return a


def _good_quat(q: NDArray[np.float64]) -> NDArray[np.bool_]:
    return np.isfinite(q).all(axis=1) & (np.abs(q).sum(axis=1) > 0)


def _wrap_deg(x: NDArray[np.float64]) -> NDArray[np.float64]:
    return (x + 180.0) % 360.0 - 180.0


def _is_real(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _num(x: float, nd: int = 3) -> float | None:
    """JSON-ready number (NaN -> null)."""
    return round(float(x), nd) if math.isfinite(x) else None


def json_safe(detail: dict[str, Any]) -> dict[str, Any]:
    """``detail`` as strict JSON can carry it: non-finite numbers become None,
    other objects their ``str``; nesting deeper than 20 levels, or a detail whose
    JSON exceeds :data:`DETAIL_MAX` bytes, becomes ``{"truncated": its start}``."""
    def walk(x: Any, depth: int) -> Any:
        if isinstance(x, float):
            return x if math.isfinite(x) else None
        if x is None or isinstance(x, (bool, int, str)):
            return x
        if depth > 20:
            raise ValueError("nested too deep")
        if isinstance(x, dict):
            return {str(k): walk(v, depth + 1) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [walk(v, depth + 1) for v in x]
        return str(x)

    text: str | None = None
    try:
        out = walk(detail, 0)
        text = json.dumps(out, separators=(",", ":"), allow_nan=False)
    except (ValueError, RecursionError):
        pass
    if text is not None and len(text) <= DETAIL_MAX:
        return out  # type: ignore[no-any-return]
    return {"truncated": (text or repr(detail)[:DETAIL_MAX])[:DETAIL_MAX // 2]}


@dataclass
class _Event:
    t: float
    kind: str
    detail: dict[str, Any]


@dataclass
class _Processed:
    """A batch of samples after completion (angles in rad, truth angles apart)."""

    a: NDArray[np.float64]        # (k, WIDTH)
    td: NDArray[np.float64]       # (k,) display time (monotonic)
    true_eul: NDArray[np.float64]  # (k, 3) rad, NaN without truth
    true_head: NDArray[np.float64]  # (k,) rad


_Item = Union[_Processed, _Event]


class Recorder:
    """Every sample and event, in order, in a CSV file (:data:`CSV_HEADER`),
    written by one worker thread so the event loop never waits for the disk.

    ``path``: where the recording is kept (written to ``PATH.part`` and
    renamed into place by :meth:`close` when complete, else to
    :func:`partial_name`); None keeps it in a temporary directory removed by
    :meth:`close`.
    """

    def __init__(self, path: str | Path | None = None) -> None:
        self.keep = Path(path) if path is not None else None
        if self.keep is not None:
            self._tmpdir: Path | None = None
            self.path = self.keep.with_name(self.keep.name + ".part")
        else:
            self._tmpdir = Path(tempfile.mkdtemp(prefix="attitude-view-"))
            self.path = self._tmpdir / "recording.csv"
        self._fh = open(self.path, "w", newline="", encoding="utf-8", buffering=1 << 16)  # noqa: SIM115
        self._fh.write(",".join(CSV_HEADER) + "\n")
        self._pool = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="view-recorder")
        self._lock = threading.Lock()
        self.samples = 0  #: sample rows written so far (worker thread)
        self.events = 0   #: event rows written so far
        self.error: str | None = None  #: the first write error (recording stopped there)
        self._closed = False

    def write(self, items: Sequence[_Item]) -> None:
        """Queue items for writing (returns at once)."""
        if items and not self._closed:
            self._pool.submit(self._write, list(items))

    def _write(self, items: list[_Item]) -> None:
        if self.error is not None:
            return
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        ns = ne = 0
        for it in items:
            if isinstance(it, _Event):
                w.writerow([_g(it.t)] + [""] * (len(CSV_HEADER) - 3)
                           + [it.kind, json.dumps(it.detail, separators=(",", ":")) if it.detail else ""])
                ne += 1
                continue
            a = it.a
            deg = np.concatenate([a[:, _EUL], a[:, _HEAD:_HEAD + 1]], axis=1) * _DEG
            tdeg = np.concatenate([it.true_eul, it.true_head[:, None]], axis=1) * _DEG
            for i in range(a.shape[0]):
                r = a[i]
                fields = [_g(r[_T]), "" if not math.isfinite(r[_N]) else str(int(r[_N]))]
                fields += [_g(x) for x in r[_Q]]
                fields += [_g(x) for x in deg[i]]
                fields += [_g(x * _DEG) for x in r[_RATE]]
                fields += [_g(x) for x in r[_TQ]]
                fields += [_g(x) for x in tdeg[i]]
                buf.write(",".join(fields) + ",,\n")
            ns += a.shape[0]
        try:
            self._fh.write(buf.getvalue())
        except OSError as exc:
            self.error = f"recording {self.path}: {exc.strerror or exc}"
            return
        with self._lock:
            self.samples += ns
            self.events += ne

    def snapshot(self) -> concurrent.futures.Future[tuple[Path, int]]:
        """A future of ``(path, size)``: everything queued before the call is
        on disk and the first ``size`` bytes are a complete CSV."""
        return self._pool.submit(self._flush)

    def _flush(self) -> tuple[Path, int]:
        if self.error is None:
            try:
                self._fh.flush()
            except OSError as exc:
                self.error = f"recording {self.path}: {exc.strerror or exc}"
        return self.path, self._fh.tell() if self.error is None else os.path.getsize(self.path)

    def counts(self) -> tuple[int, int]:
        with self._lock:
            return self.samples, self.events

    def close(self, complete: bool = True) -> Path | None:
        """Finish writing. Returns the kept recording's path: ``FILE`` when the
        recording is complete, :func:`partial_name` (``FILE.partial.csv``, cut
        after its last whole row) when it is not -- ``complete`` False (the
        stream was cut short) or a write failed (:attr:`error` says why) --
        None when it was temporary or nothing could be kept."""
        if self._closed:
            return self.path if self.keep is not None and self.path.exists() else None
        self._closed = True
        self._pool.submit(self._flush).result()
        self._pool.shutdown(wait=True)
        try:
            self._fh.close()
        except OSError as exc:
            self.error = self.error or f"recording {self.path}: {exc.strerror or exc}"
        if self._tmpdir is not None:
            shutil.rmtree(self._tmpdir, ignore_errors=True)
            return None
        assert self.keep is not None
        dest = self.keep if complete and self.error is None else partial_name(self.keep)
        try:
            if dest != self.keep:
                _cut_after_last_row(self.path)
            os.replace(self.path, dest)
        except OSError as exc:
            self.error = self.error or f"recording {self.path}: {exc.strerror or exc}"
            return None
        self.path = dest
        return dest


def partial_name(path: Path) -> Path:
    """Where a recording that is not complete is kept: ``run.csv`` -> ``run.partial.csv``."""
    return path.with_name(f"{path.stem}.partial{path.suffix or '.csv'}")


def _cut_after_last_row(path: Path) -> None:
    """Truncate ``path`` after its last newline (a write that failed may have cut a row)."""
    with open(path, "rb+") as fh:
        end = fh.seek(0, os.SEEK_END)
        pos = end
        while pos > 0:
            step = min(1 << 16, pos)
            fh.seek(pos - step)
            block = fh.read(step)
            k = block.rfind(b"\n")
            if k >= 0:
                fh.truncate(pos - step + k + 1)
                return
            pos -= step
        fh.truncate(0)


def _g(x: float) -> str:
    return "" if not math.isfinite(x) else f"{x:.9g}"


class Client:
    """One connected display: a bounded queue of serialized frames.

    :meth:`offer` never waits: when the queue is full the oldest frame is
    dropped (counted in :attr:`dropped`). None in the queue means "closed".
    """

    def __init__(self, maxsize: int = 16) -> None:
        if maxsize < 1:
            raise InvalidArgument(f"maxsize must be >= 1, got {maxsize}")
        self.queue: asyncio.Queue[str | None] = asyncio.Queue(maxsize)
        self.dropped = 0
        self.offered = 0
        self.closed = False

    def offer(self, msg: str) -> None:
        if self.closed:
            return
        self.offered += 1
        if self.queue.full():
            try:
                self.queue.get_nowait()
                self.dropped += 1
            except asyncio.QueueEmpty:  # pragma: no cover - single-threaded: cannot happen
                pass
        self.queue.put_nowait(msg)

    def close(self) -> None:
        """Tell the client's writer to stop (whatever is still queued is dropped)."""
        if self.closed:
            return
        self.closed = True
        while not self.queue.empty():
            self.queue.get_nowait()
        self.queue.put_nowait(None)


@dataclass
class _Rate:
    """Samples and records per second over the last ``span`` seconds of wall time."""

    span: float = 2.0
    marks: collections.deque[tuple[float, int, float]] = field(default_factory=collections.deque)

    def add(self, now: float, count: int, n_last: float) -> None:
        self.marks.append((now, count, n_last))
        while len(self.marks) > 2 and now - self.marks[0][0] > self.span:
            self.marks.popleft()

    def rates(self, now: float) -> tuple[float, float]:
        """(records/s, samples/s by sample number; NaN when unknown), from the
        first tick with data in the window (what it brought arrived before it)
        to now: right when the stream has just started, falling when it stops."""
        m = [x for x in self.marks if now - x[0] <= self.span and x[1] > 0]
        if not m:
            return 0.0, 0.0
        dt = now - m[0][0]
        if len(m) < 2 or dt <= 0:
            return float("nan"), float("nan")
        recs = sum(c for _, c, _ in m[1:]) / dt
        ns = [n for _, _, n in m if math.isfinite(n)]
        sps = (ns[-1] - ns[0]) / dt if len(ns) >= 2 and ns[-1] >= ns[0] else float("nan")
        return recs, sps


class Hub:
    """Fan-out of one source to the recorder and any number of clients.

    ``display_rate``: frames per second sent to the browsers (the stream is
    decimated to it); ``history_s``: seconds of chart points kept for tabs
    that connect later (and the longest chart window); ``stall_s``: seconds
    without a sample before the stream counts as stalled (at least four
    typical intervals between samples); ``client_queue``: frames a client may
    have waiting before its oldest are dropped. ``clock``: wall clock
    (monotonic seconds), replaceable in tests.
    """

    def __init__(self, *, recorder: Recorder, description: str = "", display_rate: float = 25.0,
                 history_s: float = 600.0, stall_s: float = 1.0, client_queue: int = 16,
                 clock: Callable[[], float] = time.monotonic) -> None:
        for name, v in (("display_rate", display_rate), ("history_s", history_s), ("stall_s", stall_s)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InvalidArgument(f"{name} must be a finite number > 0, got {v!r}")
        if not DISPLAY_RATE_MIN <= display_rate <= DISPLAY_RATE_MAX:
            raise InvalidArgument(f"display_rate must be {DISPLAY_RATE_MIN:g}..{DISPLAY_RATE_MAX:g} frames/s, "
                                  f"got {display_rate!r}")
        if history_s > HISTORY_MAX_S:
            raise InvalidArgument(f"history_s must be at most {HISTORY_MAX_S:g} s, got {history_s!r}")
        self.recorder = recorder
        self.description = description
        self.display_rate = float(display_rate)
        self.history_s = float(history_s)
        self.stall_s = float(stall_s)
        self.client_queue = int(client_queue)
        self.clock = clock
        self.session = f"{os.getpid():x}-{int(time.time() * 1000):x}"
        # intake: appended by source threads, drained by tick() on the loop
        self._intake: collections.deque[tuple[str, Any]] = collections.deque()
        self._source_state: SourceState = "starting"
        self._source_text = ""
        self._counters: Callable[[], dict[str, Any]] = dict
        # loop side
        self.clients: set[Client] = set()
        # chart points, each kept serialized (a third of the memory of a list of floats)
        self.history: collections.deque[str] = collections.deque(
            maxlen=max(1, math.ceil(self.history_s * self.display_rate)))
        self.events: collections.deque[dict[str, Any]] = collections.deque(maxlen=100)
        self.event_counts: dict[str, int] = {}
        self.seq = 0
        self.points_total = 0  # chart points ever made (the ring holds the newest len(history))
        self.failure: str | None = None  # the first tick that failed: what it held is not recorded
        self.samples_in = 0
        self.frames_dropped = 0  # by clients that have gone, plus the live ones at frame time
        self._prev_q = np.full(4, np.nan)
        self._prev_t = float("nan")
        self._offset = 0.0  # display time = source time + offset (monotonic across restarts)
        self._last_td = -math.inf
        self._last: dict[str, Any] | None = None
        self._last_wall = -math.inf
        self._arrival = float("nan")  # typical wall time between ticks that brought samples (moving average)
        self._rate = _Rate()
        self._last_status: str = ""
        self._last_status_wall = -math.inf
        self._last_counters: str = ""
        self._gnss: dict[str, Any] | None = None  # the newest GNSS fix, with its time and the count so far
        self.gnss_fixes = 0

    # ---- source side (any thread) -------------------------------------------------

    def samples(self, rows: ArrayLike | Sequence[Sequence[float]]) -> None:
        """Queue samples (rows of :data:`COLUMNS`). Never blocks."""
        a = _as_rows(rows)
        if a.shape[0]:
            self._intake.append(("s", a))

    def event(self, t: float, kind: str, detail: dict[str, Any] | None = None) -> None:
        """Queue a report (``"BOOT"``, ``"OVERRUN"``...), an ``"error"`` or a
        ``"note"`` at source time ``t``. Never blocks. The detail is kept as JSON
        can carry it (:func:`json_safe`: NaN and infinities as null, at most
        :data:`DETAIL_MAX` bytes)."""
        self._intake.append(("e", _Event(float(t), str(kind)[:64], json_safe(dict(detail or {})))))

    def gnss(self, t: float, fix: dict[str, Any]) -> None:
        """Queue a GNSS fix at source time ``t`` (the dict of
        :func:`attitude_c.view.sources.gnss_fix`). Never blocks."""
        self._intake.append(("g", _Event(float(t), GNSS_EVENT, json_safe(dict(fix)))))

    def status(self, state: SourceState, text: str = "") -> None:
        """The source's own condition (see :data:`SourceState`)."""
        if state not in _SOURCE_STATES:
            raise InvalidArgument(f"state must be one of {_SOURCE_STATES}, got {state!r}")
        self._intake.append(("c", (state, str(text))))

    def counters_from(self, fn: Callable[[], dict[str, Any]]) -> None:
        """Where the link/source counters come from (called on the loop at each frame)."""
        self._counters = fn

    # ---- loop side ------------------------------------------------------------------

    def _complete(self, a: NDArray[np.float64]) -> _Processed:
        q = a[:, _Q]
        # attitude from Euler angles where only those were given
        eul_ok = np.isfinite(a[:, _EUL]).all(axis=1)
        need_q = ~_good_quat(q) & eul_ok
        if need_q.any():
            q[need_q] = core.euler_to_quat(a[need_q, _EUL])
        qok = _good_quat(q)
        need = np.isnan(a[:, _EUL]).any(axis=1) & qok
        if need.any():
            a[need, _EUL] = core.quat_to_euler(q[need])
        need = np.isnan(a[:, _HEAD]) & qok
        if need.any():
            a[need, _HEAD] = core.heading(q[need])
        # body rates from successive attitudes: Φ of q(k-1)* ⊗ q(k) over the time step
        t = a[:, _T]
        prev_q = np.vstack([self._prev_q[None, :], q[:-1]])
        prev_t = np.concatenate([[self._prev_t], t[:-1]])
        dt = t - prev_t
        need = np.isnan(a[:, _RATE]).any(axis=1) & qok & _good_quat(prev_q) & np.isfinite(dt) & (dt > 0)
        if need.any():
            dq = core.quat_multiply(core.quat_conj(prev_q[need]), q[need])
            a[need, _RATE] = core.quat_to_rotvec(dq) / dt[need, None]
        if qok.any():
            last = int(np.flatnonzero(qok)[-1])
            self._prev_q, self._prev_t = q[last].copy(), float(t[last])
        # the truth's angles
        tq = a[:, _TQ]
        te = np.full((a.shape[0], 3), np.nan)
        th = np.full(a.shape[0], np.nan)
        tok = _good_quat(tq)
        if tok.any():
            te[tok] = core.quat_to_euler(tq[tok])
            th[tok] = core.heading(tq[tok])
        # display time: monotonic even when the source's clock starts again
        td = t + self._offset
        for i in np.flatnonzero(np.diff(np.concatenate([[self._last_td], td])) < -1e-9):
            self._offset += self._last_td - td[i] if i == 0 else td[i - 1] - td[i]
            td[i:] = t[i:] + self._offset
        if td.size:
            self._last_td = float(td[-1])
        return _Processed(a, td, te, th)

    def tick(self) -> str | None:
        """Take everything queued, record it, and broadcast one frame (returned,
        serialized; None when nothing needed sending)."""
        now = self.clock()
        items: list[_Item] = []
        batches: list[_Processed] = []
        new_events: list[dict[str, Any]] = []
        pending: list[NDArray[np.float64]] = []
        gnss_new = False

        def flush_samples() -> None:
            if pending:
                p = self._complete(np.concatenate(pending) if len(pending) > 1 else pending[0])
                items.append(p)
                batches.append(p)
                pending.clear()

        while self._intake:
            kind, x = self._intake.popleft()
            if kind == "s":
                pending.append(x)
            elif kind == "e":
                flush_samples()
                items.append(x)
                ev = {"t": _num(x.t), "kind": x.kind, "detail": x.detail}
                self.events.append(ev)
                new_events.append(ev)
                if x.kind != _NOTE:
                    self.event_counts[x.kind] = self.event_counts.get(x.kind, 0) + 1
            elif kind == "g":
                flush_samples()
                items.append(x)  # recorded, in order; shown in the GNSS panel, not among the events
                self.gnss_fixes += 1
                self._gnss = {"t": _num(x.t, 6), **x.detail, "count": self.gnss_fixes}
                gnss_new = True
            else:
                self._source_state, self._source_text = x
        flush_samples()
        self.recorder.write(items)

        point: list[float | None] | None = None
        k = sum(b.a.shape[0] for b in batches)
        if k:
            a = np.concatenate([b.a for b in batches]) if len(batches) > 1 else batches[0].a
            td = np.concatenate([b.td for b in batches]) if len(batches) > 1 else batches[0].td
            te = np.concatenate([b.true_eul for b in batches]) if len(batches) > 1 else batches[0].true_eul
            th = np.concatenate([b.true_head for b in batches]) if len(batches) > 1 else batches[0].true_head
            self.samples_in += k
            if math.isfinite(self._last_wall):
                gap = now - self._last_wall
                self._arrival = gap if not math.isfinite(self._arrival) else 0.8 * self._arrival + 0.2 * gap
            self._last_wall = self.clock()  # taken now: a tick slowed by a loaded machine is not a stall
            point = self._chart_point(a, td, te, th)
            self.history.append(json.dumps(point, separators=(",", ":"), allow_nan=False))
            self.points_total += 1
            self._last = self._last_sample(a[-1], td[-1], te[-1], th[-1])
            n_fin = a[np.isfinite(a[:, _N]), _N]
            self._rate.add(now, k, float(n_fin[-1]) if n_fin.size else float("nan"))
        else:
            self._rate.add(now, 0, float("nan"))
        state, text = self.state(now)
        counters = self.counters()
        ctext = json.dumps(counters, sort_keys=True)
        status_key = f"{state}|{text}"
        if point is None and not new_events and not gnss_new and status_key == self._last_status \
                and ctext == self._last_counters and now - self._last_status_wall < 0.5:
            return None  # nothing new: a status frame at most twice a second
        self._last_status, self._last_counters, self._last_status_wall = status_key, ctext, now
        self.seq += 1
        recs, sps = self._rate.rates(now)
        frame: dict[str, Any] = {"type": "frame", "seq": self.seq, "state": state, "text": text,
                                 "rate": {"records": _num(recs, 2), "samples": _num(sps, 2)},
                                 "counters": counters, "hub": self._hub_counters()}
        if point is not None:
            frame["point"] = point
            frame["last"] = self._last
            frame["count"] = k
        if new_events:
            frame["events"] = new_events
        if gnss_new:
            frame["gnss"] = self._gnss
        msg = json.dumps(frame, separators=(",", ":"), allow_nan=False)
        for c in list(self.clients):
            before = c.dropped
            c.offer(msg)
            self.frames_dropped += c.dropped - before
        return msg

    def _chart_point(self, a: NDArray[np.float64], td: NDArray[np.float64], te: NDArray[np.float64],
                     th: NDArray[np.float64]) -> list[float | None]:
        out: list[float | None] = [_num(td[-1], 4)]
        eul = a[:, _EUL] * _DEG
        for j in range(3):  # angles: envelope of the values unwrapped around the newest one
            v = eul[:, j]
            last = v[-1]
            u = last + _wrap_deg(v - last)
            fin = np.isfinite(u)
            out += [_num(last), _num(float(u[fin].min())) if fin.any() else None,
                    _num(float(u[fin].max())) if fin.any() else None]
        rates = a[:, _RATE] * _DEG
        for j in range(3):
            v = rates[:, j]
            fin = np.isfinite(v)
            out += [_num(v[-1]), _num(float(v[fin].min())) if fin.any() else None,
                    _num(float(v[fin].max())) if fin.any() else None]
        out += [_num(x * _DEG) for x in te[-1]]
        out += [_num(a[-1, _HEAD] * _DEG), _num(th[-1] * _DEG)]
        g = self._gnss
        out.append(g["speed"] if g is not None and g.get("valid") is True and _is_real(g.get("speed")) else None)
        return out

    @staticmethod
    def _last_sample(r: NDArray[np.float64], td: float, te: NDArray[np.float64], th: float) -> dict[str, Any]:
        d: dict[str, Any] = {
            "t": _num(r[_T], 6), "td": _num(td, 6), "n": int(r[_N]) if math.isfinite(r[_N]) else None,
            "q": [_num(x, 9) for x in r[_Q]],
            "yaw": _num(r[13] * _DEG, 4), "pitch": _num(r[14] * _DEG, 4), "roll": _num(r[15] * _DEG, 4),
            "heading": _num(r[_HEAD] * _DEG, 4), "rate": [_num(x * _DEG, 4) for x in r[_RATE]],
        }
        if _good_quat(r[None, _TQ])[0]:
            d["true"] = {"q": [_num(x, 9) for x in r[_TQ]], "yaw": _num(te[0] * _DEG, 4),
                         "pitch": _num(te[1] * _DEG, 4), "roll": _num(te[2] * _DEG, 4),
                         "heading": _num(th * _DEG, 4)}
        return d

    def counters(self) -> dict[str, Any]:
        """The source's counters and the count of each report/error kind."""
        try:
            c = dict(self._counters())
        except Exception as exc:  # noqa: BLE001 - a source's bug must not stop the display
            c = {"counters_error": str(exc)}
        out: dict[str, Any] = {k: v for k, v in c.items() if isinstance(v, (int, float, str))
                               and not (isinstance(v, float) and not math.isfinite(v))}
        out.update(self.event_counts)
        return out

    def _hub_counters(self) -> dict[str, Any]:
        rec_s, rec_e = self.recorder.counts()
        return {"samples": self.samples_in, "recorded": rec_s, "recorded_events": rec_e,
                "clients": len(self.clients), "frames_dropped": self.frames_dropped,
                "recording_error": self.recorder.error,
                # what the server holds (diagnostics: bounded, whatever the run's length)
                "history_points": len(self.history), "queued_frames": sum(c.queue.qsize() for c in self.clients),
                "py_blocks": sys.getallocatedblocks()}

    def state(self, now: float | None = None) -> tuple[str, str]:
        """The stream's state for the display: ``waiting`` (no data yet),
        ``live``, ``stalled`` (no sample for longer than the stall time),
        ``ended`` or ``lost`` (from the source), with a text for people."""
        now = self.clock() if now is None else now
        if self._source_state in ("ended", "lost"):
            return self._source_state, self._source_text or self._source_state
        if self._last is None:
            return "waiting", self._source_text or "no data yet"
        limit = self.stall_s
        if math.isfinite(self._arrival):
            limit = max(limit, 4.0 * self._arrival)
        quiet = now - self._last_wall
        if quiet > limit:
            return "stalled", f"no data for {quiet:.1f} s"
        return "live", self._source_text

    def hello(self) -> str:
        """The first message to a client: what the stream is, and how many points of
        history follow (:meth:`history_messages`)."""
        state, text = self.state()
        msg = {"type": "hello", "session": self.session, "seq": self.seq, "source": self.description,
               "display_rate": self.display_rate, "history_s": self.history_s, "columns": list(CHART_COLUMNS),
               "events": list(self.events), "last": self._last, "gnss": self._gnss, "history_points": len(self.history),
               "state": state, "text": text, "counters": self.counters(), "hub": self._hub_counters()}
        return json.dumps(msg, separators=(",", ":"), allow_nan=False)

    def history_messages(self) -> Iterator[str]:
        """The history as it is now, in messages of at most :data:`HISTORY_CHUNK`
        points, oldest first, each made when it is asked for (a client that reads
        slowly costs one message; points the ring dropped meanwhile are skipped).
        Call it with :meth:`add_client`: the points after it come in frames."""
        end = self.points_total
        return self._history_from(end - len(self.history), end)

    def _history_from(self, first: int, end: int) -> Iterator[str]:
        while first < end:
            oldest = self.points_total - len(self.history)
            first = max(first, oldest)
            if first >= end:
                return
            k = min(end, first + HISTORY_CHUNK)
            pts = itertools.islice(self.history, first - oldest, k - oldest)
            yield '{"type":"history","points":[' + ",".join(pts) + "]}"
            first = k

    def add_client(self) -> tuple[Client, str]:
        """A new client and its hello message (to send, then :meth:`history_messages`
        taken at the same time, before anything queued)."""
        c = Client(self.client_queue)
        self.clients.add(c)
        return c, self.hello()

    def remove_client(self, c: Client) -> None:
        c.close()
        self.clients.discard(c)

    def close_clients(self) -> None:
        for c in list(self.clients):
            self.remove_client(c)

    async def run(self, stop: asyncio.Event) -> None:
        """Tick at the display rate until ``stop`` is set (then one last tick)."""
        period = 1.0 / self.display_rate
        loop = asyncio.get_running_loop()
        due = loop.time()
        while not stop.is_set():
            self._safe_tick()
            due += period
            delay = due - loop.time()
            if delay < 0:  # fell behind (a busy machine): do not try to catch up
                due = loop.time()
                delay = 0
            try:
                await asyncio.wait_for(stop.wait(), timeout=delay)
            except asyncio.TimeoutError:
                pass
        self._safe_tick()

    def _safe_tick(self) -> None:
        """:meth:`tick`, whose failure (a bug) must not stop the display: the first is
        kept in :attr:`failure` (the recording then misses what that tick held and is
        kept as partial) and said once on stderr; the ticks go on."""
        try:
            self.tick()
        except Exception as exc:  # noqa: BLE001 - the stream goes on; the recording says it is partial
            if self.failure is None:
                self.failure = f"{type(exc).__name__}: {exc}"[:300]
                print(f"attitude view: error: a display tick failed ({self.failure}); the stream goes on, "
                      "the recording will be kept as partial", file=sys.stderr, flush=True)
