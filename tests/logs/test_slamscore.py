"""``omnibot log score``: a SLAM run that happened outside omnibot, scored from logs written by rosbags.

Two bags, both written with rosbags' own writer and type store (a tool we did not write): the
robot's (``/omnibot/truth``, ``/odom``, ``/tf`` odom -> base_link, as ``omnibot ros2 --log`` records
them) in one MCAP file, the SLAM node's (``/tf`` map -> odom at 10 Hz and ``/map``) in a rosbag2
directory. The truth drives a loop in the room; the odometry drifts (3 % long, heading creeping at
0.02 rad/s); the SLAM's correction puts its estimate exactly 1 cm to the robot's left of the truth.
Its map is the room's own geometry in the SLAM's frame (the odometry frame where it started). The
scores must come out as these known quantities: estimate APE 1 cm, the odometry's APE as computed
here from the drift, a map in the right place (scoring as the room's own map scores) and, placed
wrong, a map that does not fit.
"""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="rosbags is not installed (pip install 'omnibot[logs]')")

from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from omnibot.cli import main
from omnibot.logs.slamscore import read_slam_logs, score_slam_logs
from omnibot.mapping import OccupancyGrid, compose, inverse
from omnibot.mapping.score import score_map, world_grid
from omnibot.motion import Pose2D
from omnibot.sim import load_world
from tests.cli.conftest import assert_one_line_error

STORE = get_typestore(Stores.ROS2_JAZZY)
START = Pose2D(1.0, 1.0, 0.0)
OFFSET = Pose2D(0.0, 0.01, 0.0)
"""The SLAM's estimate, in the robot's frame, from the truth: 1 cm to its left."""
T0 = 1_700_000_000.0
DT = 0.01


def loop() -> list[Pose2D]:
    """The truth: a loop in the room at 0.3 m/s, turning at the corners (world frame)."""
    corners = [(1.0, 1.0), (3.0, 1.0), (3.0, 2.5), (1.0, 2.5), (1.0, 1.2)]
    poses: list[Pose2D] = []
    for (x0, y0), (x1, y1) in itertools.pairwise(corners):
        n = int(math.hypot(x1 - x0, y1 - y0) / (0.3 * DT))
        heading = math.atan2(y1 - y0, x1 - x0)
        poses += [Pose2D(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n, heading) for k in range(n)]
    return poses


def drifted(truth: list[Pose2D]) -> list[Pose2D]:
    """The odometry: the truth's steps 3 % long, the heading creeping 0.02 rad/s, from (0, 0, 0)."""
    odom = [Pose2D(0.0, 0.0, 0.0)]
    for a, b in itertools.pairwise(truth):
        step = compose(inverse(a), b)
        step = Pose2D(1.03 * step.x, 1.03 * step.y, step.theta + 0.02 * DT)
        odom.append(compose(odom[-1], step))
    return odom


def header(t: float, frame: str) -> Any:
    sec = int(t)
    stamp = STORE.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=round((t - sec) * 1e9))
    return STORE.types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)


def quat(yaw: float) -> Any:
    return STORE.types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def transform(t: float, parent: str, child: str, p: Pose2D) -> Any:
    types = STORE.types
    tf = types["geometry_msgs/msg/TransformStamped"](
        header=header(t, parent),
        child_frame_id=child,
        transform=types["geometry_msgs/msg/Transform"](
            translation=types["geometry_msgs/msg/Vector3"](x=p.x, y=p.y, z=0.0), rotation=quat(p.theta)
        ),
    )
    return types["tf2_msgs/msg/TFMessage"](transforms=[tf])


