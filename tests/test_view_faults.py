"""attitude view under what users feed it (issue 29, items 2-8): odd lines on
stdin and in replays, replay content checked before serving, the history sent
in bounded messages, the client limit, client mistakes and system errors as
one rate-limited line, the Host allow-list on any bind, the option ranges.
Every failing case here failed on the code before issue 29's fixes. Tests that
start ``attitude view`` are marked ``system``; the others run in-process with
bounded waits (no sleep synchronizes anything)."""

from __future__ import annotations

import asyncio
import contextlib
import csv
import io
import json
import os
import signal
import socket
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, _missing, broad_mat, peak_memory

import attitude_c
from attitude_c.cli import build_parser
from attitude_c.errors import InvalidArgument
from attitude_c.view import sources, stream
from attitude_c.view.stream import Hub, Recorder, row

Q = attitude_c.euler_to_quat([0.1, 0.2, 0.3]).tolist()


def _aiohttp() -> None:
    try:
        import aiohttp  # noqa: F401
    except ImportError:
        _missing("needs aiohttp: pip install -e '.[test]'")


def _sample(k: int) -> bytes:
    return (json.dumps({"t": k * 0.01, "n": k, "q": Q}) + "\n").encode()


#: Lines that stopped the stdin source for good, or ended a replay in a traceback.
ODD_LINES = {
    "100,000 nested brackets": b"[" * 100_000 + b"\n",
    "a CSV field over 128 KiB": b'0,"' + b"x" * (200 << 10) + b'"\n',
    "a line over the 1 MiB bound": b"{" + b" " * ((1 << 20) + 10) + b"}\n",
    "a NUL byte": b'{"t":1,\0}\n',
    "not UTF-8": b'{"t":"\xff"}\n',
    "t of Infinity": b'{"t":Infinity,"q":[1,0,0,0]}\n',
    "t of 1e300": b'{"t":1e300,"q":[1,0,0,0]}\n',
}


# ---- item 2: a bad line on stdin is counted, shown, and the stream goes on -------------------

@pytest.mark.parametrize("through", ["pipe", "file object"])
def test_odd_stdin_lines_are_counted_and_the_stream_goes_on(through: str) -> None:
    data = b"".join(_sample(k) + line for k, line in enumerate(ODD_LINES.values())) + _sample(len(ODD_LINES))
    hub = Hub(recorder=Recorder())
    if through == "pipe":
        rfd, wfd = os.pipe()
        rd = os.fdopen(rfd, "rb")
        src = sources.StdinSource(rd, "pipe")
        src.start(hub)

        def feed() -> None:
            with os.fdopen(wfd, "wb") as wr, contextlib.suppress(OSError):
                wr.write(data)  # a source that died leaves it blocked: a daemon thread, not the test
        threading.Thread(target=feed, daemon=True).start()
    else:
        rd = io.BytesIO(data)
        src = sources.StdinSource(rd, "pipe")
        src.start(hub)
    src.join(60)
    hub.tick()
    c = hub.counters()
    assert c["bad_lines"] == c["error"] == len(ODD_LINES), c
    assert hub.samples_in == len(ODD_LINES) + 1  # every sample, before and after each odd line
    assert hub.state()[0] == "lost" and hub.state()[1] == "input ended (pipe closed)"
    errors = [e["detail"]["error"] for e in hub.events]
    assert all(len(json.dumps(e)) < 400 for e in hub.events), errors  # cut to a sensible length
    assert "line 2: not JSON this reader takes: nested too deep" in errors[0]
    assert "field larger than field limit" in errors[1] and "longer than 1,048,576 bytes" in errors[2]
    rd.close()
    hub.recorder.close()


def test_a_byte_order_mark_on_the_first_line_is_dropped(tmp_path: Path) -> None:
    """A CSV saved by a spreadsheet (UTF-8 with BOM) replays: the header's t is t."""
    f = tmp_path / "bom.csv"
    f.write_bytes("\ufefft,q0,q1,q2,q3\n0,1,0,0,0\n0.1,1,0,0,0\n".encode())
    assert sources.load_recording(f).samples == 2


# ---- items 2, 7, 9: a replay is checked whole before serving, streaming ----------------------

@pytest.mark.parametrize("what", list(ODD_LINES))
def test_odd_replay_lines_are_one_line_naming_the_file_and_line(tmp_path: Path, what: str) -> None:
    f = tmp_path / "odd.jsonl"
    f.write_bytes(_sample(0) + ODD_LINES[what] + _sample(1))
    with pytest.raises(InvalidArgument) as exc:
        sources.load_recording(f)
    msg = str(exc.value)
    if what == "a NUL byte":  # found in the first KiB, before any line is parsed
        assert msg == f"{f}: not a text file (a NUL byte at offset {len(_sample(0)) + 7})", msg
    else:
        assert msg.startswith(f"recording '{f}' line 2: ") and len(msg) < 300 and "\n" not in msg, msg


