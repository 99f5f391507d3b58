"""The web server: the page, its assets, and one websocket per page for the live stream and driving.

::

    GET /            the page (index.html); with a token configured, only with ?token=TOKEN
    GET /static/...  app.js, style.css
    WS  /ws          server -> page: scene (on connect), trail (on connect), state (20 Hz), log,
                     error (a rejected message), pong
                     page -> server: drive, joy, estop, resume, teach, ping (omnibot.web.messages)

Access (omnibot.web.access, docs/dashboard.md "Security"): a request whose ``Host`` is not this
server is refused (DNS rebinding); a token (when configured) must be given as ``?token=`` on the
page and the websocket (compared in constant time); a websocket whose ``Origin`` is not this server
is refused, so another site open in the same browser cannot drive the robot.

Hostile frames end the connection with a close frame, never an exception: binary 1003, larger
than :data:`MAX_FRAME` 1009 (uvicorn closes frames over ``ws_max_size`` with 1009 itself, text that
is not UTF-8 with 1007), more than :data:`RATE` messages a second (bursts :data:`BURST`) 1008; at
most :data:`MAX_PAGES` pages at once (1013). Messages that fail validation (not JSON, nested too
deeply, wrong types, out of range) are answered with an ``error`` frame and never reach the robot
link; a robot link too busy to take a message (its inbox full) is said the same way.

:class:`Hub` lives in the server's event loop: the broadcaster task drains the link's outbox every
50 ms, keeps the trail and the newest state, and sends to every page.
"""

from __future__ import annotations

import asyncio
import contextlib
import queue
import threading
from collections import deque
from collections.abc import AsyncIterator, Callable
from importlib.resources import files
from typing import Any

from fastapi import FastAPI, Query, WebSocket, WebSocketDisconnect
from fastapi.responses import HTMLResponse, Response
from fastapi.staticfiles import StaticFiles
from starlette.websockets import WebSocketState

from omnibot.web.access import RateLimit, same_origin, token_ok
from omnibot.web.inbox import PageGone, Request
from omnibot.web.messages import MAX_FRAME, Ping, parse_message

BROADCAST_PERIOD = 0.05
SEND_TIMEOUT = 1.0
"""s a page may take to accept one frame."""
TRAIL_MAX = 5000
TRAIL_STEP = 0.005
"""m: a pose joins the trail when it is this far from the last one kept."""
RATE = 100.0
"""Messages a second one page may send on average (the page sends about 41: drive and joy at 20 Hz, a
ping a second)."""
BURST = 200
"""Messages one page may send at once before :data:`RATE` applies."""
MAX_PAGES = 16
"""Websockets served at once."""

CLOSE_UNSUPPORTED = 1003
CLOSE_POLICY = 1008
CLOSE_TOO_BIG = 1009
CLOSE_BUSY = 1013

STATIC = files("omnibot.web") / "static"

FORBIDDEN = """<!doctype html><meta charset="utf-8"><title>omnibot dashboard</title>
<p>This dashboard needs its access token: open the address <code>omnibot dashboard</code> printed
(it ends in <code>?token=...</code>).</p>"""