def odometry(t: float, p: Pose2D) -> Any:
    types = STORE.types
    pose = types["geometry_msgs/msg/Pose"](
        position=types["geometry_msgs/msg/Point"](x=p.x, y=p.y, z=0.0), orientation=quat(p.theta)
    )
    twist = types["geometry_msgs/msg/Twist"](
        linear=types["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
        angular=types["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
    )
    return types["nav_msgs/msg/Odometry"](
        header=header(t, "odom"),
        child_frame_id="base_link",
        pose=types["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
        twist=types["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)),
    )


def room_map() -> OccupancyGrid:
    """The room's own map, its walls in the middle of cells (not on their edges, where a rounding
    error of the placing would move them by a cell)."""
    return world_grid(load_world("room"), 0.05, 0.125)


def occupancy(t: float, frame_in_world: Pose2D) -> Any:
    """The room's own map, expressed in a frame placed at ``frame_in_world``."""
    types = STORE.types
    grid = room_map()
    origin = compose(inverse(frame_in_world), grid.origin)
    rows, cols = grid.shape
    info = types["nav_msgs/msg/MapMetaData"](
        map_load_time=header(t, "").stamp,
        resolution=grid.resolution,
        width=cols,
        height=rows,
        origin=types["geometry_msgs/msg/Pose"](
            position=types["geometry_msgs/msg/Point"](x=origin.x, y=origin.y, z=0.0),
            orientation=quat(origin.theta),
        ),
    )
    return types["nav_msgs/msg/OccupancyGrid"](header=header(t, "map"), info=info, data=grid.data.reshape(-1))


def write(path: Path, messages: list[tuple[str, str, float, Any]]) -> None:
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections: dict[str, Any] = {}
        for topic, msgtype, t, msg in messages:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=STORE)
            writer.write(connections[topic], round(t * 1e9), STORE.serialize_cdr(msg, msgtype))


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, float]:
    """The robot's MCAP file, the SLAM's rosbag2 directory and the odometry's APE (m) computed here."""
    base = tmp_path_factory.mktemp("slam")
    truth = loop()
    odom = drifted(truth)
    robot: list[tuple[str, str, float, Any]] = []
    slam: list[tuple[str, str, float, Any]] = []
    errors = []
    for k, (true, o) in enumerate(zip(truth, odom, strict=True)):
        t = T0 + k * DT
        robot.append(("/omnibot/truth", "nav_msgs/msg/Odometry", t, odometry(t, true)))
        robot.append(("/odom", "nav_msgs/msg/Odometry", t, odometry(t, o)))
        robot.append(("/tf", "tf2_msgs/msg/TFMessage", t, transform(t, "odom", "base_link", o)))
        placed = compose(START, o)
        errors.append(math.hypot(placed.x - true.x, placed.y - true.y))
        if k % 10 == 0:  # the SLAM's correction at 10 Hz: its estimate 1 cm left of the truth
            estimate = compose(compose(inverse(START), true), OFFSET)
            slam.append(
                (
                    "/tf",
                    "tf2_msgs/msg/TFMessage",
                    t,
                    transform(t, "map", "odom", compose(estimate, inverse(o))),
                )
            )
    slam.append(
        ("/map", "nav_msgs/msg/OccupancyGrid", T0 + 1.0, occupancy(T0 + 1.0, Pose2D(5.0, 5.0, 1.0)))
    )  # an early map, replaced
    slam.append(("/map", "nav_msgs/msg/OccupancyGrid", T0 + 5.0, occupancy(T0 + 5.0, START)))
    robot_dir = base / "robot"
    write(robot_dir, robot)
    write(base / "slam", slam)
    (mcap,) = robot_dir.glob("*.mcap")
    return mcap, base / "slam", float(np.sqrt(np.mean(np.square(errors))))


def test_the_logs_are_read_together(logs: tuple[Path, Path, float]) -> None:
    mcap, bag, _ = logs
    run = read_slam_logs([mcap, bag])
    assert len(run.truth) == len(run.odometry) == len(run.odom_to_base) > 2000
    assert len(run.map_to_odom) == math.ceil(len(run.truth) / 10)
    assert run.grid is not None and run.grid.frame == "map"
    assert run.grid.origin.theta == pytest.approx(0.0, abs=1e-9)  # the later map, not the early one


def test_the_scores_are_the_known_errors(logs: tuple[Path, Path, float], tmp_path: Path) -> None:
    mcap, bag, odometry_ape = logs
    result = score_slam_logs([mcap, bag], tmp_path, world=load_world("room"), plot=False)
    report = json.loads((tmp_path / "report.json").read_text())
    assert report == result.report
    assert report["map_frame_in_world"] == pytest.approx([START.x, START.y, START.theta], abs=1e-9)
    estimate, odom = report["trajectory"]["estimate"], report["trajectory"]["odometry"]
    assert estimate["ape_rmse_m"] == pytest.approx(0.01, abs=5e-4)  # the correction's 1 cm
    assert odom["ape_rmse_m"] == pytest.approx(odometry_ape, rel=0.01)
    assert odom["ape_rmse_m"] > 10 * estimate["ape_rmse_m"]
    own = score_map(room_map(), load_world("room"))  # the map in its place scores as the room's own
    assert report["map"]["precision"] == pytest.approx(own.precision) and own.precision > 0.8
    assert report["map"]["recall"] == pytest.approx(own.recall) and own.recall > 0.99
    for name in ("map.yaml", "map.pgm", "estimate.tum", "odometry.tum", "truth.tum"):
        assert (tmp_path / name).is_file(), name


def test_a_map_placed_wrong_does_not_fit(logs: tuple[Path, Path, float], tmp_path: Path) -> None:
    mcap, bag, _ = logs
    result = score_slam_logs(
        [mcap, bag], tmp_path, world=load_world("room"), map_pose=Pose2D(0.0, 0.0, 0.0), plot=False
    )
    assert result.report["map"]["precision"] < 0.5
    assert result.report["trajectory"]["estimate"]["ape_rmse_m"] > 1.0


def test_the_command(
    logs: tuple[Path, Path, float], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mcap, bag, _ = logs
    assert main(["log", "score", str(mcap), str(bag), "--world", "room", "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert "score: estimate: APE RMSE 1.0 cm" in out, out
    assert "the map frame at (1.000, 1.000, 0.0 deg) in the world" in out
    assert (tmp_path / "out" / "map.png").is_file()


@pytest.mark.parametrize(
    ("which", "text"),
    [("robot", "no map -> odom transform on /tf in the logs"), ("slam", "no odom -> base_link transform")],
)
def test_logs_without_the_slam_or_the_odometry_are_one_line_and_exit_2(
    logs: tuple[Path, Path, float], tmp_path: Path, capsys: pytest.CaptureFixture[str], which: str, text: str
) -> None:
    mcap, bag, _ = logs
    given = str(mcap) if which == "robot" else str(bag)
    assert main(["log", "score", given, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert text in err, err
    assert_one_line_error(err)


def test_omnibots_own_log_beside_a_slam_bag(tmp_path: Path) -> None:
    """The robot's side is a log of omnibot's recorder (the simulated omni4 driven round a curve);
    the SLAM's bag, written by rosbags from that log's own /odom and truth (read with rosbags), puts
    its estimate 1 cm left of the truth. The scores match what is computed here from the same
    messages."""
    from rosbags.highlevel import AnyReader

    from tests.logs.conftest import drive

    run = tmp_path / "run.mcap"
    drive(run, seconds=4.0)
    odom: dict[int, Pose2D] = {}
    truth: dict[int, Pose2D] = {}
    with AnyReader([run]) as reader:
        conns = [c for c in reader.connections if c.topic in ("/odom", "/omnibot/truth")]
        for conn, _, raw in reader.messages(connections=conns):
            msg: Any = reader.deserialize(raw, conn.msgtype)
            ns = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
            p, q = msg.pose.pose.position, msg.pose.pose.orientation
            (odom if conn.topic == "/odom" else truth)[ns] = Pose2D(p.x, p.y, 2 * math.atan2(q.z, q.w))
    both = sorted(set(odom) & set(truth))
    assert len(both) > 300
    start = compose(truth[both[0]], inverse(odom[both[0]]))  # the odometry frame in the world
    slam: list[tuple[str, str, float, Any]] = []
    for ns in both[::10]:
        t = ns / 1e9
        estimate = compose(compose(inverse(start), truth[ns]), OFFSET)
        m2o = compose(estimate, inverse(odom[ns]))
        slam.append(("/tf", "tf2_msgs/msg/TFMessage", t, transform(t, "map", "odom", m2o)))
    slam.append(("/map", "nav_msgs/msg/OccupancyGrid", both[-1] / 1e9, occupancy(both[-1] / 1e9, start)))
    write(tmp_path / "slam", slam)
    result = score_slam_logs([run, tmp_path / "slam"], tmp_path / "out", plot=False)
    report = result.report
    assert report["map_frame_in_world"] == pytest.approx([start.x, start.y, start.theta], abs=1e-6)
    placed = [compose(start, odom[ns]) for ns in both]
    expected = math.sqrt(
        sum((p.x - truth[ns].x) ** 2 + (p.y - truth[ns].y) ** 2 for p, ns in zip(placed, both, strict=True))
        / len(both)
    )
    assert report["trajectory"]["odometry"]["ape_rmse_m"] == pytest.approx(expected, rel=1e-3, abs=1e-6)
    assert report["trajectory"]["estimate"]["ape_rmse_m"] == pytest.approx(0.01, abs=1e-3)
    assert report["scans"] == 0 and report["corrections"] == len(both[::10])
