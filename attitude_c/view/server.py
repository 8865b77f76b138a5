"""The display's web server (aiohttp; ``pip install 'attitude-c[view]'``).

Read-only by construction: every route is a GET of a fixed name -- the page
and its assets (loaded from the package at start, no path from a request
ever reaches the file system), the WebSocket that pushes display frames
(anything a browser sends on it is ignored), and the recording as CSV.
Requests whose ``Host`` is not one of the server's names (:class:`HostPolicy`)
are refused (DNS rebinding), and so are WebSockets opened by a page of
another origin; at most :data:`MAX_CLIENTS` tabs are served at once. Why
aiohttp: docs/view.md.
"""

from __future__ import annotations

import asyncio
import contextlib
import datetime
import errno
import importlib.resources
import ipaddress
import logging
import socket
import sys
import time
from collections.abc import Awaitable, Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any
from urllib.parse import urlsplit

from .stream import Client, Hub

try:
    from aiohttp import WSMsgType, web
except ImportError:  # pragma: no cover - depends on the install
    web = None  # type: ignore[assignment]
    WSMsgType = None  # type: ignore[assignment,misc]

if TYPE_CHECKING:
    from .sources import Source

__all__ = ["ASSETS", "MAX_CLIENTS", "HostPolicy", "available", "is_loopback", "listen", "make_app", "serve"]

#: The page's files (attitude_c/view/static/) and their content types.
ASSETS: dict[str, str] = {
    "index.html": "text/html; charset=utf-8",
    "view.js": "text/javascript; charset=utf-8",
    "view.css": "text/css; charset=utf-8",
    "favicon.svg": "image/svg+xml",
}

_CSP = ("default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
        "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")
_HEADERS = {"Content-Security-Policy": _CSP, "X-Content-Type-Options": "nosniff",
            "Referrer-Policy": "no-referrer", "X-Frame-Options": "DENY", "Cache-Control": "no-store"}
#: Seconds between WebSocket pings (a tab that vanished without closing is dropped after two).
HEARTBEAT_S = 10.0
#: Tabs (WebSockets) served at once; one more is refused with 503. Each costs the server at
#: most its queue (16 frames of ~1 kB) and one history message (``HISTORY_CHUNK`` points,
#: ~75 kB) beside aiohttp's own buffers: docs/view.md has the measured figures.
MAX_CLIENTS = 200
#: Seconds between two lines on stderr about the same kind of trouble (accept errors,
#: clients that went away in the middle of a request).
SAY_EVERY_S = 10.0


def available() -> bool:
    """aiohttp is installed."""
    return web is not None


def _require() -> None:
    if web is None:
        raise ImportError("attitude view needs aiohttp: pip install 'attitude-c[view]'")


def load_assets() -> dict[str, bytes]:
    base = importlib.resources.files(__package__).joinpath("static")
    return {name: base.joinpath(name).read_bytes() for name in ASSETS}


def _addresses(address: str) -> list[Any]:
    """The IP addresses ``address`` (a literal in any form ``getaddrinfo`` takes, such as
    ``127.1``, or a name) resolves to; [] when it does not."""
    try:
        infos = socket.getaddrinfo(address.strip("[]"), None, type=socket.SOCK_STREAM)
    except (OSError, UnicodeError):
        return []
    out = []
    for info in infos:
        with contextlib.suppress(ValueError):
            out.append(ipaddress.ip_address(str(info[4][0]).split("%")[0]))
    return out


def is_loopback(address: str) -> bool:
    """``address`` resolves to loopback addresses only (``127.1``, ``localhost``, ``::1``)."""
    addrs = _addresses(address)
    return bool(addrs) and all(a.is_loopback for a in addrs)


