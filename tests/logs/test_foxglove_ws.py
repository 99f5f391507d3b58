"""The Foxglove WebSocket protocol server on its own (127.0.0.1 only): the token, the subprotocol
names, and a client that breaks the protocol told why and kept, or cut off when it floods."""

from __future__ import annotations

import json
import socket
import struct
from collections.abc import Iterator

import pytest
from websockets.exceptions import ConnectionClosed, InvalidHandshake, InvalidStatus
from websockets.sync.client import ClientConnection, connect
from websockets.typing import Subprotocol

from omnibot.errors import ConfigError
from omnibot.logs.foxglove_conn import ClientChannel
from omnibot.logs.foxglove_ws import BURST, FoxgloveServer

TOKEN = "a-token-of-ours"
SDK = Subprotocol("foxglove.sdk.v1")


class Taken:
    """A :class:`~omnibot.logs.foxglove_conn.Publishing` that keeps what it is given; refuses the
    topic ``no``."""

    def __init__(self) -> None:
        self.got: list[tuple[str, bytes]] = []

    def advertised(self, channel: ClientChannel) -> None:
        if channel.topic == "no":
            raise ValueError("not this one")

    def received(self, channel: ClientChannel, data: bytes) -> None:
        if data == b"bad":
            raise ValueError("bad data")
        self.got.append((channel.topic, data))


@pytest.fixture
def taken() -> Taken:
    return Taken()


@pytest.fixture
def server(taken: Taken) -> Iterator[FoxgloveServer]:
    s = FoxgloveServer("127.0.0.1", 0, taken, token=TOKEN)
    try:
        yield s
    finally:
        s.close()


def opened(server: FoxgloveServer, query: str = f"?token={TOKEN}", proto: str = SDK) -> ClientConnection:
    return connect(f"ws://127.0.0.1:{server.port}/{query}", subprotocols=[Subprotocol(proto)], open_timeout=5)


def next_status(ws: ClientConnection) -> dict[str, object]:
    while True:
        frame = ws.recv(timeout=5)
        if isinstance(frame, str) and json.loads(frame)["op"] == "status":
            return dict(json.loads(frame))


@pytest.mark.parametrize("query", ["", "?token=", "?token=wrong-token-x", f"?token={TOKEN}&token={TOKEN}"])
def test_no_token_or_a_wrong_one_is_refused(server: FoxgloveServer, query: str) -> None:
    with pytest.raises(InvalidStatus) as refused:
        opened(server, query)
    assert refused.value.response.status_code == 403
    assert b"access token" in refused.value.response.body
    assert server.refused == 1 and server.clients == 0


@pytest.mark.parametrize("proto", ["foxglove.sdk.v1", "foxglove.websocket.v1"])
def test_both_subprotocol_names_are_answered_by_the_name_offered(server: FoxgloveServer, proto: str) -> None:
    with opened(server, proto=proto) as ws:
        assert ws.subprotocol == proto
        info = json.loads(ws.recv(timeout=5))
        assert info["op"] == "serverInfo" and info["capabilities"] == ["clientPublish"]


