"""In front of the Foxglove SDK's WebSocket server: an access token, which it has not, and the old
name of its subprotocol, which it does not accept.

The SDK's server accepts every client that speaks its subprotocol (its handshake checks only
``Sec-WebSocket-Protocol``; its listener hears of a client first when it subscribes or publishes,
too late to refuse it), so bound anywhere but loopback it would let anyone on the network drive the
robot through the Teleop panel. :class:`TokenGate` listens where the user asked, reads each
connection's HTTP upgrade request, and relays it to the SDK's server (bound to 127.0.0.1 on a port
of its own) only when its query carries the access token, ``ws://HOST:PORT/?token=TOKEN``, compared
in constant time by the dashboard's own :func:`omnibot.web.access.token_ok`. Any other request gets
``403 Forbidden`` and is closed before a byte reaches the SDK. Without a token (on loopback) every
request is relayed.

The SDK's handshake accepts only ``foxglove.sdk.v1``; Lichtblick and ws-protocol's clients offer
``foxglove.websocket.v1``, the same protocol under its old name (Foxglove says so: the two are
identical for now). A request that offers the old name and not the new one is relayed offering the
new one (:func:`offer_sdk`), and the SDK's answer goes back naming the old one (:func:`answer_old`).
Past the handshake, bytes flow both ways unchanged (the WebSocket handshake is the SDK's).

The gate runs its own asyncio loop in a thread (``omnibot-foxglove-gate``), started by the
constructor (which binds the port, so a port in use or a bad address fails at once) and stopped by
:meth:`close`, which ends every relayed connection.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
import threading
from urllib.parse import parse_qs, urlsplit

from omnibot.errors import ConfigError
from omnibot.web.access import listening_socket, token_ok

HEAD_LIMIT = 8192
"""Bytes an upgrade request's head may have."""
HEAD_TIMEOUT = 5.0
"""s a client has to send its whole request head."""
REFUSED = b"This server needs its access token: ws://HOST:PORT/?token=TOKEN (printed where it started).\n"


def listen(host: str, port: int, key: str) -> socket.socket:
    """A non-blocking listening TCP socket on ``host:port`` (0: a free port); ConfigError (``key``)
    saying why not."""
    sock = listening_socket(host, port, host_key=key, port_key=key, backlog=16)
    sock.setblocking(False)
    return sock


SDK_SUBPROTOCOL = "foxglove.sdk.v1"
OLD_SUBPROTOCOL = "foxglove.websocket.v1"
_PROTOCOL_HEADER = b"sec-websocket-protocol"


def _rename_protocols(head: bytes, old: str, new: str, *, unless: str = "") -> tuple[bytes, bool]:
    """``head`` with ``old`` named ``new`` in its ``Sec-WebSocket-Protocol`` header (not when it
    names ``unless`` too); whether it was renamed."""
    lines = head.split(b"\r\n")
    for i, line in enumerate(lines):
        name, sep, value = line.partition(b":")
        if not sep or name.strip().lower() != _PROTOCOL_HEADER:
            continue
        offered = [v.strip() for v in value.decode("latin-1").split(",")]
        if old not in offered or (unless and unless in offered):
            return head, False
        renamed = ", ".join(new if v == old else v for v in offered)
        lines[i] = name + b": " + renamed.encode("latin-1")
        return b"\r\n".join(lines), True
    return head, False


def offer_sdk(head: bytes) -> tuple[bytes, bool]:
    """An upgrade request offering :data:`OLD_SUBPROTOCOL` (and not the SDK's) made to offer
    :data:`SDK_SUBPROTOCOL`; whether it was."""
    return _rename_protocols(head, OLD_SUBPROTOCOL, SDK_SUBPROTOCOL, unless=SDK_SUBPROTOCOL)


def answer_old(head: bytes) -> bytes:
    """The SDK's answer to a request :func:`offer_sdk` renamed: the subprotocol by its old name."""
    return _rename_protocols(head, SDK_SUBPROTOCOL, OLD_SUBPROTOCOL)[0]