def _mat(path: Path, **kw) -> Path:
    return broad_mat(path, 50, **kw)


@pytest.mark.parametrize("case,kw,says", [
    ("rate 0", {"sampling_rate": np.array([[0.0]])}, "sampling_rate must be one finite number > 0"),
    ("rate -100", {"sampling_rate": np.array([[-100.0]])}, "sampling_rate must be one finite number > 0"),
    ("rate empty", {"sampling_rate": np.zeros((0, 0))}, "sampling_rate must be one finite number > 0"),
    ("no samples", {k: np.zeros((0, c)) for k, c in (("imu_gyr", 3), ("imu_acc", 3), ("imu_mag", 3),
                                                      ("opt_quat", 4), ("movement", 1))}, "holds no sample"),
    ("complex gyro", {"imu_gyr": np.full((50, 3), 0.1 + 1j)}, "imu_gyr holds complex128 values"),
    ("movement short", {"movement": np.ones((40, 1))}, "movement has 40 values, expected 50"),
])
def test_a_bad_broad_trial_is_refused_before_serving(tmp_path: Path, case: str, kw: dict, says: str) -> None:
    pytest.importorskip("scipy", reason="needs SciPy: pip install -e '.[test]'")
    f = _mat(tmp_path / "trial.mat", **kw)
    with pytest.raises(InvalidArgument, match=says) as exc:
        sources.ReplaySource(f)
    assert str(f) in str(exc.value)


def test_a_large_replay_is_streamed_not_held(tmp_path: Path) -> None:
    """The check reads the file a line at a time, and so does the replay: memory
    does not grow with the recording (a 6.3 GB read before issue 29)."""
    f = tmp_path / "big.jsonl"
    with open(f, "wb") as fh:
        fh.writelines(_sample(k) for k in range(20_000))

    def check_and_play() -> tuple[int, int]:
        rec = sources.load_recording(f)
        return rec.samples, sum(1 for _ in rec.items())

    (samples, n), peak = peak_memory(check_and_play)
    assert samples == n == 20_000
    # the file is 1.8 MB; read whole (text + 20,000 items of 17 floats) it costs > 15 MB
    assert peak < 1.5e6, peak


def test_a_sparse_file_is_refused_at_once(tmp_path: Path) -> None:
    f = tmp_path / "sparse.csv"
    with open(f, "wb") as fh:
        fh.truncate(64 << 20)  # 64 MiB of NUL bytes, none on the disk

    def refused() -> str:
        with pytest.raises(InvalidArgument, match="not a text file") as exc:
            sources.load_recording(f)
        return str(exc.value)

    msg, peak = peak_memory(refused)
    assert peak < 1 << 20 and len(msg) < 200, (peak, msg[:300])


# ---- item 4: the history in bounded messages; a client limit -------------------------------

def _filled_hub(points: int, **kw) -> Hub:
    hub = Hub(recorder=Recorder(), clock=lambda: 0.0, display_rate=100, history_s=600, **kw)
    for k in range(points):
        hub.samples([row(k * 0.01, Q, n=k)])
        hub.tick()
    return hub


def test_the_history_comes_in_bounded_messages_made_on_demand() -> None:
    """A late tab gets a small hello and the history in messages of at most
    HISTORY_CHUNK points, each made when the writer asks for it: a tab that does
    not read costs one message, never the whole history (2.2 MB each before)."""
    hub = _filled_hub(2 * stream.HISTORY_CHUNK + 7)
    _, hello = hub.add_client()
    msgs = hub.history_messages()
    assert len(hello) < 10_000 and json.loads(hello)["history_points"] == 2 * stream.HISTORY_CHUNK + 7
    first = json.loads(next(msgs))
    assert first["type"] == "history" and len(first["points"]) == stream.HISTORY_CHUNK
    # the ring moves on while the tab reads: points made after the hello come as frames
    hub.samples([row(99.0, Q, n=99_999)])
    frame = json.loads(hub.tick())
    rest = [json.loads(m)["points"] for m in msgs]
    assert [len(p) for p in rest] == [stream.HISTORY_CHUNK, 7]
    got = [p[0] for p in first["points"]] + [p[0] for ps in rest for p in ps]
    assert got == sorted(got) and got[-1] < frame["point"][0]
    hub.recorder.close()


