"""``--foxglove``: a plain ``websockets`` client speaking the ``foxglove.sdk.v1`` subprotocol
subscribes to the live channels and decodes what it gets: the values the client sent."""

from __future__ import annotations

import asyncio
import json
import math
import os
import struct
import time
from typing import Any

import pytest
import websockets
from websockets.typing import Subprotocol

from omnibot.cli import main
from omnibot.client import RobotClient, guarded
from omnibot.logs import schemas, topics
from omnibot.logs.live import FoxgloveLive
from omnibot.logs.recorder import Recorder
from omnibot.protocol.messages import Vel
from omnibot.robot import load_robot

MESSAGE_DATA = 0x01


def test_each_server_leaves_nothing_behind() -> None:
    def run_one() -> None:
        live = FoxgloveLive(0)
        text = schemas.new("std_msgs/msg/String", data="x")
        live("x", "std_msgs/msg/String", schemas.serialize(text, "std_msgs/msg/String"), 1)
        live.close()

    def fds() -> int:
        return len(os.listdir("/proc/self/fd"))

    before = fds()
    for _ in range(3):
        run_one()
    assert fds() == before


def test_a_websocket_client_gets_the_live_channels() -> None:
    robot = load_robot("omni4")
    live = FoxgloveLive(0)
    rec = Recorder(None, mirrors=[live])
    client = RobotClient.open("sim://omni4?seed=2", robot)
    sent: list[Vel] = []

    def drive(steps: int) -> None:
        for i in range(steps):
            sent.append(client.vel(0.2, 0.05 * math.sin(i / 10), 0.3, 0.2))
            client.sleep(0.01)

    async def session() -> tuple[dict[int, str], list[tuple[int, bytes]]]:
        url = f"ws://127.0.0.1:{live.port}"
        async with websockets.connect(url, subprotocols=[Subprotocol("foxglove.sdk.v1")]) as ws:
            assert ws.subprotocol == "foxglove.sdk.v1"
            info = json.loads(await asyncio.wait_for(ws.recv(), 5))
            assert info["op"] == "serverInfo"
            drive(20)  # the channels are advertised once they carry a message
            channels: dict[str, dict[str, Any]] = {}
            while topics.CMD_VEL not in channels or topics.ODOM not in channels:
                msg = json.loads(await asyncio.wait_for(ws.recv(), 5))
                if msg["op"] == "advertise":
                    channels |= {c["topic"]: c for c in msg["channels"]}
            assert channels[topics.ODOM]["schemaEncoding"] == "ros2msg"
            assert channels[topics.ODOM]["encoding"] == "cdr"
            wanted = {1: topics.CMD_VEL, 2: topics.ODOM}
            subs = [{"id": sid, "channelId": channels[topic]["id"]} for sid, topic in wanted.items()]
            await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
            await asyncio.sleep(0.3)
            drive(50)
            got: list[tuple[int, bytes]] = []
            try:
                while True:
                    frame = await asyncio.wait_for(ws.recv(), 1.0)
                    if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
                        sub, _ = struct.unpack_from("<IQ", frame, 1)
                        got.append((sub, frame[13:]))
            except TimeoutError:
                pass
            return wanted, got

    try:
        with guarded(client, robot=robot):
            rec.attach(client, robot)
            client.telemetry(0.01)
            wanted, got = asyncio.run(session())
    finally:
        rec.close()  # stops the server
    cmd = [
        schemas.deserialize(d, "geometry_msgs/msg/TwistStamped")
        for s, d in got
        if wanted[s] == topics.CMD_VEL
    ]
    odom = [schemas.deserialize(d, "nav_msgs/msg/Odometry") for s, d in got if wanted[s] == topics.ODOM]
    assert len(cmd) >= 50 and len(odom) >= 40
    expected = sent[-len(cmd) :]
    assert [round(m.twist.linear.y * 100) for m in cmd] == [v.vy for v in expected]
    assert [round(math.degrees(m.twist.angular.z)) for m in cmd] == [v.w for v in expected]
    assert odom[-1].pose.pose.position.x > 0.05  # the robot drove ahead, and the estimate saw it


def test_sim_refuses_foxglove(capsys: Any) -> None:
    assert main(["sim", "--pty", "--foxglove"]) == 2
    assert "--foxglove goes on the command that drives it" in capsys.readouterr().err


def test_a_token_guards_the_live_server() -> None:
    """Bound with a token (on 127.0.0.1: tests bind nothing else): refused without the token or with
    a wrong one, served with it."""
    from websockets.exceptions import InvalidStatus

    token = "live-token-123"
    live = FoxgloveLive(0, token=token)
    try:
        assert live.url == f"ws://127.0.0.1:{live.port}/?token={token}"

        async def handshake(query: str) -> str:
            url = f"ws://127.0.0.1:{live.port}/{query}"
            async with websockets.connect(url, subprotocols=[Subprotocol("foxglove.sdk.v1")]) as ws:
                info = json.loads(await asyncio.wait_for(ws.recv(), 5))
                return str(info["op"])

        for query in ("", "?token=wrong-token-1"):
            with pytest.raises(InvalidStatus) as refused:
                asyncio.run(handshake(query))
            assert refused.value.response.status_code == 403
        assert asyncio.run(handshake(f"?token={token}")) == "serverInfo"
    finally:
        live.close()


