"""Display tasks: ``invoke view-soak`` (the long run of ``attitude view``),
``invoke view-soak-clients`` (its memory under many clients) and
``invoke view-firmware`` (the firmware in s51 -> attitude-rx -> view recipe).
See docs/view.md."""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
import select
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path
from typing import Any, Callable

from invoke import task

ROOT = Path(__file__).resolve().parents[2]

#: Debian's chromium (apt-get install chromium), driven by Playwright: its own
#: browser download is not available. The flags keep it headless and quiet on a
#: machine without a network (no component updates, sync or background requests).
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def browser_missing() -> str | None:
    """Why the browser tests cannot run here (None: they can)."""
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "needs playwright: pip install -e '.[test]'"
    if not os.path.exists(CHROMIUM):
        return f"needs {CHROMIUM}: apt-get install chromium (scripts/setup.sh)"
    return None


def launch_chromium(pw: Any) -> Any:
    return pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)


class ViewProcess:
    """``attitude view ARGS`` in a subprocess; ``url`` from its first line."""

    def __init__(self, *args: str, stdin: Any = subprocess.DEVNULL, timeout: float = 120.0) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "attitude_c", "view", *args], stdin=stdin,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT,
                                     start_new_session=True)
        assert self.proc.stdout is not None
        r, _, _ = select.select([self.proc.stdout], [], [], timeout)
        line = self.proc.stdout.readline().decode() if r else ""
        m = re.search(r"(http://\S+/)", line)
        if m is None:
            self.kill()
            err = self.proc.stderr.read().decode() if self.proc.stderr else ""
            raise RuntimeError(f"attitude view printed no URL: {line!r}; stderr: {err}")
        self.url = m.group(1)
        self.port = int(self.url.rsplit(":", 1)[1].strip("/"))

    def get(self, path: str, timeout: float = 60.0) -> bytes:
        with urllib.request.urlopen(self.url + path.lstrip("/"), timeout=timeout) as r:
            return r.read()

    def rss_mb(self) -> float:
        """Resident memory of the server process (MiB), from /proc."""
        with open(f"/proc/{self.proc.pid}/status") as fh:
            for ln in fh:
                if ln.startswith("VmRSS:"):
                    return int(ln.split()[1]) / 1024.0
        return float("nan")

    def stop(self, timeout: float = 30.0) -> tuple[int, str]:
        """Ctrl-C; the exit status and everything it said on stderr."""
        self.proc.send_signal(signal.SIGINT)
        try:
            self.proc.wait(timeout=timeout)
        finally:
            self.kill()
        err = self.proc.stderr.read().decode() if self.proc.stderr else ""
        return self.proc.returncode, err

    def kill(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()


def run_soak(seconds: float, *, period: float = 0.005, tabs: int = 2, history: float = 120.0,
             every: float = 10.0, log: Callable[[str], None] | None = None,
             browser: Any = None) -> dict[str, Any]:
    """``attitude view --simulate`` for ``seconds`` of simulated time at 1/period
    samples/s (rv3-reuse: one attitude update per sample) with ``tabs`` browser
    tabs open. Samples the server's memory every ``every`` seconds, then checks
    the recording: every update, numbered 0..N-1 without a gap, times increasing.
    Returns the figures (the caller asserts). ``browser``: a Playwright browser
    to open the tabs in (default: launch chromium for the run)."""
    import contextlib

    if log is None:
        def log(line: str) -> None:
            print(line, flush=True)
    n_expected = math.floor(seconds / period + 1e-9)
    v = ViewProcess("--port", "0", "--history", f"{history:g}", "--simulate", "--duration", f"{seconds:g}",
                    "--period", f"{period:g}", "--method", "rv3-reuse", "--calibration", "5", "--no-progress")
    figures: dict[str, Any] = {"seconds": seconds, "rate_hz": 1 / period, "tabs": tabs, "history_s": history,
                               "expected_samples": n_expected}
    rss: list[tuple[float, float]] = []
    held: list[tuple[float, Any, Any, Any]] = []  # (s, Python blocks allocated, history points, queued frames)
    try:
        with contextlib.ExitStack() as stack:
            if browser is None:
                from playwright.sync_api import sync_playwright

                pw = stack.enter_context(sync_playwright())
                browser = launch_chromium(pw)
                stack.callback(browser.close)
            ctx = browser.new_context(viewport={"width": 1280, "height": 900})
            stack.callback(ctx.close)
            pages = []
            for _ in range(tabs):
                pg = ctx.new_page()
                pg.goto(v.url)
                pages.append(pg)
            # the simulation runs first; playback starts when a page says "live"
            pages[0].wait_for_selector("body[data-state=live]", timeout=600_000)
            t0 = time.monotonic()
            log(f"view-soak: {v.url} live; {seconds:g} s at {1 / period:g} samples/s, {tabs} tabs")
            next_mark = 0.0
            while True:
                el = time.monotonic() - t0
                if el >= next_mark:
                    rss.append((round(el, 1), round(v.rss_mb(), 2)))
                    hub = pages[0].evaluate("window.attitudeView.S.hub")
                    held.append((round(el, 1), hub.get("py_blocks"), hub.get("history_points"),
                                 hub.get("queued_frames")))
                    log(f"view-soak: t={el:6.1f} s  rss={rss[-1][1]:7.1f} MiB  py_blocks={hub.get('py_blocks')}  "
                        f"samples={hub.get('samples')} recorded={hub.get('recorded')}  "
                        f"dropped frames={hub.get('frames_dropped')}")
                    next_mark += every
                if pages[0].evaluate("document.body.dataset.state") == "ended":
                    break
                if el > seconds * 1.5 + 60:
                    raise RuntimeError(f"the simulation did not end within {el:.0f} s")
                time.sleep(0.5)
            figures["playback_wall_s"] = round(time.monotonic() - t0, 1)
            rss.append((round(time.monotonic() - t0, 1), round(v.rss_mb(), 2)))
            figures["tab_stats"] = [pg.evaluate("({frames: window.attitudeView.stats.frames, draws: "
                                                "window.attitudeView.stats.draws, missed: "
                                                "window.attitudeView.S.missedFrames, maxDrawMs: "
                                                "window.attitudeView.stats.maxDrawMs, medianDrawMs: "
                                                "window.attitudeView.stats.medianDrawMs()})") for pg in pages]
            figures["hub"] = pages[0].evaluate("window.attitudeView.S.hub")
        body = v.get("/recording.csv", timeout=300).decode()
        rc, err = v.stop()
    finally:
        v.kill()
    rows = list(csv.DictReader(io.StringIO(body)))
    ns = [int(r["n"]) for r in rows if not r["event"]]
    ts = [float(r["t"]) for r in rows if not r["event"]]
    figures["recorded_samples"] = len(ns)
    figures["numbered_0_to_n_minus_1"] = ns == list(range(n_expected))
    figures["times_increasing"] = all(b > a for a, b in zip(ts, ts[1:]))
    figures["exit_status"] = rc
    figures["stopped_line"] = err.strip().splitlines()[-1] if err.strip() else ""
    figures["rss_mb"] = rss
    mb = [m for _, m in rss]
    figures["rss_max_mb"] = max(mb)
    half = [m for t, m in rss if t >= rss[-1][0] / 2]
    figures["rss_growth_second_half_mb"] = round(half[-1] - half[0], 2) if len(half) >= 2 else 0.0
    # the Python heap in objects, which RSS can hide (a leak reusing memory freed by the simulation)
    figures["server_held"] = held
    blocks = [b for t, b, _, _ in held if b is not None and t >= held[-1][0] / 2] if held else []
    figures["py_blocks_second_half"] = [min(blocks), max(blocks)] if blocks else None
    figures["history_points_max"] = max((h for _, _, h, _ in held if h is not None), default=None)
    figures["queued_frames_max"] = max((q for _, _, _, q in held if q is not None), default=None)
    return figures


#: A WebSocket handshake a raw socket sends, then never reads (a tab that stopped reading).
_WS_REQUEST = ("GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
               "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n")


def _non_reader(port: int) -> Any:
    """A connected WebSocket that never reads: its receive buffer is as small as the
    kernel allows, so what the server cannot send stays in the server."""
    import socket

    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.connect(("127.0.0.1", port))
    s.sendall(_WS_REQUEST.format(port=port).encode())
    return s


async def _reader(url: str, stats: dict[str, Any], stop: Any) -> None:
    """A tab that reads everything: the size of its first message and of its largest."""
    import asyncio

    import aiohttp

    async with aiohttp.ClientSession() as session, session.ws_connect(url + "ws", max_msg_size=0) as ws:
        first = True
        while not stop.is_set():
            try:
                msg = await ws.receive(timeout=0.5)
            except asyncio.TimeoutError:
                continue
            if msg.type != aiohttp.WSMsgType.TEXT:
                break
            n = len(msg.data)
            if first:
                stats["first"].append(n)
                first = False
            stats["largest"] = max(stats["largest"], n)
            stats["messages"] += 1
            if '"type":"frame"' in msg.data[:40]:
                stats["hub"] = json.loads(msg.data).get("hub", stats.get("hub"))


def run_client_soak(seconds: float = 60.0, clients: int = 200, *, warmup: float = 30.0, rate: float = 200.0,
                    display_rate: float = 100.0, every: float = 5.0,
                    log: Callable[[str], None] | None = None) -> dict[str, Any]:
    """``attitude view --simulate`` at ``rate`` samples/s and ``display_rate`` frames/s;
    after ``warmup`` seconds (the history ring filling), ``clients`` WebSockets for
    ``seconds``: half read everything, half never read a byte; one more beyond the
    server's limit. The server's resident memory every ``every`` seconds, the
    first and largest message a reader got, the refusals, and the stop."""
    import asyncio

    from attitude_c.view.server import MAX_CLIENTS

    say = log or (lambda line: print(line, flush=True))
    v = ViewProcess("--port", "0", "--display-rate", f"{display_rate:g}", "--simulate", "--duration",
                    f"{warmup + seconds + 60:g}", "--period", f"{1 / rate:g}", "--method", "rv3-reuse",
                    "--calibration", "5", "--no-progress")
    fig: dict[str, Any] = {"clients": clients, "readers": clients - clients // 2, "non_readers": clients // 2,
                           "seconds": seconds, "warmup_s": warmup, "rate_hz": rate, "display_rate": display_rate,
                           "max_clients": MAX_CLIENTS}
    stats: dict[str, Any] = {"first": [], "largest": 0, "messages": 0, "hub": {}}
    rss: list[tuple[float, float]] = []
    raw: list[Any] = []

    async def main() -> None:
        stop = asyncio.Event()
        await _until_live(v.url)  # the simulation runs first, then plays
        await asyncio.sleep(warmup)
        fig["rss_before_mb"] = round(v.rss_mb(), 2)
        readers = [asyncio.ensure_future(_reader(v.url, stats, stop)) for _ in range(fig["readers"])]
        for _ in range(fig["non_readers"]):
            raw.append(_non_reader(v.port))
        await asyncio.sleep(1.0)
        fig["beyond_the_limit"] = await _one_more(v.url)
        t0 = time.monotonic()
        while (el := time.monotonic() - t0) < seconds:
            rss.append((round(el, 1), round(v.rss_mb(), 2)))
            say(f"view-soak-clients: t={el:5.1f} s  rss={rss[-1][1]:7.1f} MiB  hub={stats['hub'].get('clients')} "
                f"clients, {stats['hub'].get('history_points')} history points, py_blocks "
                f"{stats['hub'].get('py_blocks')}")
            await asyncio.sleep(every)
        rss.append((round(time.monotonic() - t0, 1), round(v.rss_mb(), 2)))
        fig["hub"] = dict(stats["hub"])
        stop.set()
        await asyncio.gather(*readers, return_exceptions=True)

    try:
        say(f"view-soak-clients: {v.url}; warm-up {warmup:g} s, then {clients} clients for {seconds:g} s")
        asyncio.run(main())
        for s in raw:
            s.close()
        rc, err = v.stop()
    finally:
        v.kill()
    fig["rss_mb"] = rss
    fig["rss_max_mb"] = max(m for _, m in rss)
    fig["rss_growth_mb"] = round(rss[-1][1] - rss[0][1], 2)
    fig["first_message_bytes"] = max(stats["first"]) if stats["first"] else None
    fig["largest_message_bytes"] = stats["largest"]
    fig["readers_served"] = len(stats["first"])
    fig["messages_read"] = stats["messages"]
    fig["exit_status"] = rc
    fig["stderr_lines"] = len(err.strip().splitlines())
    fig["tracebacks"] = err.count("Traceback")
    fig["stopped_line"] = err.strip().splitlines()[-1] if err.strip() else ""
    return fig


async def _until_live(url: str, timeout: float = 600.0) -> None:
    import aiohttp

    async with aiohttp.ClientSession() as session, session.ws_connect(url + "ws", max_msg_size=0) as ws:
        while json.loads((await ws.receive(timeout=timeout)).data).get("state") != "live":
            pass


async def _one_more(url: str) -> int | str:
    """Open a WebSocket now: the HTTP status of a refusal, or "open"."""
    import aiohttp

    async with aiohttp.ClientSession() as session:
        try:
            ws = await session.ws_connect(url + "ws")
        except aiohttp.WSServerHandshakeError as exc:
            return exc.status
        await ws.close()
        return "open"


@task(help={
    "seconds": "seconds the clients stay connected (default 60)",
    "clients": "WebSocket clients: half read everything, half never read (default 200)",
    "warmup": "seconds of data before the clients connect, filling the history ring (default 30)",
    "out": "write the figures as JSON here",
})
def view_soak_clients(c, seconds=60, clients=200, warmup=30, out=""):
    """The display under many clients: the server's memory with CLIENTS WebSockets (readers and
    non-readers) for SECONDS, the first and largest message, the client limit; no browser needed."""
    fig = run_client_soak(float(seconds), int(clients), warmup=float(warmup))
    text = json.dumps(fig, indent=2)
    print(text)
    if out:
        Path(out).write_text(text + "\n")
    ok = fig["exit_status"] == 0 and fig["tracebacks"] == 0 and fig["readers_served"] == fig["readers"]
    print(f"view-soak-clients: {'OK' if ok else 'FAILED'}: memory {fig['rss_before_mb']:.1f} MiB before the "
          f"clients, at most {fig['rss_max_mb']:.1f} MiB with them; first message {fig['first_message_bytes']} "
          f"bytes, largest {fig['largest_message_bytes']}; one more client: {fig['beyond_the_limit']}")
    if not ok:
        raise SystemExit(1)


@task(help={
    "minutes": "simulated (and wall-clock) minutes (default 10)",
    "rate": "samples per second (default 200)",
    "tabs": "browser tabs open (default 2)",
    "history": "seconds of chart history the server keeps (default 120: reached early, so the "
               "memory's steady state shows)",
    "out": "write the figures as JSON here",
})
def view_soak(c, minutes=10.0, rate=200.0, tabs=2, history=120.0, out=""):
    """Long run of `attitude view`: the simulator at RATE samples/s for MINUTES with TABS tabs;
    memory bounded, no sample missing from the recording."""
    if (why := browser_missing()) is not None:
        print(f"view-soak: {why}", file=sys.stderr)
        raise SystemExit(1)
    fig = run_soak(float(minutes) * 60.0, period=1.0 / float(rate), tabs=int(tabs), history=float(history))
    text = json.dumps(fig, indent=2)
    print(text)
    if out:
        Path(out).write_text(text + "\n")
    ok = (fig["numbered_0_to_n_minus_1"] and fig["recorded_samples"] == fig["expected_samples"]
          and fig["times_increasing"] and fig["exit_status"] == 0)
    print(f"view-soak: {'OK' if ok else 'FAILED'}: {fig['recorded_samples']} of {fig['expected_samples']} "
          f"samples recorded, memory max {fig['rss_max_mb']:.1f} MiB, growth over the second half "
          f"{fig['rss_growth_second_half_mb']:+.1f} MiB, Python blocks over the second half "
          f"{fig['py_blocks_second_half']}")
    if not ok:
        raise SystemExit(1)


@task(help={
    "samples": "samples the firmware sends before it stops (default 3000: a minute at 20 ms)",
    "port": "the view's TCP port (default 8765)",
    "period_ticks": "sampling period in ticks of 1/3600 s (default 72 = 20 ms, the firmware's)",
})
def view_firmware(c, samples=3000, port=8765, period_ticks=72):
    """The firmware in s51 -> socat pty -> attitude-rx --format jsonl -> attitude view --stdin."""
    from toolchain import firmware as tool
    from toolchain.tasks.cross import cross_build_target

    build = ROOT / "build" / "view-firmware"
    exe = str(cross_build_target("host", out=build / "rx")["app"])
    # long link timeouts: a host answering late (a loaded machine) costs overruns, never duplicates
    cfg = tool.Config(period_ticks=int(period_ticks), syn_timeout=3600, answer_timeout=3600)
    img = tool.build(build / "fw", cfg, kind="sim", sim_samples=int(samples), name="fw_view")
    print(img.size_report())
    period = int(period_ticks) / tool.TICK_HZ
    with tool.Session(img, timeout=int(samples) * period * 5 + 120) as sess:
        rx = subprocess.Popen([exe, "--port", str(sess.port), "--format", "jsonl", "--gyro-zero", "2047.5",
                               "--gap-ms", "2000"], stdout=subprocess.PIPE)
        view = subprocess.Popen([sys.executable, "-m", "attitude_c", "view", "--stdin", "--port", str(port)],
                                stdin=rx.stdout, cwd=ROOT)
        try:
            time.sleep(1.0)  # attitude-rx has the port open before the firmware's BOOT
            out = sess.run()
            print(f"view-firmware: the firmware sent its {samples} samples ({out.sim_seconds:.1f} s simulated in "
                  f"{out.wall_seconds:.1f} s); the view stays up: Ctrl-C to stop")
            rx.send_signal(signal.SIGINT)
            view.wait()
        except KeyboardInterrupt:
            pass
        finally:
            for p in (rx, view):
                if p.poll() is None:
                    p.send_signal(signal.SIGINT)
                    try:
                        p.wait(timeout=10)
                    except subprocess.TimeoutExpired:
                        p.kill()


@task(help={
    "out": "PNG to write (default docs/img/view.png)",
    "seconds": "seconds of playback before the picture (default 12)",
    "gnss": "the GNSS panel instead (docs/img/view-gnss.png): a simulated car drive with a NEO-M8N receiver",
})
def view_screenshot(c, out="", seconds=12.0, gnss=False):
    """The screenshot of docs/view.md: the simulator at 200 samples/s with bit errors on the link; with
    --gnss, the GNSS panel (docs/img/view-gnss.png) after a simulated car drive with a NEO-M8N receiver
    and a 4 s outage in the roundabout, played at 2x to its end."""
    if (why := browser_missing()) is not None:
        print(f"view-screenshot: {why}", file=sys.stderr)
        raise SystemExit(1)
    from playwright.sync_api import sync_playwright

    path = Path(out) if out else ROOT / "docs" / "img" / ("view-gnss.png" if gnss else "view.png")
    if gnss:
        v = ViewProcess("--port", "0", "--speed", "2", "--simulate", "--trajectory", "car", "--duration", "40",
                        "--period", "0.01", "--method", "rv3-reuse", "--calibration", "5", "--gnss", "neo-m8n",
                        "--gnss-outage", "20,24")
    else:
        v = ViewProcess("--port", "0", "--simulate", "--duration", "60", "--period", "0.005", "--method",
                        "rv3-reuse", "--ber", "1e-3", "--calibration", "5")
    try:
        with sync_playwright() as pw:
            browser = launch_chromium(pw)
            try:
                page = browser.new_page(viewport={"width": 1280, "height": 860})
                page.goto(v.url)
                page.wait_for_selector("body[data-state=live]", timeout=300_000)
                page.select_option("#window", "60" if gnss else "10")
                if gnss:
                    page.wait_for_selector("body[data-state=ended]", timeout=300_000)
                    page.wait_for_timeout(1000)  # the status frames after the end have been drawn
                    page.locator("#gnss-panel").screenshot(path=str(path))
                else:
                    page.wait_for_timeout(float(seconds) * 1000)
                    page.screenshot(path=str(path), full_page=True)
            finally:
                browser.close()
        v.stop()
    finally:
        v.kill()
    print(f"view-screenshot: wrote {path}")


TOP_LEVEL = (view_soak, view_soak_clients, view_firmware, view_screenshot)