def test_the_history_ring_is_bounded_by_the_options_limits() -> None:
    with pytest.raises(InvalidArgument, match="history_s must be at most 600"):
        Hub(recorder=Recorder(), history_s=601)
    with pytest.raises(InvalidArgument, match="display_rate must be 1..100"):
        Hub(recorder=Recorder(), display_rate=1e-300)
    hub = Hub(recorder=Recorder(), history_s=stream.HISTORY_MAX_S, display_rate=stream.DISPLAY_RATE_MAX)
    assert hub.history.maxlen == 60_000
    hub.recorder.close()


def _serve(fn, *, hub: Hub | None = None, **app_kw):
    """``fn(session, hub, port, said)`` against the app on a real loopback socket, with
    aiohttp's logs and the loop's errors going through ``Say`` into ``said``."""
    _aiohttp()
    from aiohttp import ClientSession, web

    from attitude_c.view import server

    said: list[str] = []

    async def main():
        h = hub or Hub(recorder=Recorder())
        say = server.Say(out=said.append)
        asyncio.get_running_loop().set_exception_handler(server.loop_errors(say))
        undo = server.quiet_logs(say)
        sock = server.listen("127.0.0.1", 0)
        port = sock.getsockname()[1]
        runner = web.AppRunner(server.make_app(h, port=port, **app_kw))
        await runner.setup()
        await web.SockSite(runner, sock).start()
        try:
            async with ClientSession(f"http://127.0.0.1:{port}") as session:
                return await fn(session, h, port, said)
        finally:
            h.close_clients()
            await runner.cleanup()
            undo()
            h.recorder.close()

    return asyncio.run(main()), said


def test_tabs_beyond_the_limit_are_refused_with_503() -> None:
    import aiohttp

    async def fn(session, hub, port, said):
        open_ = [await session.ws_connect("/ws") for _ in range(3)]
        for ws in open_:
            assert json.loads((await ws.receive(timeout=10)).data)["type"] == "hello"
        with pytest.raises(aiohttp.WSServerHandshakeError) as exc:
            await session.ws_connect("/ws")
        status = exc.value.status
        await open_[0].close()
        for _ in range(100):  # the server sees the close, then a new tab fits
            if len(hub.clients) < 3:
                break
            await asyncio.sleep(0.01)
        again = await session.ws_connect("/ws")
        await again.close()
        for ws in open_[1:]:
            await ws.close()
        return status

    status, said = _serve(fn, max_clients=3)
    assert status == 503 and said == []


def test_accept_errors_are_one_line_every_ten_seconds() -> None:
    """EMFILE on accept (out of descriptors) printed 6,126 tracebacks in 8 s: now
    one line per SAY_EVERY_S with the count of those not said."""
    import errno

    from attitude_c.view import server

    now = [0.0]
    said: list[str] = []
    handler = server.loop_errors(server.Say(clock=lambda: now[0], out=said.append))
    err = OSError(errno.EMFILE, "Too many open files")
    for k in range(1000):
        now[0] = k * 0.01  # 1000 errors over 10 s
        handler(None, {"message": "socket.accept() out of system resource", "exception": err})  # type: ignore[arg-type]
    now[0] = 10.0
    handler(None, {"message": "socket.accept() out of system resource", "exception": err})  # type: ignore[arg-type]
    assert len(said) == 2 and "Traceback" not in "".join(said)
    assert said[0].startswith("attitude view: cannot accept a connection: Too many open files")
    assert said[1].endswith("(999 more since the last such line)")


# ---- item 5: client actions are quiet --------------------------------------------------------

def test_head_aborted_download_and_ping_flood_print_no_traceback(capfd) -> None:

    hub = Hub(recorder=Recorder())
    q = np.tile(Q, (60_000, 1))
    hub.samples([row(k * 0.01, q[k], n=k) for k in range(60_000)])  # a recording of ~8 MB
    hub.tick()

    async def fn(session, hub, port, said):
        async with session.head("/recording.csv") as r:
            head = (r.status, int(r.headers["Content-Length"]), await r.read())
        for _ in range(3):  # downloads aborted after their first bytes
            r = await session.get("/recording.csv")
            await r.content.read(1000)
            r.close()
        ws = await session.ws_connect("/ws", autoping=False)
        for _ in range(2000):
            await ws.ping()
        ws._response.connection.transport.abort()  # gone without a close frame
        await asyncio.sleep(0.2)  # the server notices (not a synchronization: nothing waits on it)
        async with session.get("/") as r:  # and still serves
            return head, r.status

    (head, status), said = _serve(fn, hub=hub)
    err = capfd.readouterr().err
    assert head[0] == 200 and head[1] > 8_000_000 and head[2] == b""
    assert status == 200
    assert "Traceback" not in err and len(said) <= 1, (said, err[-2000:])


