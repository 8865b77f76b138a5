"""The display's web server (aiohttp; ``pip install 'attitude-c[view]'``).

Read-only by construction: every route is a GET of a fixed name -- the page
and its assets (loaded from the package at start, no path from a request
ever reaches the file system), the WebSocket that pushes display frames
(anything a browser sends on it is ignored), and the recording as CSV.
Requests whose ``Host`` is not the loopback address the server listens on
are refused (DNS rebinding), and so are WebSockets opened by a page of
another origin. Why aiohttp: docs/view.md.
"""

from __future__ import annotations

import asyncio
import datetime
import importlib.resources
import ipaddress
import socket
from collections.abc import Awaitable, Callable
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

__all__ = ["ASSETS", "available", "is_loopback", "listen", "make_app", "serve"]

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


def available() -> bool:
    """aiohttp is installed."""
    return web is not None


def _require() -> None:
    if web is None:
        raise ImportError("attitude view needs aiohttp: pip install 'attitude-c[view]'")


def load_assets() -> dict[str, bytes]:
    base = importlib.resources.files(__package__).joinpath("static")
    return {name: base.joinpath(name).read_bytes() for name in ASSETS}


def is_loopback(address: str) -> bool:
    """``address`` (a literal IP or ``localhost``) is a loopback address."""
    if address.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(address.strip("[]")).is_loopback
    except ValueError:
        return False


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


def _host_ok(host_header: str, port: int, loopback_only: bool) -> bool:
    if not loopback_only:
        return True
    h = host_header.strip().lower()
    if h.startswith("["):
        name, _, rest = h[1:].partition("]")
        p = rest[1:] if rest.startswith(":") else ""
    else:
        name, _, p = h.partition(":")
    if p and p != str(port):
        return False
    return is_loopback(name)


def make_app(hub: Hub, *, port: int, loopback_only: bool = True) -> Any:
    """The web application over ``hub``. ``port``: the port clients use (for
    the Host check, enforced when ``loopback_only``)."""
    _require()
    assets = load_assets()

    @web.middleware
    async def guard(request: Any, handler: Callable[[Any], Awaitable[Any]]) -> Any:
        if not _host_ok(request.host or "", port, loopback_only):
            return web.Response(status=403, text="403: this server answers only to its loopback address\n")
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
        ws = web.WebSocketResponse(heartbeat=HEARTBEAT_S, max_msg_size=4096)
        await ws.prepare(request)
        client, hello = hub.add_client()
        writer = asyncio.ensure_future(_writer(ws, client, hello))
        try:
            async for msg in ws:  # the page has nothing to say: whatever it sends is ignored
                if msg.type == WSMsgType.ERROR:
                    break
        finally:
            hub.remove_client(client)
            if not writer.done():
                writer.cancel()
            await asyncio.gather(writer, return_exceptions=True)
        return ws

    async def recording(request: Any) -> Any:
        path, size = await asyncio.wrap_future(hub.recorder.snapshot())
        stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
        resp = web.StreamResponse(headers={
            "Content-Type": "text/csv; charset=utf-8", "Content-Length": str(size),
            "Content-Disposition": f'attachment; filename="attitude-view-{stamp}.csv"'})
        for k, v in _HEADERS.items():
            resp.headers.setdefault(k, v)
        await resp.prepare(request)
        loop = asyncio.get_running_loop()
        fh = await loop.run_in_executor(None, open, path, "rb")
        try:  # the first `size` bytes are complete rows
            left = size
            while left > 0:
                chunk = await loop.run_in_executor(None, fh.read, min(1 << 16, left))
                if not chunk:
                    break
                await resp.write(chunk)
                left -= len(chunk)
        finally:
            fh.close()
        await resp.write_eof()
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


async def _writer(ws: Any, client: Client, hello: str) -> None:
    try:
        await ws.send_str(hello)
        while True:
            msg = await client.queue.get()
            if msg is None:
                await ws.close(code=1001, message=b"server stopping")
                return
            await ws.send_str(msg)
    except (ConnectionError, RuntimeError):  # the browser went away mid-send
        return


async def serve(hub: Hub, source: Source, sock: socket.socket, stop: asyncio.Event, *,
                loopback_only: bool = True, on_ready: Callable[[], None] | None = None) -> None:
    """Serve ``hub`` on ``sock`` and run ``source`` until ``stop`` is set; then
    stop the source, close every client (they reconnect to the next server)
    and the server."""
    _require()
    port = sock.getsockname()[1]
    app = make_app(hub, port=port, loopback_only=loopback_only)
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