def test_foxglove_address_and_token_are_checked_before_anything_runs(
    capsys: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    from omnibot.logs.live import parse_address
    from omnibot.logs.recording import FoxgloveBind

    assert parse_address("8765") == ("127.0.0.1", 8765)
    assert parse_address("0.0.0.0:0") == ("0.0.0.0", 0)
    assert parse_address("[::1]:9000") == ("::1", 9000)
    assert parse_address("robot.local:8765") == ("robot.local", 8765)
    monkeypatch.delenv("OMNIBOT_FOXGLOVE_TOKEN", raising=False)
    assert FoxgloveBind.parse("8765") == FoxgloveBind("127.0.0.1", 8765)
    made = FoxgloveBind.parse("0.0.0.0:8765")  # parsed only: nothing is bound
    assert made.token is not None and len(made.token) >= 16 and made.made_up
    assert FoxgloveBind.parse("0.0.0.0:8765", "given-token").token == "given-token"
    monkeypatch.setenv("OMNIBOT_FOXGLOVE_TOKEN", "from-the-env")
    assert FoxgloveBind.parse("127.0.0.1:0") == FoxgloveBind("127.0.0.1", 0, "from-the-env")
    monkeypatch.delenv("OMNIBOT_FOXGLOVE_TOKEN")
    cases = [
        (["--foxglove", "::1:8765"], "expected [HOST:]PORT"),
        (["--foxglove", "70000"], "expected [HOST:]PORT"),
        (["--foxglove", "host:"], "expected [HOST:]PORT"),
        (["--foxglove", "0", "--foxglove-token", "short"], "at least 8 characters"),
        (["--foxglove-token", "long-enough-token"], "--foxglove-token goes with --foxglove"),
    ]
    for extra, message in cases:
        assert main(["send", "--port", "sim://omni4", "STATUS", *extra]) == 2, extra
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err, err


@pytest.mark.parametrize("token", [None, "live-token-123"], ids=["loopback", "with a token"])
def test_a_client_speaking_only_the_old_subprotocol_is_served(token: str | None) -> None:
    """Lichtblick and ws-protocol's clients offer only ``foxglove.websocket.v1`` (the SDK's
    ``foxglove.sdk.v1`` under its old name): the handshake answers with it, and the client gets
    the server's info, the channel advertised and its messages."""
    live = FoxgloveLive(0, token=token)
    text = schemas.new("std_msgs/msg/String", data="hello")
    data = schemas.serialize(text, "std_msgs/msg/String")

    async def session() -> tuple[str | None, str, bytes]:
        async with websockets.connect(live.url, subprotocols=[Subprotocol("foxglove.websocket.v1")]) as ws:
            info = json.loads(await asyncio.wait_for(ws.recv(), 5))
            live("/greeting", "std_msgs/msg/String", data, 1)  # advertised once it carries a message
            channel = None
            while channel is None:
                msg = json.loads(await asyncio.wait_for(ws.recv(), 5))
                if msg["op"] == "advertise":
                    channel = next((c for c in msg["channels"] if c["topic"] == "/greeting"), None)
            await ws.send(
                json.dumps({"op": "subscribe", "subscriptions": [{"id": 7, "channelId": channel["id"]}]})
            )
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline:  # a message logged before the subscription is not sent
                live("/greeting", "std_msgs/msg/String", data, 2)
                try:
                    frame = await asyncio.wait_for(ws.recv(), 0.2)
                except TimeoutError:
                    continue
                if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
                    (sub,) = struct.unpack_from("<I", frame, 1)
                    assert sub == 7
                    return ws.subprotocol, str(info["op"]), frame[13:]
            raise AssertionError("no message on the subscription")

    try:
        subprotocol, op, payload = asyncio.run(session())
    finally:
        live.close()
    assert (subprotocol, op) == ("foxglove.websocket.v1", "serverInfo")
    assert schemas.deserialize(payload, "std_msgs/msg/String").data == "hello"


def test_a_command_with_foxglove_serves_and_closes(capsys: Any) -> None:
    """``omnibot send --foxglove 0`` serves on a free loopback port while it runs and closes it
    (the leak check: no thread, fd or port left), without a token on loopback."""
    assert main(["send", "--port", "sim://omni4", "--foxglove", "0", "STATUS"]) == 0
    err = capsys.readouterr().err
    url = next(line for line in err.splitlines() if "Foxglove live on" in line).split()[-1]
    assert url.startswith("ws://127.0.0.1:") and url.endswith("/") and "token" not in url