# ---- item 6: loopback by the resolved address; the Host allow-list on any bind -----------

def test_loopback_is_decided_by_the_resolved_address() -> None:
    from attitude_c.view import server

    assert server.is_loopback("127.1") and server.is_loopback("127.0.0.1") and server.is_loopback("localhost")
    assert server.is_loopback("::1") and server.is_loopback("[::1]")
    assert not server.is_loopback("0.0.0.0") and not server.is_loopback("no-such-host.invalid")


def test_the_host_allow_list_holds_on_a_wildcard_bind() -> None:
    from attitude_c.view import server

    pol = server.HostPolicy.for_bind("0.0.0.0")
    ok = server._host_ok
    for host in ("evil.example:8765", "evil.example", "attacker.localhost.evil:8765"):
        assert not ok(host, 8765, pol), host
    for host in ("127.0.0.1:8765", "localhost:8765", "192.168.1.20:8765", "[fe80::1]:8765",
                 f"{socket.gethostname()}:8765"):
        assert ok(host, 8765, pol), host
    assert not ok("127.0.0.1:1", 8765, pol)
    wide = server.HostPolicy.for_bind("0.0.0.0", ["display.lab"])
    assert ok("display.lab:8765", 8765, wide) and not ok("evil.example:8765", 8765, wide)
    assert ok("evil.example:8765", 8765, server.HostPolicy.for_bind("0.0.0.0", ["*"]))
    loop = server.HostPolicy.for_bind("127.1")
    assert ok("127.0.0.1:8765", 8765, loop) and not ok("192.168.1.20:8765", 8765, loop)


def test_a_rebinding_page_gets_no_websocket_on_a_wildcard_bind() -> None:
    import aiohttp

    from attitude_c.view import server

    async def fn(session, hub, port, said):
        out = {}
        for host in (f"evil.example:{port}", f"127.0.0.1:{port}"):
            try:
                ws = await session.ws_connect("/ws", headers={"Host": host, "Origin": f"http://{host}"})
                out[host.split(":")[0]] = "open"
                await ws.close()
            except aiohttp.WSServerHandshakeError as exc:
                out[host.split(":")[0]] = exc.status
        return out

    out, _ = _serve(fn, hosts=server.HostPolicy.for_bind("0.0.0.0"))
    assert out == {"evil.example": 403, "127.0.0.1": "open"}


# ---- item 8: the option ranges ---------------------------------------------------------------

