"""Who may drive the robot through Foxglove live: the dashboard's access rules (a foreign
``Origin`` and a rebinding ``Host`` refused, the token on every port the process listens on) and
typed numbers in the Teleop panel's twists. Each case attacks as a web page or a program would,
then runs the runtime for 1 s of simulated time: the simulator's truth says whether the robot moved."""

from __future__ import annotations

import asyncio
import json
import math
import os
import re
import socket
import struct
from collections.abc import Iterator
from typing import Any

import pytest
import websockets
from websockets.typing import Subprotocol

from omnibot.client import RobotClient
from omnibot.logs.live import FoxgloveLive
from omnibot.runtime import Runtime
from tests.teleop.fakes import truth

CLIENT_MESSAGE_DATA = 0x01
TOKEN = "live-token-12345"
MOVED = 0.005
"""m: more than this is a robot that moved."""
AHEAD = {"linear": {"x": 0.4, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}


def listening_ports() -> set[int]:
    """Every TCP port this process listens on (its sockets in LISTEN state, IPv4 and IPv6)."""
    inodes = set()
    for fd in os.listdir("/proc/self/fd"):
        with_target = os.readlink(f"/proc/self/fd/{fd}") if os.path.islink(f"/proc/self/fd/{fd}") else ""
        found = re.fullmatch(r"socket:\[(\d+)\]", with_target)
        if found:
            inodes.add(found.group(1))
    ports = set()
    for table in ("/proc/self/net/tcp", "/proc/self/net/tcp6"):
        with open(table) as f:
            for line in f.readlines()[1:]:
                cols = line.split()
                if cols[3] == "0A" and cols[9] in inodes:  # LISTEN
                    ports.add(int(cols[1].rsplit(":", 1)[1], 16))
    return ports


async def attempt(
    port: int,
    *,
    host: str | None = None,
    origin: str | None = None,
    query: str = "",
    twist: Any = AHEAD,
    protocol: str = "foxglove.sdk.v1",
) -> tuple[str, list[dict[str, Any]]]:
    """Connect to 127.0.0.1:``port`` saying ``Host: host`` (default 127.0.0.1:port) and ``Origin:
    origin``, advertise ``/cmd_vel`` as the Teleop panel does and publish ``twist`` (JSON) three
    times; "refused" or "open", and the status messages the server sent."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=5)
    sock.setblocking(False)
    try:
        ws = await websockets.connect(
            f"ws://{host or f'127.0.0.1:{port}'}/{query}",
            sock=sock,
            additional_headers={"Origin": origin} if origin else None,
            subprotocols=[Subprotocol(protocol)],
            open_timeout=5,
            close_timeout=2,
        )
    except (websockets.exceptions.InvalidHandshake, OSError, TimeoutError):
        sock.close()
        return "refused", []
    statuses: list[dict[str, Any]] = []
    try:
        json.loads(await asyncio.wait_for(ws.recv(), 5))  # serverInfo
        channel = {"id": 7, "topic": "/cmd_vel", "encoding": "json", "schemaName": "geometry_msgs/Twist"}
        await ws.send(json.dumps({"op": "advertise", "channels": [channel]}))
        for _ in range(3):
            await ws.send(struct.pack("<BI", CLIENT_MESSAGE_DATA, 7) + json.dumps(twist).encode())
        try:
            while True:
                frame = await asyncio.wait_for(ws.recv(), 1.0)
                if isinstance(frame, str) and json.loads(frame).get("op") == "status":
                    statuses.append(json.loads(frame))
        except TimeoutError:
            pass
        return "open", statuses
    except websockets.exceptions.ConnectionClosed:
        return "closed", statuses
    finally:
        await ws.close()


def moved_after(live: FoxgloveLive, port: int, **how: Any) -> tuple[str, float, list[dict[str, Any]]]:
    """Run :func:`attempt` against a runtime that has ``live``'s panel as a source, then 1 s of
    simulated time: the verdict, how far the simulated robot moved (m), the status messages."""
    with RobotClient.open("sim://omni4?seed=3", timeout=0.5) as client:
        runtime = Runtime(client, period=0.01, sources=[live.panel])
        p0 = truth(client).pose
        verdict, statuses = asyncio.run(attempt(port, **how))
        runtime.run(duration=1.0)
        runtime.close()
        p1 = truth(client).pose
    return verdict, math.hypot(p1.x - p0.x, p1.y - p0.y), statuses


@pytest.fixture
def open_live() -> Iterator[FoxgloveLive]:
    live = FoxgloveLive(0)
    try:
        yield live
    finally:
        live.close()


@pytest.fixture
def guarded_live() -> Iterator[FoxgloveLive]:
    live = FoxgloveLive(0, token=TOKEN)
    try:
        yield live
    finally:
        live.close()


@pytest.mark.parametrize("protocol", ["foxglove.sdk.v1", "foxglove.websocket.v1"])
def test_a_local_client_without_origin_drives(open_live: FoxgloveLive, protocol: str) -> None:
    """The control: a Foxglove app on this computer (no Origin, no token set) drives."""
    verdict, moved, statuses = moved_after(open_live, open_live.port, protocol=protocol)
    assert (verdict, statuses) == ("open", [])
    assert moved > 0.1


@pytest.mark.parametrize(
    "origin", ["http://evil.example", "null", "http://127.0.0.1:1", "https://app.foxglove.dev.evil.example"]
)
def test_a_foreign_origin_is_refused_and_the_robot_stays(open_live: FoxgloveLive, origin: str) -> None:
    verdict, moved, _ = moved_after(open_live, open_live.port, origin=origin)
    assert verdict == "refused" and moved < MOVED


def test_a_rebinding_host_is_refused_and_the_robot_stays(open_live: FoxgloveLive) -> None:
    host = f"evil.example:{open_live.port}"
    verdict, moved, _ = moved_after(open_live, open_live.port, host=host, origin=f"http://{host}")
    assert verdict == "refused" and moved < MOVED


@pytest.mark.parametrize("origin", ["https://app.foxglove.dev", "http://127.0.0.1:{port}"])
def test_foxglove_s_app_and_the_server_s_own_origin_drive(open_live: FoxgloveLive, origin: str) -> None:
    verdict, moved, _ = moved_after(open_live, open_live.port, origin=origin.format(port=open_live.port))
    assert verdict == "open" and moved > 0.1


def test_with_a_token_no_port_of_the_process_takes_a_client_without_it(guarded_live: FoxgloveLive) -> None:
    ports = listening_ports()
    assert guarded_live.port in ports
    for port in sorted(ports):
        for query in ("", "?token=wrong-token-1"):
            verdict, moved, _ = moved_after(guarded_live, port, query=query)
            assert verdict == "refused" and moved < MOVED, (port, query)
    verdict, moved, _ = moved_after(guarded_live, guarded_live.port, query=f"?token={TOKEN}")
    assert verdict == "open" and moved > 0.1


@pytest.mark.parametrize(
    ("field", "value"),
    [("x", "0.3"), ("x", True), ("x", None), ("x", [0.3]), ("y", "1e3"), ("z", False)],
)
def test_a_twist_with_numbers_that_are_not_numbers_is_refused_with_a_notice(
    open_live: FoxgloveLive, field: str, value: Any
) -> None:
    twist = json.loads(json.dumps(AHEAD))
    twist["angular" if field == "z" else "linear"][field] = value
    verdict, moved, statuses = moved_after(open_live, open_live.port, twist=twist)
    assert verdict == "open" and moved < MOVED
    assert open_live.panel.received == 0
    assert statuses and statuses[0]["level"] == 2
    assert f"{'angular' if field == 'z' else 'linear'}.{field}" in statuses[0]["message"]
    assert "number" in statuses[0]["message"]


@pytest.mark.parametrize("text", ["NaN", "Infinity", "-Infinity"])
def test_a_twist_that_is_not_finite_is_refused(open_live: FoxgloveLive, text: str) -> None:
    raw = json.dumps(AHEAD).replace('"x": 0.4', f'"x": {text}')
    verdict, moved, statuses = moved_after(open_live, open_live.port, twist=json.loads(raw))
    assert verdict == "open" and moved < MOVED and open_live.panel.received == 0
    assert statuses and "finite" in statuses[0]["message"]