def listen(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host``:``port`` (0: any free port). Raises OSError."""
    infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    if not infos:  # pragma: no cover - getaddrinfo raises instead
        raise OSError(f"no address for {host!r}")
    family, stype, proto, _, addr = infos[0]
    s = socket.socket(family, stype, proto)
    try:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind(addr)
        s.listen(128)
        s.setblocking(False)
    except OSError:
        s.close()
        raise
    return s


@dataclass(frozen=True)
class HostPolicy:
    """Which ``Host`` a request may name (DNS rebinding: a page of another site whose
    name was made to resolve to this machine names that site). ``names``: host names
    and addresses allowed (lower case); ``any_address``: any IP literal too (a server
    listening on every address is reached by the machine's addresses, and a rebinding
    page always names a host, never an address); ``anyone``: no check at all."""

    names: frozenset[str]
    any_address: bool = False
    anyone: bool = False

    @classmethod
    def for_bind(cls, bind: str, allow: Iterable[str] = ()) -> HostPolicy:
        """The loopback names, the machine's own names, ``bind`` and the addresses it
        resolves to, and ``allow`` (``*``: anyone)."""
        allow = [a.strip().lower() for a in allow if a.strip()]
        names = {"localhost", bind.strip("[]").lower(), *allow}
        with contextlib.suppress(OSError):
            names.update({socket.gethostname().lower(), socket.getfqdn().lower()})
        names.update(str(a) for a in _addresses(bind))
        wildcard = any(a.is_unspecified for a in _addresses(bind))
        return cls(frozenset(names), any_address=wildcard, anyone="*" in allow)

    def allows(self, name: str) -> bool:
        if self.anyone or name in self.names:
            return True
        try:
            a = ipaddress.ip_address(name)
        except ValueError:
            return False
        return a.is_loopback or self.any_address or str(a) in self.names


#: The default: a server on the loopback address.
LOOPBACK = HostPolicy.for_bind("127.0.0.1")


def _host_ok(host_header: str, port: int, policy: HostPolicy) -> bool:
    h = host_header.strip().lower()
    if h.startswith("["):
        name, _, rest = h[1:].partition("]")
        p = rest[1:] if rest.startswith(":") else ""
    else:
        name, _, p = h.partition(":")
    if p and p != str(port):
        return False
    return policy.allows(name.rstrip("."))


class Say:
    """One line on stderr per kind of trouble every :data:`SAY_EVERY_S` seconds at most,
    with the count of those not said (``clock``: replaceable in tests)."""

    def __init__(self, every: float = SAY_EVERY_S, clock: Callable[[], float] = time.monotonic,
                 out: Callable[[str], None] | None = None) -> None:
        self.every, self.clock = every, clock
        self.out = out or (lambda line: print(line, file=sys.stderr, flush=True))
        self._last: dict[str, float] = {}
        self._held: dict[str, int] = {}

    def __call__(self, kind: str, text: str) -> None:
        now = self.clock()
        if now - self._last.get(kind, -float("inf")) < self.every:
            self._held[kind] = self._held.get(kind, 0) + 1
            return
        held = self._held.pop(kind, 0)
        more = f" ({held} more since the last such line)" if held else ""
        self._last[kind] = now
        self.out(f"attitude view: {text}{more}")


def _brief(exc: BaseException | None) -> str:
    if exc is None:
        return ""
    text = str(exc).splitlines()[0][:160] if str(exc) else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


class _OneLine(logging.Handler):
    """aiohttp's log records (a client that went away mid-request: "Error handling
    request" with a traceback) as one short line each, through :class:`Say`."""

    def __init__(self, say: Say) -> None:
        super().__init__(logging.WARNING)
        self.say = say

    def emit(self, record: logging.LogRecord) -> None:
        exc = record.exc_info[1] if record.exc_info else None
        with contextlib.suppress(Exception):
            msg = record.getMessage().splitlines()[0][:160]
            self.say(f"log:{record.name}", f"{msg}{': ' + _brief(exc) if exc else ''}")


def quiet_logs(say: Say) -> Callable[[], None]:
    """Route aiohttp's warnings and errors through ``say``; returns the undo."""
    log = logging.getLogger("aiohttp")
    handler = _OneLine(say)
    old = log.propagate
    log.addHandler(handler)
    log.propagate = False

    def undo() -> None:
        log.removeHandler(handler)
        log.propagate = old
    return undo


def loop_errors(say: Say) -> Callable[[asyncio.AbstractEventLoop, dict[str, Any]], None]:
    """An event-loop exception handler: one line per kind through ``say``, never a
    traceback. Accept errors (EMFILE: out of descriptors) are said with what to do;
    asyncio itself stops accepting for a second after one (no busy loop)."""
    def handler(loop: asyncio.AbstractEventLoop, ctx: dict[str, Any]) -> None:
        exc = ctx.get("exception")
        if isinstance(exc, OSError) and exc.errno in (errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM):
            say("accept", f"cannot accept a connection: {exc.strerror} (too many open connections or files; "
                "see ulimit -n); trying again in a second")
            return
        say(f"loop:{type(exc).__name__}", f"{ctx.get('message', 'event loop error')}: {_brief(exc)}".rstrip(": "))
    return handler


def make_app(hub: Hub, *, port: int, hosts: HostPolicy = LOOPBACK, max_clients: int = MAX_CLIENTS) -> Any:
    """The web application over ``hub``. ``port``: the port clients use and
    ``hosts`` the names they may use (the Host check); ``max_clients``: tabs served at once."""
    _require()
    assets = load_assets()

    @web.middleware
    async def guard(request: Any, handler: Callable[[Any], Awaitable[Any]]) -> Any:
        if not _host_ok(request.host or "", port, hosts):
            return web.Response(status=403, text="403: this server does not answer to that host name "
                                "(attitude view --allow-host NAME)\n")
        resp = await handler(request)
        if not isinstance(resp, web.WebSocketResponse):
            for k, v in _HEADERS.items():
                resp.headers.setdefault(k, v)
        return resp

    def asset(name: str) -> Callable[[Any], Awaitable[Any]]:
        body, ctype = assets[name], ASSETS[name]

        async def handler(request: Any) -> Any:
            return web.Response(body=body, headers={"Content-Type": ctype})
        return handler

    async def ws_handler(request: Any) -> Any:
        origin = request.headers.get("Origin")
        if origin is not None and urlsplit(origin).netloc.lower() != (request.host or "").lower():
            return web.Response(status=403, text="403: WebSocket from another origin\n")
        if len(hub.clients) >= max_clients:
            return web.Response(status=503, text=f"503: {max_clients} tabs are open, the most this server "
                                "serves at once\n", headers={"Retry-After": "5"})
        ws = web.WebSocketResponse(heartbeat=HEARTBEAT_S, max_msg_size=4096)
        await ws.prepare(request)
        client, hello = hub.add_client()
        writer = asyncio.ensure_future(_writer(ws, client, hello, hub.history_messages()))
        try:
            async for msg in ws:  # the page has nothing to say: whatever it sends is ignored
                if msg.type == WSMsgType.ERROR:
                    break
        except (ConnectionError, asyncio.CancelledError):  # the tab went away: nothing to say
            pass
        finally:
            hub.remove_client(client)
            if not writer.done():
                writer.cancel()
            await asyncio.gather(writer, return_exceptions=True)
        return ws

    async def recording(request: Any) -> Any:
        path, size = await asyncio.wrap_future(hub.recorder.snapshot())
        stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
        headers = {"Content-Type": "text/csv; charset=utf-8", "Content-Length": str(size),
                   "Content-Disposition": f'attachment; filename="attitude-view-{stamp}.csv"', **_HEADERS}
        if request.method == "HEAD":
            return web.Response(headers=headers)
        resp = web.StreamResponse(headers=headers)
        try:
            await resp.prepare(request)
            await _send_file(resp, path, size)
            await resp.write_eof()
        except ConnectionError:  # the download was aborted: nothing to say
            pass
        return resp

    app = web.Application(middlewares=[guard])
    app.router.add_get("/", asset("index.html"))
    for name in ASSETS:
        if name != "index.html":
            app.router.add_get(f"/static/{name}", asset(name))
    app.router.add_get("/favicon.ico", asset("favicon.svg"))
    app.router.add_get("/ws", ws_handler)
    app.router.add_get("/recording.csv", recording)
    return app


async def _send_file(resp: Any, path: Any, size: int) -> None:
    """The first ``size`` bytes of ``path`` (complete rows), read off the loop."""
    loop = asyncio.get_running_loop()
    fh = await loop.run_in_executor(None, open, path, "rb")
    try:
        left = size
        while left > 0:
            chunk = await loop.run_in_executor(None, fh.read, min(1 << 16, left))
            if not chunk:
                break
            await resp.write(chunk)
            left -= len(chunk)
    finally:
        fh.close()


async def _writer(ws: Any, client: Client, hello: str, history: Iterable[str] = ()) -> None:
    try:
        await ws.send_str(hello)
        for part in history:  # one message at a time: send_str waits while the socket is full
            await ws.send_str(part)
        while True:
            msg = await client.queue.get()
            if msg is None:
                await ws.close(code=1001, message=b"server stopping")
                return
            await ws.send_str(msg)
    except (ConnectionError, RuntimeError):  # the browser went away mid-send
        return


async def serve(hub: Hub, source: Source, sock: socket.socket, stop: asyncio.Event, *,
                hosts: HostPolicy = LOOPBACK, max_clients: int = MAX_CLIENTS,
                on_ready: Callable[[], None] | None = None) -> None:
    """Serve ``hub`` on ``sock`` and run ``source`` until ``stop`` is set; then
    stop the source, close every client (they reconnect to the next server)
    and the server. Trouble caused by clients or the system (a download
    aborted, out of descriptors) is one line on stderr, at most every
    :data:`SAY_EVERY_S` seconds per kind."""
    _require()
    say = Say()
    asyncio.get_running_loop().set_exception_handler(loop_errors(say))
    undo = quiet_logs(say)
    try:
        await _serve(hub, source, sock, stop, hosts, max_clients, on_ready)
    finally:
        undo()


async def _serve(hub: Hub, source: Source, sock: socket.socket, stop: asyncio.Event, hosts: HostPolicy,
                 max_clients: int, on_ready: Callable[[], None] | None) -> None:
    port = sock.getsockname()[1]
    app = make_app(hub, port=port, hosts=hosts, max_clients=max_clients)
    runner = web.AppRunner(app, access_log=None, handle_signals=False, shutdown_timeout=1.0)
    await runner.setup()
    try:
        site = web.SockSite(runner, sock)
        await site.start()
        source.start(hub)
        ticker = asyncio.ensure_future(hub.run(stop))
        if on_ready is not None:
            on_ready()
        await stop.wait()
        source.stop()  # then let it hand over what it holds (a source blocked in a read just stays)
        await asyncio.get_running_loop().run_in_executor(None, source.join, 1.0)
        await ticker
        hub.tick()  # everything handed over is recorded
        hub.close_clients()
        await asyncio.sleep(0.05)  # let the writers send their close frames
    finally:
        await runner.cleanup()