def token_of(head: bytes) -> str | None:
    """The ``token`` query parameter of an HTTP ``GET`` request head (None: none, or not exactly one)."""
    line = head.split(b"\r\n", 1)[0].decode("latin-1")
    parts = line.split(" ")
    if len(parts) != 3 or parts[0] != "GET" or not parts[2].startswith("HTTP/"):
        return None
    values = parse_qs(urlsplit(parts[1]).query).get("token", [])
    return values[0] if len(values) == 1 else None


class TokenGate:
    """Listens on ``host:port`` and relays the connections that give ``token`` (None: every one) to
    127.0.0.1:``upstream``, the old subprotocol's as the SDK's (see the module docstring);
    :attr:`port` is the port bound, :attr:`refused` counts the connections turned away."""

    def __init__(
        self, host: str, port: int, upstream: int, token: str | None, *, key: str = "--foxglove"
    ) -> None:
        self.host = host
        self.upstream = upstream
        self.token = token
        self.refused = 0
        self.accepted = 0
        self._sock = listen(host, port, key)
        self.port: int = self._sock.getsockname()[1]
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._ready = threading.Event()
        self._failed: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="omnibot-foxglove-gate", daemon=True)
        self._thread.start()
        self._ready.wait()
        if self._failed is not None:
            self._thread.join()
            self._sock.close()
            raise ConfigError(f"cannot serve on {host}:{port}: {self._failed}", key=key)

    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except BaseException as exc:  # before serving: the constructor reports it
            self._failed = exc
        finally:
            self._ready.set()

    async def _main(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        tasks: set[asyncio.Task[None]] = set()

        async def serve(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
            task = asyncio.current_task()
            assert task is not None
            tasks.add(task)
            try:
                await self._serve(reader, writer)
            finally:
                tasks.discard(task)
                writer.close()
                with contextlib.suppress(Exception):
                    await writer.wait_closed()

        server = await asyncio.start_server(serve, sock=self._sock, limit=HEAD_LIMIT)
        self._ready.set()
        try:
            await self._stop.wait()
        finally:
            server.close()
            for task in list(tasks):
                task.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)
            await server.wait_closed()

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            head = await asyncio.wait_for(reader.readuntil(b"\r\n\r\n"), HEAD_TIMEOUT)
        except (asyncio.IncompleteReadError, asyncio.LimitOverrunError, TimeoutError, ConnectionError):
            self.refused += 1
            return
        if self.token is not None and not token_ok(self.token, token_of(head)):
            self.refused += 1
            writer.write(
                b"HTTP/1.1 403 Forbidden\r\nContent-Type: text/plain; charset=utf-8\r\n"
                + f"Content-Length: {len(REFUSED)}\r\nConnection: close\r\n\r\n".encode("ascii")
                + REFUSED
            )
            with contextlib.suppress(ConnectionError):
                await writer.drain()
            return
        try:
            up_reader, up_writer = await asyncio.open_connection("127.0.0.1", self.upstream)
        except OSError:
            return
        self.accepted += 1
        head, renamed = offer_sdk(head)
        try:
            up_writer.write(head)
            if renamed:  # the SDK's answer names the subprotocol as the client asked
                try:
                    answer = await asyncio.wait_for(up_reader.readuntil(b"\r\n\r\n"), HEAD_TIMEOUT)
                except (
                    asyncio.IncompleteReadError,
                    asyncio.LimitOverrunError,
                    TimeoutError,
                    ConnectionError,
                ):
                    return
                writer.write(answer_old(answer))
            await asyncio.gather(_pipe(reader, up_writer), _pipe(up_reader, writer))
        finally:
            up_writer.close()
            with contextlib.suppress(Exception):
                await up_writer.wait_closed()

    def close(self) -> None:
        """Stop listening and end every relayed connection (idempotent)."""
        loop, stop = self._loop, self._stop
        if loop is not None and stop is not None and self._thread.is_alive():
            with contextlib.suppress(RuntimeError):  # the loop already ended
                loop.call_soon_threadsafe(stop.set)
            self._thread.join(timeout=5.0)
        self._sock.close()


async def _pipe(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
    """Copy ``reader`` to ``writer`` until either end closes; then close ``writer``."""
    try:
        while data := await reader.read(65536):
            writer.write(data)
            await writer.drain()
    except ConnectionError:
        pass
    finally:
        writer.close()
