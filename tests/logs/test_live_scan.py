"""``--foxglove`` live: a runtime with the simulator's scanner serves ``/scan`` (sensor_msgs/LaserScan)
on the live server, as the recorder writes it; a plain ``websockets`` client speaking
``foxglove.sdk.v1`` subscribes and decodes the simulator's scans."""

from __future__ import annotations

import asyncio
import json
import struct
from typing import Any

import numpy as np
import pytest
import websockets
from websockets.typing import Subprotocol

from omnibot.client import robot_session
from omnibot.lidar import open_scanner
from omnibot.logs import schemas, topics
from omnibot.logs.live import FoxgloveLive
from omnibot.logs.recorder import Recorder
from omnibot.logs.sink import RuntimeRecorder
from omnibot.protocol import codes
from omnibot.runtime import Runtime
from omnibot.scan import Scan
from tests.logs.test_live import MESSAGE_DATA


def test_a_websocket_client_gets_the_live_scans() -> None:
    live = FoxgloveLive(0)
    rec = Recorder(None, mirrors=[live])
    seen: list[Scan] = []
    with robot_session("sim://omni4?seed=4&world=room", "omni4", timeout=0.5) as session:
        client, robot = session.client, session.robot
        rec.attach(client, robot)
        runtime = Runtime(client, period=0.01)
        scans = open_scanner(None, client.link, robot)
        runtime.scanner = scans
        runtime.add_sink(RuntimeRecorder(rec, runtime))  # what --foxglove's attach_runtime adds
        runtime.add_sink(lambda cycle: seen.extend(cycle.scans))

        def cycles(n: int) -> None:
            for _ in range(n):
                runtime.step()
                runtime.pacer.wait()

        async def watch() -> tuple[dict[str, Any], list[bytes]]:
            url = f"ws://127.0.0.1:{live.port}"
            async with websockets.connect(url, subprotocols=[Subprotocol("foxglove.sdk.v1")]) as ws:
                info = json.loads(await asyncio.wait_for(ws.recv(), 5))
                assert info["op"] == "serverInfo"
                channels: dict[str, dict[str, Any]] = {}
                while topics.SCAN not in channels:
                    cycles(20)  # the channel is advertised once it carries a message
                    try:
                        while True:
                            msg = await asyncio.wait_for(ws.recv(), 0.2)
                            if isinstance(msg, str) and json.loads(msg)["op"] == "advertise":
                                channels |= {c["topic"]: c for c in json.loads(msg)["channels"]}
                    except TimeoutError:
                        pass
                sub = {"id": 7, "channelId": channels[topics.SCAN]["id"]}
                await ws.send(json.dumps({"op": "subscribe", "subscriptions": [sub]}))
                await asyncio.sleep(0.3)
                cycles(100)  # 1 s of simulated time: 10 revolutions
                got: list[bytes] = []
                try:
                    while True:
                        frame = await asyncio.wait_for(ws.recv(), 1.0)
                        if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
                            sid, _ = struct.unpack_from("<IQ", frame, 1)
                            if sid == 7:
                                got.append(frame[13:])
                except TimeoutError:
                    pass
                return channels[topics.SCAN], got

        try:
            runtime.start()
            client.telemetry(0.01, codes.TEL_MASK)
            channel, got = asyncio.run(watch())
        finally:
            runtime.close()
            scans.close()
            rec.close()  # stops the server
    assert channel["schemaName"] == "sensor_msgs/msg/LaserScan" and channel["encoding"] == "cdr"
    decoded = [schemas.deserialize(d, "sensor_msgs/msg/LaserScan") for d in got]
    assert len(decoded) >= 8
    for msg in decoded:
        assert msg.header.frame_id == "laser"
        match = [s for s in seen if np.array_equal(s.ranges.astype(np.float32), msg.ranges)]
        assert len(match) == 1  # one of the simulator's scans, every range as it was (inf included)
        assert msg.angle_increment == pytest.approx(match[0].angle_increment, rel=1e-6)
