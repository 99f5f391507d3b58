"""TCP links against a local echo server on 127.0.0.1 (ephemeral port)."""

from __future__ import annotations

import socket
import time

import pytest

from omnibot.errors import ConfigError, LinkError
from omnibot.transport import TcpLink, open_link

from .fakes import EchoServer


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_roundtrip_over_url() -> None:
    with EchoServer() as server, open_link(f"tcp://127.0.0.1:{server.port}") as link:
        assert isinstance(link, TcpLink)
        link.write(b"ping\n")
        data = b""
        while len(data) < 5:
            data += link.read(timeout=2)
        assert data == b"ping\n"
        t0 = time.monotonic()
        assert link.read(timeout=0.05) == b""
        assert time.monotonic() - t0 >= 0.04


def test_peer_close_is_a_link_error_and_reopen_reconnects() -> None:
    with EchoServer() as server, TcpLink("127.0.0.1", server.port) as link:
        # generous waits (each ends when the peer acts): the echo server is a thread of this process,
        # which a loaded machine may not run for a while
        link.write(b"a")
        assert link.read(timeout=10) == b"a"
        server.drop_client()
        with pytest.raises(LinkError, match="closed by peer"):
            link.read(timeout=10)
        with pytest.raises(LinkError, match="not connected"):
            link.write(b"x")
        link.reopen(retry=20.0)
        link.write(b"b")
        assert link.read(timeout=10) == b"b"


def test_refused() -> None:
    port = free_port()
    with pytest.raises(LinkError, match=f"cannot connect to 127.0.0.1:{port}"):
        TcpLink("127.0.0.1", port)


def test_bad_port() -> None:
    with pytest.raises(ValueError):
        TcpLink("127.0.0.1", 0)
    with pytest.raises(ConfigError):
        open_link("tcp://127.0.0.1:notaport")
