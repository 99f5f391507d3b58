"""Foxglove's Teleop panel as a runtime source: a plain ``websockets`` client speaking
``foxglove.sdk.v1`` advertises ``cmd_vel`` and publishes a twist, as the panel does; it drives the
simulated robot (simulator truth) through the runtime's arbitration and stops when the publishing stops."""

from __future__ import annotations

import json
import struct
import threading

import pytest
from websockets.sync.client import connect
from websockets.typing import Subprotocol

from omnibot.client import RobotClient
from omnibot.logs import schemas
from omnibot.logs.live import PANEL_HOLD, FoxgloveLive, PanelSource, decode_twist
from omnibot.motion import Twist
from omnibot.runtime import Cycle, Runtime, ScriptSource
from tests.teleop.fakes import truth

CLIENT_MESSAGE_DATA = 0x01


def cycle(now: float) -> Cycle:
    return Cycle(0, now, now, None)


def test_the_panel_holds_its_twist_then_stops_once_then_is_silent() -> None:
    panel = PanelSource()
    assert panel.propose(cycle(0.0)) is None
    panel.put(Twist(0.2, 0.0, 0.1))
    for now in (1.0, 1.2, 1.0 + PANEL_HOLD):
        p = panel.propose(cycle(now))
        assert p is not None and p.twist == Twist(0.2, 0.0, 0.1)
    p = panel.propose(cycle(1.01 + PANEL_HOLD))
    assert p is not None and p.twist == Twist()
    assert panel.propose(cycle(1.1 + PANEL_HOLD)) is None
    panel.put(Twist(0.0, 0.1, 0.0))
    p = panel.propose(cycle(5.0))
    assert p is not None and p.twist == Twist(0.0, 0.1, 0.0)


def test_twists_in_cdr_and_json() -> None:
    msg = schemas.new(
        "geometry_msgs/msg/Twist",
        linear=schemas.new("geometry_msgs/msg/Vector3", x=0.1, y=-0.2, z=0.0),
        angular=schemas.new("geometry_msgs/msg/Vector3", x=0.0, y=0.0, z=0.5),
    )
    cdr = schemas.serialize(msg, "geometry_msgs/msg/Twist")
    assert decode_twist("cdr", cdr) == Twist(0.1, -0.2, 0.5)
    text = json.dumps({"linear": {"x": 0.1, "y": -0.2, "z": 0}, "angular": {"x": 0, "y": 0, "z": 0.5}})
    assert decode_twist("json", text.encode()) == Twist(0.1, -0.2, 0.5)
    with pytest.raises(ValueError, match="encoding 'ros1'"):
        decode_twist("ros1", b"")


def test_a_published_twist_drives_the_simulated_robot_and_stops_when_it_stops() -> None:
    live = FoxgloveLive(0)
    try:
        with RobotClient.open("sim://omni4?seed=3", timeout=0.5) as client:
            # a source at the follower's priority: the panel takes over from it and hands back
            below = ScriptSource(lambda t: Twist(0.0, 0.0, 0.0), name="below", priority=10)
            runtime = Runtime(client, period=0.01, sources=[below, live.panel])
            got = threading.Event()
            with connect(f"ws://127.0.0.1:{live.port}", subprotocols=[Subprotocol("foxglove.sdk.v1")]) as ws:
                info = json.loads(ws.recv(timeout=5))
                assert info["op"] == "serverInfo" and "clientPublish" in info["capabilities"]
                assert "json" in info["supportedEncodings"]
                channel = {
                    "id": 7,
                    "topic": "/cmd_vel",
                    "encoding": "json",
                    "schemaName": "geometry_msgs/Twist",
                }
                ws.send(json.dumps({"op": "advertise", "channels": [channel]}))
                twist = {"linear": {"x": 0.25, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
                ws.send(struct.pack("<BI", CLIENT_MESSAGE_DATA, 7) + json.dumps(twist).encode())
                for _ in range(500):  # the server hands it over in its own thread
                    if live.panel.received:
                        got.set()
                        break
                    got.wait(0.01)
            assert got.is_set()
            x0 = truth(client).pose.x
            seen: list[Cycle] = []
            speeds: list[tuple[str, float]] = []  # who is in control, the simulated robot's speed
            runtime.add_sink(seen.append)
            runtime.add_sink(lambda c: speeds.append((c.decision.source, truth(client).twist.vx)))
            runtime.run(duration=2.0)  # lockstep: 2 s of simulated time, the panel silent after its first
            runtime.close()
            sim = truth(client)
            drove = [c for c in seen if c.decision.source == "foxglove"]
            assert drove and drove[0].sent == Twist(0.25, 0.0, 0.0)
            assert drove[0].decision.reason == "foxglove (priority 30) over below"
            # held for PANEL_HOLD s of the cycle clock, one stop; silent but in control for its
            # timeout (twist_mux), then the source below drives again
            sent = [c.sent for c in drove if c.sent is not None]
            assert len(sent) == pytest.approx(PANEL_HOLD / 0.01 + 2, abs=2)
            assert sent[-1] == Twist() and set(sent[:-1]) == {Twist(0.25, 0.0, 0.0)}
            assert len(drove) == pytest.approx((PANEL_HOLD + live.panel.timeout) / 0.01 + 1, abs=2)
            assert seen[-1].decision.source == "below"
            assert sim.pose.x - x0 > 0.08  # it drove ahead on the panel's twist
            panel = [v for who, v in speeds if who == "foxglove"]
            assert max(panel) > 0.2
            assert abs(panel[-1]) < 1e-3  # stopped by the panel's own stop, before the source below drives
    finally:
        live.close()


@pytest.mark.parametrize(
    ("text", "error"),
    [
        ('{"linear": {"x": "0.3"}}', r"linear\.x: expected a number, got \"0\.3\""),
        ('{"linear": {"x": 0.1, "y": true}}', r"linear\.y: expected a number, got true"),
        ('{"angular": {"z": null}}', r"angular\.z: expected a number, got null"),
        ('{"angular": {"z": NaN}}', r"angular\.z: expected a finite number, got nan"),
        ('{"linear": {"x": 1' + "0" * 400 + "}}", r"linear\.x: expected a finite number, got 1000"),
        ('{"linear": [0.3, 0, 0]}', r"linear: expected an object"),
        ("[0.3]", r"expected a JSON object"),
    ],
)
def test_a_twist_s_numbers_must_be_numbers(text: str, error: str) -> None:
    with pytest.raises(ValueError, match=error):
        decode_twist("json", text.encode())


def test_a_cdr_twist_that_is_not_finite_is_refused() -> None:
    vector = "geometry_msgs/msg/Vector3"
    msg = schemas.new(
        "geometry_msgs/msg/Twist",
        linear=schemas.new(vector, x=float("inf"), y=0.0, z=0.0),
        angular=schemas.new(vector, x=0.0, y=0.0, z=0.0),
    )
    with pytest.raises(ValueError, match=r"linear\.x: expected a finite number, got inf"):
        decode_twist("cdr", schemas.serialize(msg, "geometry_msgs/msg/Twist"))
