"""The access token in front of a WebSocket server: a plain ``websockets`` client is refused (403)
without the token or with a wrong one, relayed with the right one, on 127.0.0.1 only (a test never
binds another address); the upstream here is a ``websockets`` echo server, the Foxglove SDK's is in
test_live.py."""

from __future__ import annotations

import asyncio
import socket
import threading
from collections.abc import Iterator

import pytest
from websockets.asyncio.server import ServerConnection, serve
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import connect
from websockets.typing import Subprotocol

from omnibot.errors import ConfigError
from omnibot.logs.gate import TokenGate, token_of

TOKEN = "a-token-of-ours"
PROTOCOL = Subprotocol("foxglove.sdk.v1")


class Echo:
    """A ``websockets`` echo server speaking the Foxglove subprotocol, on 127.0.0.1 in a thread of its
    own (its asyncio loop closed with it)."""

    def __init__(self) -> None:
        self.port = 0
        self._ready = threading.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._thread = threading.Thread(target=asyncio.run, args=(self._main(),))
        self._thread.start()
        self._ready.wait(10)

    async def _main(self) -> None:
        async def echo(ws: ServerConnection) -> None:
            async for message in ws:
                await ws.send(message)

        self._loop, self._stop = asyncio.get_running_loop(), asyncio.Event()
        async with serve(echo, "127.0.0.1", 0, subprotocols=[PROTOCOL]) as server:
            self.port = server.sockets[0].getsockname()[1]
            self._ready.set()
            await self._stop.wait()

    def close(self) -> None:
        assert self._loop is not None and self._stop is not None
        self._loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(10)


@pytest.fixture
def upstream() -> Iterator[Echo]:
    server = Echo()
    try:
        yield server
    finally:
        server.close()


@pytest.fixture
def gate(upstream: Echo) -> Iterator[TokenGate]:
    g = TokenGate("127.0.0.1", 0, upstream.port, TOKEN)
    try:
        yield g
    finally:
        g.close()


def url(gate: TokenGate, query: str = "") -> str:
    return f"ws://127.0.0.1:{gate.port}/{query}"


@pytest.mark.parametrize("query", ["", "?token=", "?token=wrong-token-x", f"?token={TOKEN}&token={TOKEN}"])
def test_no_token_or_a_wrong_one_is_refused(gate: TokenGate, query: str) -> None:
    with pytest.raises(InvalidStatus) as refused:
        connect(url(gate, query), subprotocols=[PROTOCOL], open_timeout=5)
    assert refused.value.response.status_code == 403
    assert b"access token" in refused.value.response.body
    assert gate.refused == 1 and gate.accepted == 0


def test_the_token_opens_the_relayed_server(gate: TokenGate) -> None:
    with connect(url(gate, f"?token={TOKEN}"), subprotocols=[PROTOCOL], open_timeout=5) as ws:
        assert ws.subprotocol == PROTOCOL  # the upstream's handshake, relayed
        ws.send(b"\x01binary")
        assert ws.recv(timeout=5) == b"\x01binary"
        ws.send("text")
        assert ws.recv(timeout=5) == "text"
    assert gate.accepted == 1 and gate.refused == 0


def test_close_ends_the_relayed_connections(upstream: Echo) -> None:
    gate = TokenGate("127.0.0.1", 0, upstream.port, TOKEN)
    with connect(url(gate, f"?token={TOKEN}"), subprotocols=[PROTOCOL], open_timeout=5) as ws:
        gate.close()
        with pytest.raises(ConnectionClosed):
            ws.recv(timeout=5)
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", gate.port), timeout=1).close()


def test_a_request_that_is_no_upgrade_is_refused(gate: TokenGate) -> None:
    with socket.create_connection(("127.0.0.1", gate.port), timeout=5) as s:
        s.sendall(b"POST /?token=" + TOKEN.encode() + b" HTTP/1.1\r\nHost: x\r\n\r\n")
        assert s.recv(100).startswith(b"HTTP/1.1 403")


def test_a_port_in_use_is_a_clear_error(gate: TokenGate) -> None:
    with pytest.raises(ConfigError, match=r"cannot listen on 127\.0\.0\.1"):
        TokenGate("127.0.0.1", gate.port, 1, TOKEN)


def test_token_of_reads_the_query_of_a_get() -> None:
    assert token_of(b"GET /?token=abc HTTP/1.1\r\nHost: x\r\n\r\n") == "abc"
    assert token_of(b"GET /path?x=1&token=a%2Bb HTTP/1.1\r\n\r\n") == "a+b"
    assert token_of(b"GET / HTTP/1.1\r\n\r\n") is None
    assert token_of(b"GET /?token=a&token=b HTTP/1.1\r\n\r\n") is None
    assert token_of(b"GARBAGE\r\n\r\n") is None


def test_the_old_subprotocol_is_offered_as_the_sdks_and_answered_by_its_old_name() -> None:
    from omnibot.logs.gate import answer_old, offer_sdk

    old = b"GET / HTTP/1.1\r\nHost: x\r\nsec-websocket-protocol: foxglove.websocket.v1\r\n\r\n"
    assert offer_sdk(old) == (
        b"GET / HTTP/1.1\r\nHost: x\r\nsec-websocket-protocol: foxglove.sdk.v1\r\n\r\n",
        True,
    )
    both = b"GET / HTTP/1.1\r\nSec-WebSocket-Protocol: foxglove.sdk.v1, foxglove.websocket.v1\r\n\r\n"
    assert offer_sdk(both) == (both, False)  # the SDK picks its own
    assert offer_sdk(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")[1] is False
    answer = b"HTTP/1.1 101 Switching Protocols\r\nsec-websocket-protocol: foxglove.sdk.v1\r\n\r\n"
    assert answer_old(answer) == answer.replace(b"foxglove.sdk.v1", b"foxglove.websocket.v1")
