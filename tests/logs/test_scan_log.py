"""Scans in MCAP logs: a runtime with the simulator's scanner records each revolution on ``/scan``
(sensor_msgs/LaserScan), read back with rosbags and with Foxglove's own libraries, field for field
against the simulator's Scan; ``omnibot map --log`` records its scans, and at its end ``/map``
(nav_msgs/OccupancyGrid, the map it wrote) and ``/tf`` map -> odom."""

from __future__ import annotations

import contextlib
import io
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from omnibot.cli import main
from omnibot.client import robot_session
from omnibot.control import Path as RobotPath
from omnibot.control import resample, write_path
from omnibot.lidar import open_scanner
from omnibot.logs import topics
from omnibot.logs.recording import open_recording
from omnibot.mapping import load_map
from omnibot.protocol import codes
from omnibot.runtime import Runtime
from omnibot.scan import Scan
from tests.logs.test_foxglove_reader import read_with_foxglove


def read_topics(path: Path, wanted: set[str]) -> dict[str, list[tuple[int, Any]]]:
    """topic -> [(log time ns, message)] through rosbags' AnyReader."""
    out: dict[str, list[tuple[int, Any]]] = {}
    with AnyReader([path]) as reader:
        conns = [c for c in reader.connections if c.topic in wanted]
        for connection, ns, raw in reader.messages(connections=conns):
            out.setdefault(connection.topic, []).append((ns, reader.deserialize(raw, connection.msgtype)))
    return out


@pytest.fixture(scope="module")
def scanned(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[Scan]]:
    """1.5 s of simulated time on sim://omni4 with its scanner the runtime's, under ``--log``."""
    path = tmp_path_factory.mktemp("scanlog") / "scan.mcap"
    seen: list[Scan] = []
    with (
        open_recording(path) as rec,
        robot_session("sim://omni4?seed=4&world=room", "omni4", timeout=0.5, recording=rec) as session,
    ):
        runtime = Runtime(session.client, period=0.01, recording=rec)
        scans = open_scanner(None, session.client.link, session.robot)
        runtime.scanner = scans
        runtime.add_sink(lambda cycle: seen.extend(cycle.scans))
        try:
            runtime.start()
            session.client.telemetry(0.01, codes.TEL_MASK)
            runtime.run(duration=1.5)
        finally:
            runtime.close()
            scans.close()
    return path, seen


def test_rosbags_reads_every_scan_as_the_simulator_made_it(scanned: tuple[Path, list[Scan]]) -> None:
    path, seen = scanned
    assert len(seen) >= 12  # omni4's scanner turns at 10 Hz
    got = read_topics(path, {topics.SCAN})[topics.SCAN]
    assert len(got) == len(seen)
    first_ns = got[0][0]
    for (ns, msg), scan in zip(got, seen, strict=True):
        assert msg.header.frame_id == "laser"
        assert msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec == ns
        assert (ns - first_ns) / 1e9 == pytest.approx(scan.stamp - seen[0].stamp, abs=1e-6)
        assert msg.angle_min == pytest.approx(scan.angle_min)
        assert msg.angle_increment == pytest.approx(scan.angle_increment, rel=1e-6)
        assert msg.angle_increment < 0  # omni4's RPLIDAR turns clockwise: a legal negative increment
        assert msg.angle_max == pytest.approx(scan.angles[-1], rel=1e-6)
        assert (msg.range_min, msg.range_max) == pytest.approx((scan.range_min, scan.range_max))
        assert msg.time_increment == pytest.approx(scan.time_increment, rel=1e-6)
        assert msg.ranges.dtype == np.float32 and len(msg.ranges) == len(scan)
        np.testing.assert_array_equal(msg.ranges, scan.ranges.astype(np.float32))  # inf where no return
    assert any(np.isinf(msg.ranges).any() for _, msg in got)


def test_foxglove_reads_the_scans(scanned: tuple[Path, list[Scan]]) -> None:
    path, seen = scanned
    messages, end = read_with_foxglove(path)
    assert end["done"] is True
    scans = [m for m in messages if m["topic"] == topics.SCAN]
    assert len(scans) == len(seen)
    assert {m["type"] for m in scans} == {"sensor_msgs/msg/LaserScan"}
    for m, scan in zip(scans, seen, strict=True):
        msg = m["message"]
        assert msg["header"]["frame_id"] == "laser"
        assert msg["angle_increment"] == pytest.approx(scan.angle_increment, rel=1e-6)
        ranges = [math.inf if r == "Infinity" else r for r in msg["ranges"]]
        np.testing.assert_array_equal(np.array(ranges, dtype=np.float32), scan.ranges.astype(np.float32))


def test_omnibot_map_logs_scans_the_map_and_map_to_odom(tmp_path: Path) -> None:
    pts = np.array([(1.0, 1.0), (1.8, 1.0), (1.8, 1.5)])
    path = tmp_path / "p.csv"
    write_path(resample(RobotPath.from_points(pts, theta=0.0), 0.01), path)
    out, log = tmp_path / "out", tmp_path / "map.mcap"
    argv = [
        "map",
        "--path",
        str(path),
        "--world",
        "room",
        "--seed",
        "3",
        "--out",
        str(out),
        "--log",
        str(log),
    ]
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(argv) == 0, buf.getvalue()
    said = next(line for line in buf.getvalue().splitlines() if " scans, " in line)
    got = read_topics(log, {topics.SCAN, topics.MAP, topics.TF})
    assert f"map: {len(got[topics.SCAN])} scans," in said  # every scan the SLAM got is in the log
    ((map_ns, grid),) = got[topics.MAP]
    saved = load_map(out / "map.yaml")
    assert grid.header.frame_id == "map"
    assert (grid.info.width, grid.info.height) == (saved.shape[1], saved.shape[0])
    assert grid.info.resolution == pytest.approx(saved.resolution)
    assert (grid.info.origin.position.x, grid.info.origin.position.y) == pytest.approx(
        (saved.origin.x, saved.origin.y), abs=1e-6
    )
    data = np.asarray(grid.data, dtype=np.int16).reshape(saved.shape)
    # the PGM keeps free, occupied and unknown (map_server's trinary): the grid's cells agree with it
    assert ((data >= 65) == (saved.data >= 65)).all()
    assert (saved.data[data < 0] < 0).all()  # unknown stays unknown (uncertain cells become unknown too)
    map_tf = [
        (ns, t)
        for ns, m in got[topics.TF]
        for t in m.transforms
        if (t.header.frame_id, t.child_frame_id) == ("map", "odom")
    ]
    assert len(map_tf) == 1 and map_tf[0][0] == map_ns
    q = map_tf[0][1].transform.rotation
    assert math.hypot(q.z, q.w) == pytest.approx(1.0)