class Hub:
    """The page side of the link: who is connected, the trail, the newest state; thread-safe reads
    of :attr:`latest` and :attr:`logs` for tests and tools."""

    def __init__(
        self, scene: dict[str, Any], outbox: queue.Queue[dict[str, Any]], submit: Callable[[Request], bool]
    ):
        self.scene = scene
        self.outbox = outbox
        self.submit = submit
        self.pages: set[WebSocket] = set()
        self.trail: deque[list[float]] = deque(maxlen=TRAIL_MAX)
        self.rejected = 0
        self.closed: list[int] = []
        """Close codes the server sent to hostile pages, oldest first (the last 100)."""
        self.rate_limit: Callable[[], RateLimit] = lambda: RateLimit(RATE, BURST)
        """Makes each page's message budget (tests may give a smaller one)."""
        self.connections = 0
        self._lock = threading.Lock()
        self._latest: dict[str, Any] | None = None
        self._logs: list[dict[str, Any]] = []

    @property
    def latest(self) -> dict[str, Any] | None:
        """The newest state frame (from any thread)."""
        with self._lock:
            return self._latest

    @property
    def logs(self) -> list[dict[str, Any]]:
        """The recent log frames, oldest first (the last 200; from any thread)."""
        with self._lock:
            return list(self._logs)

    def _keep(self, frame: dict[str, Any]) -> None:
        if frame.get("type") == "state":
            with self._lock:
                self._latest = frame
            pose = frame.get("pose")
            if pose is not None:
                last = self.trail[-1] if self.trail else None
                if last is None or abs(pose[0] - last[0]) + abs(pose[1] - last[1]) >= TRAIL_STEP:
                    self.trail.append([pose[0], pose[1]])
        elif frame.get("type") == "log":
            with self._lock:
                self._logs = [*self._logs[-199:], frame]

    async def broadcast_forever(self) -> None:
        """Forever: drain the outbox every BROADCAST_PERIOD and send its frames to every page, of the state
        frames only the newest."""
        while True:
            frames: list[dict[str, Any]] = []
            while True:
                try:
                    frames.append(self.outbox.get_nowait())
                except queue.Empty:
                    break
            state = None
            for frame in frames:
                self._keep(frame)
                if frame.get("type") == "state":
                    state = frame  # only the newest state goes out
                else:
                    await self.send_all(frame)
            if state is not None:
                await self.send_all(state)
            await asyncio.sleep(BROADCAST_PERIOD)

    async def send_all(self, frame: dict[str, Any]) -> None:
        """Send to every page; a page that does not take a frame within SEND_TIMEOUT (gone, or not
        reading) is dropped from the stream, so it cannot hold up the others."""
        for page in list(self.pages):
            try:
                await asyncio.wait_for(page.send_json(frame), SEND_TIMEOUT)
            except Exception:  # gone or stuck; its handler cleans up when the connection ends
                self.pages.discard(page)

    async def serve_page(self, ws: WebSocket) -> None:
        """One page's websocket (accepted): hello frames, then validate and forward what it sends;
        hostile frames close it (see the module docstring)."""
        self.connections += 1
        try:
            await ws.send_json(self.scene)
            await ws.send_json({"type": "trail", "points": list(self.trail)})
            self.pages.add(ws)
            budget = self.rate_limit()
            while True:
                frame = await ws.receive()
                if frame["type"] == "websocket.disconnect":
                    break
                text = frame.get("text")
                if text is None:
                    await self._close(ws, CLOSE_UNSUPPORTED, "binary frames are not accepted: send JSON text")
                    break
                if len(text) > MAX_FRAME:
                    await self._close(ws, CLOSE_TOO_BIG, f"message too long (at most {MAX_FRAME} characters)")
                    break
                if not budget.take():
                    await self._close(ws, CLOSE_POLICY, f"too many messages (at most {RATE:g} a second)")
                    break
                await self._answer(ws, text)
        except WebSocketDisconnect:  # gone while we answered
            pass
        finally:
            self.connections -= 1
            self.pages.discard(ws)
            self.submit(PageGone())

    async def _answer(self, ws: WebSocket, text: str) -> None:
        message = parse_message(text)
        if isinstance(message, str):
            self.rejected += 1
            await ws.send_json({"type": "error", "error": f"message rejected: {message}"})
        elif isinstance(message, Ping):
            await ws.send_json({"type": "pong", "t": message.t})
        elif not self.submit(message):
            self.rejected += 1
            await ws.send_json({"type": "error", "error": "message dropped: the robot link is busy"})

    async def _close(self, ws: WebSocket, code: int, reason: str) -> None:
        self.closed = [*self.closed[-99:], code]
        self.pages.discard(ws)
        if ws.application_state == WebSocketState.CONNECTED:
            with contextlib.suppress(Exception):  # the page may be gone already
                await ws.close(code, reason)


def create_app(hub: Hub, token: str | None = None) -> FastAPI:
    """The FastAPI application serving ``hub``; ``token`` None: no token needed (loopback only).
    The Host check wraps it (:class:`omnibot.web.access.HostCheck`, added by the dashboard)."""
    required = token

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        task = asyncio.create_task(hub.broadcast_forever(), name="omnibot-broadcast")
        try:
            yield
        finally:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task

    app = FastAPI(
        title="omnibot dashboard", lifespan=lifespan, docs_url=None, redoc_url=None, openapi_url=None
    )
    app.mount("/static", StaticFiles(directory=str(STATIC)), name="static")

    @app.get("/", response_class=HTMLResponse)
    async def index(token: str | None = Query(default=None, max_length=200)) -> Response:
        if not token_ok(required, token):
            return HTMLResponse(FORBIDDEN, status_code=401)
        html = (STATIC / "index.html").read_text(encoding="utf-8")
        return HTMLResponse(html, headers={"Cache-Control": "no-store"})

    @app.websocket("/ws")
    async def stream(ws: WebSocket, token: str | None = Query(default=None, max_length=200)) -> None:
        if not token_ok(required, token) or not same_origin(ws.headers.get("origin"), ws.headers.get("host")):
            await ws.close(code=CLOSE_POLICY)  # before accepting: the client sees 403
            return
        if hub.connections >= MAX_PAGES:
            await ws.close(code=CLOSE_BUSY)
            return
        await ws.accept()
        await hub.serve_page(ws)

    return app


__all__ = ["MAX_FRAME", "Hub", "create_app"]