def test_another_subprotocol_or_a_plain_request_is_refused(server: FoxgloveServer) -> None:
    with pytest.raises(InvalidHandshake):
        opened(server, proto="chat.v2").close()
    with socket.create_connection(("127.0.0.1", server.port), timeout=5) as s:
        s.sendall(b"POST /?token=" + TOKEN.encode() + b" HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
        assert s.recv(100).startswith(b"HTTP/1.1 4")
    assert server.clients == 0


def test_a_client_breaking_the_protocol_is_told_why_and_kept(server: FoxgloveServer, taken: Taken) -> None:
    with opened(server) as ws:
        ws.recv(timeout=5)  # serverInfo
        cases: list[tuple[str | bytes, int, str]] = [
            ("not json", 1, "expected a JSON object"),
            (json.dumps({"op": "fly"}), 1, "unsupported message 'fly'"),
            (json.dumps({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": 99}]}), 2, "advertised"),
            (json.dumps({"op": "subscribe", "subscriptions": [{"id": True, "channelId": 1}]}), 2, "subscribe"),
            (json.dumps({"op": "advertise", "channels": [{"id": 3, "topic": 5}]}), 2, "strings"),
            (json.dumps({"op": "advertise", "channels": [{"id": 4, "topic": "no", "encoding": "json",
                                                          "schemaName": "x"}]}), 1, "not this one"),
            (b"\x02abcd", 2, "expected binary message data"),
            (struct.pack("<BI", 1, 4) + b"{}", 2, "did not advertise"),
        ]  # fmt: skip
        for frame, level, text in cases:
            ws.send(frame)
            status = next_status(ws)
            assert status["level"] == level and text in str(status["message"]), (frame, status)
        channel = {"id": 5, "topic": "yes", "encoding": "json", "schemaName": "x"}
        ws.send(json.dumps({"op": "advertise", "channels": [channel]}))
        ws.send(struct.pack("<BI", 1, 5) + b"bad")
        status = next_status(ws)
        assert status["level"] == 2 and "message refused, not driven: bad data" in str(status["message"])
        ws.send(struct.pack("<BI", 1, 5) + b"good")
        ws.send(json.dumps({"op": "unadvertise", "channelIds": [5]}))
        ws.send(struct.pack("<BI", 1, 5) + b"late")
        assert "did not advertise" in str(next_status(ws)["message"])
    assert taken.got == [("yes", b"good")]


def test_a_flooding_client_is_cut_off(server: FoxgloveServer) -> None:
    with opened(server) as ws:
        with pytest.raises(ConnectionClosed) as closed:
            for _ in range(BURST * 3):
                ws.send(json.dumps({"op": "unsubscribe", "subscriptionIds": []}))
            while True:
                ws.recv(timeout=5)
        assert closed.value.rcvd is not None and closed.value.rcvd.code == 1008


def test_a_subscriber_gets_what_is_published_and_others_nothing(server: FoxgloveServer) -> None:
    with opened(server) as ws, opened(server) as idle:
        ws.recv(timeout=5)
        server.publish("/a", "std_msgs/msg/String", "string data", b"one", 1)
        advert = json.loads(ws.recv(timeout=5))
        assert advert["op"] == "advertise" and advert["channels"][0]["topic"] == "/a"
        ws.send(
            json.dumps(
                {"op": "subscribe", "subscriptions": [{"id": 9, "channelId": advert["channels"][0]["id"]}]}
            )
        )
        for k in range(200):  # the subscription reaches the server's thread in its own time
            server.publish("/a", "std_msgs/msg/String", "string data", b"two", 2 + k)
            try:
                frame = ws.recv(timeout=0.05)
            except TimeoutError:
                continue
            assert isinstance(frame, bytes) and frame[:5] == struct.pack("<BI", 1, 9) and frame[13:] == b"two"
            break
        else:
            raise AssertionError("nothing on the subscription")
        assert [json.loads(idle.recv(timeout=5))["op"] for _ in range(2)] == ["serverInfo", "advertise"]
        with pytest.raises(TimeoutError):
            idle.recv(timeout=0.2)


def test_a_topic_new_while_a_client_connects_is_advertised_to_it_once(
    server: FoxgloveServer, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The topic's broadcast reaches the loop after the client's greeting already listed it."""
    held: list[tuple[object, tuple[object, ...]]] = []
    call = server._call
    monkeypatch.setattr(server, "_call", lambda fn, *args: held.append((fn, args)))
    server.publish("/a", "std_msgs/msg/String", "string data", b"one", 1)
    with opened(server) as ws:
        assert [json.loads(ws.recv(timeout=5))["op"] for _ in range(2)] == ["serverInfo", "advertise"]
        for fn, args in held:
            call(fn, *args)
        with pytest.raises(TimeoutError):
            ws.recv(timeout=0.3)


def test_a_port_in_use_is_a_clear_error(server: FoxgloveServer, taken: Taken) -> None:
    with pytest.raises(ConfigError, match=r"cannot listen on 127\.0\.0\.1"):
        FoxgloveServer("127.0.0.1", server.port, taken)


def test_close_ends_every_connection(taken: Taken) -> None:
    s = FoxgloveServer("127.0.0.1", 0, taken)
    with opened(s, "") as ws:
        s.close()
        with pytest.raises(ConnectionClosed):
            while True:
                ws.recv(timeout=5)
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", s.port), timeout=1).close()


def test_json_nested_too_deeply_is_told_not_a_traceback(server: FoxgloveServer) -> None:
    with opened(server) as ws:
        ws.recv(timeout=5)
        ws.send("[" * 30_000 + "]" * 30_000)
        assert "expected a JSON object" in str(next_status(ws)["message"])
        ws.send(json.dumps({"op": "unsubscribe", "subscriptionIds": []}))  # still served
