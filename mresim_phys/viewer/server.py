"""Viewer (output edge), server: the page, its assets and its WebSocket, on this machine.

An aiohttp application (why aiohttp: docs/viewer.md) running in a thread of its own with
its own event loop, so the simulation keeps the main thread (and its signal handlers).
``GET /`` gives the page, ``/static/`` its script and style (package data: no CDN, works
offline), ``/ws`` the WebSocket of :mod:`~mresim_phys.viewer.protocol`. Each page has a
writer task (frames go out in order) and a worker that serves only its newest frame
request (a page scrubbing fast never waits for frames it no longer wants). Replay frames
are rendered in a worker thread; live ones in the simulation's thread (``livesource``).

Every request passes the guard first (``guard``: 403 for another machine unless
``allow_remote``, a ``Host`` that does not name this viewer, an ``Origin`` of another
site). A malformed message (``protocol.decode``: too big, too deep, not JSON, wrong
fields) is answered with an error message, logged, and changes nothing.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import errno
import itertools
import logging
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from aiohttp import WSMsgType, web
from aiohttp.http_exceptions import HttpProcessingError

from mresim_phys.errors import MresimError
from mresim_phys.viewer.guard import Guard, Where
from mresim_phys.viewer.livesource import LiveSource, Want
from mresim_phys.viewer.protocol import MAX_FRAME, Message, ProtocolError, decode, parse_message
from mresim_phys.viewer.replaysource import ReplaySource

STATIC = Path(__file__).parent / "static"
ASSETS = frozenset(path.name for path in STATIC.iterdir() if path.is_file())
QUEUED_ERRORS = 16  # error replies queued for one page at most; more are only logged
Source = LiveSource | ReplaySource
log = logging.getLogger(__name__)


class ClientMistakes(logging.Filter):
    """aiohttp logs a request it cannot parse (a 400: the client's mistake, e.g. no
    ``Host``) as an error with a traceback; this makes it one info line. Errors of the
    server itself (500) stay errors."""

    def filter(self, record: logging.LogRecord) -> bool:
        exc = record.exc_info[1] if record.exc_info else None
        if isinstance(exc, HttpProcessingError) and 400 <= exc.code < 500:
            record.msg = f"{record.getMessage()}: {exc.code} {exc.message}"
            record.args, record.exc_info, record.exc_text = (), None, None
            record.levelno, record.levelname = logging.INFO, "INFO"
        return True


http_log = logging.getLogger(__name__ + ".http")
http_log.addFilter(ClientMistakes())


@dataclass
class Page:
    """One connected page: its socket, outgoing queue and newest frame request."""

    ws: web.WebSocketResponse
    out: asyncio.Queue[tuple[dict[str, Any], bytes | None]] = field(default_factory=asyncio.Queue)
    pending: Message | None = None
    wake: asyncio.Event = field(default_factory=asyncio.Event)


class ViewerServer:
    """Serve ``source`` at ``host:port`` (0: any free port) from a background thread.

    ``allow_hosts``: further names a ``Host`` or ``Origin`` may give (``--allow-host``)."""

    def __init__(
        self,
        source: Source,
        host: str,
        port: int,
        allow_remote: bool = False,
        allow_hosts: Sequence[str] = (),
    ) -> None:
        self.source, self.host, self.port, self.allow_remote = source, host, port, allow_remote
        self.guard = Guard(host, allow_hosts, allow_remote)
        self.pages: dict[int, Page] = {}
        self._ids = itertools.count(1)
        self._loop: asyncio.AbstractEventLoop | None = None
        self._runner: web.AppRunner | None = None
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        """The page's address."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    def app(self) -> web.Application:
        """The aiohttp application."""
        app = web.Application(middlewares=[self._guarded])
        app.router.add_get("/", self._index)
        app.router.add_get("/ws", self._websocket)
        app.router.add_get("/static/{name}", self._asset)
        return app

    def start(self) -> str:
        """Bind and start serving; return the URL. MresimError if the port is taken.

        The server's event loop lives in its own thread from the start (binding included),
        so a caller that runs an event loop of its own (a notebook, Playwright's sync API)
        can start it too."""
        self._runner = runner = web.AppRunner(self.app(), access_log=None, logger=http_log)
        self._loop = loop = asyncio.new_event_loop()
        bound: concurrent.futures.Future[None] = concurrent.futures.Future()
        self._thread = threading.Thread(
            target=self._serve, args=(loop, runner, bound), name="viewer", daemon=True
        )
        self._thread.start()
        try:
            bound.result()
        except OSError as exc:
            self._thread.join(5)
            self._thread = None
            raise MresimError(bind_error(self.host, self.port, exc)) from None
        return self.url

    def _serve(
        self,
        loop: asyncio.AbstractEventLoop,
        runner: web.AppRunner,
        bound: concurrent.futures.Future[None],
    ) -> None:
        """The server thread: bind (the outcome goes to ``bound``), then run the loop
        until close(), then close it."""
        asyncio.set_event_loop(loop)
        try:
            loop.run_until_complete(self._bind(runner))
        except BaseException as exc:
            loop.run_until_complete(runner.cleanup())
            loop.close()
            bound.set_exception(exc)
            return
        bound.set_result(None)
        loop.run_forever()
        loop.close()

    async def _bind(self, runner: web.AppRunner) -> None:
        await runner.setup()
        await web.TCPSite(runner, self.host, self.port, reuse_address=False).start()
        self.port = int(runner.addresses[0][1])

    def close(self) -> None:
        """Stop serving (idempotent)."""
        loop = self._loop
        if self._thread is None or self._runner is None or loop is None:
            return
        runner, self._runner = self._runner, None
        with contextlib.suppress(RuntimeError, TimeoutError):
            asyncio.run_coroutine_threadsafe(runner.cleanup(), loop).result(5)
        loop.call_soon_threadsafe(loop.stop)
        self._thread.join(5)

    def swap(self, source: Source) -> None:
        """Serve ``source`` from now on and tell every page to reload."""
        self.source = source
        assert self._loop is not None, "swap() before start()"
        for page in list(self.pages.values()):
            self._loop.call_soon_threadsafe(page.out.put_nowait, ({"type": "reload"}, None))

    @web.middleware
    async def _guarded(self, request: web.Request, handler: Any) -> web.StreamResponse:
        """Refuse (403) what the guard refuses, before any handler runs."""
        refusal = self.guard.refusal(
            request.headers.getall("Host", []),
            request.headers.getall("Origin", []),
            Where(request.remote, local_address(request), self.port),
        )
        if refusal is not None:
            log.info("viewer: %s %s refused: %s", request.method, request.path, refusal)
            return web.Response(status=403, text=refusal)
        response: web.StreamResponse = await handler(request)
        return response

    async def _index(self, request: web.Request) -> web.StreamResponse:
        return web.FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-store"})

    async def _asset(self, request: web.Request) -> web.StreamResponse:
        """One of the page's files, by name; no other path reaches the file system (aiohttp's
        static route answered 500 to a name longer than the file system allows)."""
        name = request.match_info["name"]
        if name not in ASSETS:
            raise web.HTTPNotFound(text="mresim viewer: no such file.")
        return web.FileResponse(STATIC / name)

    async def _websocket(self, request: web.Request) -> web.StreamResponse:
        ws = web.WebSocketResponse(heartbeat=30.0, max_msg_size=MAX_FRAME)
        await ws.prepare(request)
        number, page = next(self._ids), Page(ws)
        self.pages[number] = page
        tasks = [
            asyncio.create_task(self._writer(page)),
            asyncio.create_task(self._worker(number, page)),
        ]
        try:
            await page.out.put((self.source.info(), None))
            if isinstance(self.source, LiveSource):
                self.source.connect()
            await self._read(page)
        finally:
            self.pages.pop(number, None)
            if isinstance(self.source, LiveSource):
                self.source.forget(number)
            for task in tasks:
                task.cancel()
        return ws

    async def _read(self, page: Page) -> None:
        """Read the page's messages: controls at once, frame requests through the worker."""
        async for msg in page.ws:
            if msg.type == WSMsgType.ERROR:  # e.g. a message past MAX_FRAME: aiohttp closes
                log.info("viewer: a page's socket failed: %s", msg.data)
                continue
            try:
                if msg.type != WSMsgType.TEXT:
                    raise ProtocolError("the viewer takes JSON text messages, not binary ones")
                message = parse_message(decode(msg.data), self.source.names)
            except ValueError as exc:  # ProtocolError, or a check that failed on its own
                self._refuse(page, str(exc))
                continue
            if message.op == "frame":
                page.pending = message
                page.wake.set()
            elif isinstance(self.source, LiveSource):
                self.source.command(message.op, message.value)

    def _refuse(self, page: Page, why: str) -> None:
        """Answer a malformed message with an error message (only log it if the page has
        left many unread), so a client that never reads cannot grow the queue."""
        log.info("viewer: a malformed message: %s", why)
        if page.out.qsize() < QUEUED_ERRORS:
            page.out.put_nowait(({"type": "error", "message": why}, None))

    async def _writer(self, page: Page) -> None:
        """Send the page's queued messages in order (a header, then its PNG)."""
        while True:
            header, png = await page.out.get()
            await page.ws.send_json(header)
            if png is not None:
                await page.ws.send_bytes(png)

    async def _worker(self, number: int, page: Page) -> None:
        """Serve the page's newest frame request."""
        loop = asyncio.get_running_loop()
        while True:
            await page.wake.wait()
            page.wake.clear()
            message, page.pending = page.pending, None
            if message is None or message.layers is None:
                continue
            source = self.source
            if isinstance(source, ReplaySource):
                header, png = await loop.run_in_executor(
                    None, source.frame, message.n, message.layers, message.known
                )
                await page.out.put((header, png))
            else:

                def deliver(header: dict[str, Any], png: bytes, page: Page = page) -> None:
                    loop.call_soon_threadsafe(page.out.put_nowait, (header, png))

                source.request(number, Want(message.layers, deliver, message.known))


def local_address(request: web.Request) -> str | None:
    """The address a request's connection arrived at (None if unknown)."""
    transport = request.transport
    name = transport.get_extra_info("sockname") if transport is not None else None
    return str(name[0]) if isinstance(name, tuple) and name else None


def bind_error(host: str, port: int, exc: OSError) -> str:
    """The one-paragraph message for a server that could not start."""
    if exc.errno == errno.EADDRINUSE:
        return (
            f"viewer: port {port} on {host} is already in use (another viewer or server?)."
            " Choose another with --port N, or --port 0 for any free port."
        )
    return (
        f"viewer: cannot serve on {host}:{port}: {exc.strerror or exc}."
        " Check --host (an address of this machine, e.g. 127.0.0.1) and --port."
    )