@pytest.mark.parametrize("argv,says", [
    (["--history", "1e300"], "--history: must be a finite number > 0 and <= 600"),
    (["--display-rate", "1e-300"], "--display-rate: must be a finite number >= 1 and <= 100"),
    (["--stall", "1e300"], "--stall: must be a finite number > 0 and <= 3600"),
    (["--speed", "1e-300"], "--speed: must be a finite number >= 0.001 and <= 1000"),
])
def test_option_ranges(capsys, argv: list[str], says: str) -> None:
    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args(["view", "--stdin", *argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert exc.value.code == 2 and len(err) == 1 and says in err[0], err


# ---- commands: items 1, 3, 6, 7 as the user sees them ---------------------------------------

def _view(*args: str, **kw) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "attitude_c", "view", "--port", "0", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT, start_new_session=True, **kw)


def _url_line(p: subprocess.Popen) -> str:
    import select

    r, _, _ = select.select([p.stdout], [], [], 60)
    return p.stdout.readline().decode() if r else ""


def _finish(p: subprocess.Popen, sig: int | None = signal.SIGTERM) -> tuple[int, str]:
    try:
        if sig is not None:
            p.send_signal(sig)
        _, err = p.communicate(timeout=20)
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
    return p.returncode, err.decode()


@pytest.mark.system
def test_sigterm_while_stdin_is_idle_exits_0(tmp_path: Path) -> None:
    """`sleep 30 | attitude view --stdin` + SIGTERM aborted with "Fatal Python error:
    _enter_buffered_busy" (exit 134): the source thread was blocked in sys.stdin's
    buffered reader at interpreter shutdown."""
    _aiohttp()
    rfd, wfd = os.pipe()  # the writer end stays open and silent, as `sleep 30` holds it
    try:
        p = _view("--stdin", "--record", str(tmp_path / "r.csv"), stdin=rfd)
        os.close(rfd)
        assert "http://" in _url_line(p)
        rc, err = _finish(p)
    finally:
        os.close(wfd)
    assert rc == 0 and "Fatal" not in err and "Traceback" not in err, (rc, err)
    assert (tmp_path / "r.csv").read_text().startswith("t,n,q0")


@pytest.mark.system
def test_nan_in_a_replay_keeps_the_event_and_the_stream(tmp_path: Path) -> None:
    """The issue's repro: the event is kept (NaN as null), the samples after it are
    recorded, exit 0, and the recording is complete."""
    _aiohttp()
    f = tmp_path / "nan.jsonl"
    f.write_text('{"t":0,"n":0,"q":[1,0,0,0]}\n{"t":0.1,"report":"BOOT","x":NaN}\n'
                 '{"t":0.2,"n":1,"q":[1,0,0,0]}\n{"t":0.3,"n":2,"q":[1,0,0,0]}\n')
    rec = tmp_path / "r.csv"
    p = _view("--replay", str(f), "--speed", "1000", "--record", str(rec))
    rc, err = _wait_ended_then_stop(p, _url_line(p))
    assert rc == 0 and "Traceback" not in err, err
    rows = list(csv.DictReader(rec.read_text().splitlines()))
    assert [r["event"] or r["n"] for r in rows] == ["0", "BOOT", "1", "2"]
    assert json.loads(rows[1]["detail"]) == {"x": None}


def _wait_ended_then_stop(p: subprocess.Popen, line: str) -> tuple[int, str]:
    """Stop after the replay ended (the state the page is sent, read from the WebSocket)."""
    import re

    import aiohttp

    url = re.search(r"(http://\S+/)", line)
    assert url is not None, line

    async def ended() -> None:
        async with aiohttp.ClientSession() as s, s.ws_connect(url.group(1) + "ws") as ws:
            while True:
                m = json.loads((await ws.receive(timeout=30)).data)
                if m.get("state") == "ended":
                    return

    try:
        asyncio.run(ended())
    except BaseException:
        _finish(p)
        raise
    return _finish(p, signal.SIGINT)


@pytest.mark.system
def test_bad_replays_are_one_line_exit_1_before_serving(tmp_path: Path) -> None:
    _aiohttp()
    pytest.importorskip("scipy", reason="needs SciPy: pip install -e '.[test]'")
    cases = {"deep.jsonl": _sample(0) + ODD_LINES["100,000 nested brackets"],
             "field.csv": b"t,q0,q1,q2,q3\n" + ODD_LINES["a CSV field over 128 KiB"],
             "inf.jsonl": ODD_LINES["t of Infinity"], "far.jsonl": ODD_LINES["t of 1e300"]}
    files = []
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
        files.append(tmp_path / name)
    files += [_mat(tmp_path / "rate0.mat", sampling_rate=np.array([[0.0]])),
              _mat(tmp_path / "empty.mat", sampling_rate=np.zeros((0, 0)))]
    for f in files:
        r = subprocess.run([sys.executable, "-m", "attitude_c", "view", "--port", "0", "--replay", str(f)],
                           capture_output=True, text=True, timeout=60, cwd=ROOT, stdin=subprocess.DEVNULL, check=False)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 1 and len(lines) == 1, (f, r.returncode, r.stderr[-500:])
        assert str(f) in lines[0] and len(lines[0]) < 300, lines
        assert "http://" not in r.stdout  # found before serving


@pytest.mark.system
def test_bind_127_1_is_loopback_without_the_warning() -> None:
    _aiohttp()
    p = _view("--stdin", "--bind", "127.1", stdin=subprocess.PIPE)
    line = _url_line(p)
    rc, err = _finish(p)
    assert line.startswith("attitude view: http://127.0.0.1:"), line
    assert rc == 0 and "warning" not in err, err


@pytest.mark.system
def test_client_soak_smoke() -> None:
    """`invoke view-soak-clients`, short: readers and non-readers together, the
    first message small whatever the history, every message bounded, exit 0."""
    _aiohttp()
    from toolchain.tasks.view import run_client_soak

    fig = run_client_soak(2.0, 6, warmup=1.0, every=1.0, log=lambda line: None)
    assert fig["readers_served"] == 3 and fig["exit_status"] == 0 and fig["tracebacks"] == 0, fig
    assert fig["first_message_bytes"] < 10_000  # the hello: no history in it
    # a history message: HISTORY_CHUNK points of at most ~200 bytes each
    assert fig["largest_message_bytes"] <= stream.HISTORY_CHUNK * 200, fig
    assert fig["beyond_the_limit"] == "open"  # 6 of 200
