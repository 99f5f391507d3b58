"""``goal_pose`` without DDS: which goals are taken and which refused (one line each), the diagnostic
status, ``initialpose`` re-placing the localiser (or refused, one line), and ``omnibot ros2 --map``'s
bad options (one line, exit 2, before any participant).
(tests/ros2/test_rclpy_goal_pose.py drives the robot there from a genuine rclpy.)"""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

import omnibot.ros2
from omnibot.cli import main
from omnibot.logs import header, schemas
from omnibot.mapping import save_map
from omnibot.mapping.score import world_grid
from omnibot.motion import Estimate, Pose2D
from omnibot.robot import load_robot
from omnibot.ros2.goal import GOAL_TYPE, GoalPoseSource, PlaceableSink, Refusal, Spread, spread_of
from omnibot.ros2.odometry import OdometryReset
from omnibot.runtime import Cycle
from omnibot.sim import load_world
from tests.cli.conftest import assert_one_line_error
from tests.ros2.test_odometry import Node as ResetNode
from tests.ros2.test_odometry import Runtime, pose
from tests.ros2.test_path import Node, pose_message


def goal(x: float, y: float, yaw: float | None, frame: str = "map") -> Any:
    """A geometry_msgs/PoseStamped in ``frame`` (yaw None: an all-zero quaternion)."""
    return schemas.new(GOAL_TYPE, header=header(0, frame), pose=pose_message(x, y, yaw))


Placed = list[tuple[Pose2D, Spread]]


@pytest.fixture
def placed() -> Placed:
    """Where the localiser was re-placed."""
    return []


@pytest.fixture
def source(placed: Placed) -> tuple[GoalPoseSource, list[tuple[str, str]]]:
    said: list[tuple[str, str]] = []
    made = GoalPoseSource(
        Node(),  # type: ignore[arg-type]
        load_robot("omni4"),
        world_grid(load_world("room")),
        0.02,
        lambda: Pose2D(1.0, 1.0, 0.0),
        map_frame="r1/map",
        notify=lambda level, text: said.append((level, text)),
        place=lambda at, spread: placed.append((at, spread)),
    )
    return made, said


@pytest.mark.parametrize(
    ("message", "text"),
    [
        (
            goal(2.0, 2.0, 0.0, "r1/odom"),
            "goal_pose in frame 'r1/odom' refused: goals are taken in the map frame 'r1/map'",
        ),
        (goal(2.0, 2.0, 0.0, ""), "goal_pose in frame '' refused"),
        (goal(3.6, 1.2, 0.0, "r1/map"), "goal_pose refused: goal (3.60, 1.20) is inside a wall or obstacle"),
        (goal(30.0, 1.0, 0.0, "r1/map"), "goal_pose refused: goal (30.00, 1.00) is off the map"),
        (goal(2.0, 2.0, None, "r1/map"), "goal_pose refused: not a finite position and rotation"),
        (goal(math.nan, 2.0, 0.0, "r1/map"), "goal_pose refused: not a finite position and rotation"),
    ],
)
def test_bad_goals_are_refused_in_one_warning(
    source: tuple[GoalPoseSource, list[tuple[str, str]]], message: Any, text: str
) -> None:
    goals, said = source
    refusal = goals.receive(message)
    assert isinstance(refusal, Refusal) and refusal.text == said[0][1]
    assert len(said) == 1 and said[0][0] == "warn" and said[0][1].startswith(text), said
    assert not goals.goto.active
    status = goals.status()
    assert status.level == 1 and status.name == "omnibot: goal"
    assert {kv.key: kv.value for kv in status.values}["refused"] == said[0][1]


def test_a_goal_is_taken_and_a_new_one_replaces_it(
    source: tuple[GoalPoseSource, list[tuple[str, str]]],
) -> None:
    goals, said = source
    assert not isinstance(goals.receive(goal(2.5, 1.8, math.pi / 2, "/r1/map")), Refusal)
    assert not isinstance(goals.receive(goal(2.0, 2.0, 0.0, "r1/map")), Refusal)
    assert said == [
        ("info", "goal_pose received: going to (2.50, 1.80, 90 deg)"),
        (
            "warn",
            "goal_pose: did not arrive: pre-empted by a new goal (170.0 cm, 90.0 degrees from the goal)",
        ),
        ("info", "goal_pose replaced: going to (2.00, 2.00, 0 deg)"),
    ]
    values = {kv.key: kv.value for kv in goals.status().values}
    assert (
        values["state"] == "waiting" and values["goal"] == "2.000,2.000,0.0" and values["refused"] == "none"
    )
    assert [r.outcome for r in goals.goto.results] == ["cancelled"]


def initial(x: float, y: float, yaw: float, frame: str = "r1/map", covariance: float = 0.0025) -> Any:
    """A PoseWithCovarianceStamped with x, y variance ``covariance`` and yaw variance 0.01."""
    msg = pose(x, y, yaw, frame)
    row = [0.0] * 36
    row[0] = row[7] = covariance
    row[35] = 0.01
    msg.pose.covariance = row
    return msg


@pytest.fixture
def reset(source: tuple[GoalPoseSource, list[tuple[str, str]]]) -> OdometryReset:
    """The bridge's initialpose reader, handing its messages to the goal source as ``--map`` does."""
    goals, said = source
    made = OdometryReset(
        ResetNode(),  # type: ignore[arg-type]
        Runtime(),
        odom_frame="r1/odom",
        notify=lambda level, text: said.append((level, text)),
    )
    made.placer = goals.initial_pose
    return made


@pytest.mark.parametrize(
    ("message", "text"),
    [
        (
            initial(1.0, 1.0, 0.0, "r1/odom"),
            "initialpose in frame 'r1/odom' refused: the localiser is placed in the map frame 'r1/map'",
        ),
        (initial(1.0, 1.0, 0.0, ""), "initialpose in frame '' refused"),
        (initial(3.6, 1.2, 0.0), "initialpose refused: start (3.60, 1.20) is inside a wall or obstacle"),
        (initial(30.0, 1.0, 0.0), "initialpose refused: start (30.00, 1.00) is off the map"),
        (initial(math.inf, 1.0, 0.0), "initialpose refused: not a finite position, rotation and covariance"),
        (initial(1.0, 1.0, 0.0, covariance=math.nan), "initialpose refused: not a finite position"),
        (initial(1.0, 1.0, 0.0, covariance=-1.0), "initialpose refused: not a finite position"),
    ],
)
def test_bad_initial_poses_are_refused_in_one_warning(
    source: tuple[GoalPoseSource, list[tuple[str, str]]],
    reset: OdometryReset,
    placed: Placed,
    message: Any,
    text: str,
) -> None:
    goals, said = source
    assert not isinstance(goals.receive(goal(2.5, 1.8, 0.0, "r1/map")), Refusal)
    del said[:]
    assert reset.initial_pose(message) is False
    assert len(said) == 1 and said[0][0] == "warn" and said[0][1].startswith(text), said
    assert placed == [] and goals.goto.active  # nothing changed: the goal goes on
    assert reset.status().level == 1 and reset.resets == 0


def test_an_initial_pose_in_the_map_re_places_the_localiser_and_ends_the_goal(
    source: tuple[GoalPoseSource, list[tuple[str, str]]], reset: OdometryReset, placed: Placed
) -> None:
    goals, said = source
    assert not isinstance(goals.receive(goal(2.5, 1.8, 0.0, "r1/map")), Refusal)
    assert reset.initial_pose(initial(1.2, 0.8, math.pi / 2, "/r1/map", covariance=0.04))
    ((at, spread),) = placed
    assert (at.x, at.y, at.theta) == pytest.approx((1.2, 0.8, math.pi / 2))
    assert spread == pytest.approx((0.2, 0.1))  # the covariance's standard deviations
    assert said[-2:] == [
        (
            "warn",
            "goal_pose: did not arrive: the robot was re-placed by initialpose (170.0 cm, 0.0 degrees "
            "from the goal)",
        ),
        ("info", "localiser re-placed by initialpose at (1.20, 0.80, 90 deg), spread 20 cm, 6 deg"),
    ]
    assert not goals.goto.active and reset.status().level == 0


def test_spread_of_a_covariance() -> None:
    row = [0.0] * 36
    assert spread_of(row) == (0.01, 0.01)  # none given: the least spread
    row[0], row[7], row[35] = 0.01, 0.09, 0.25
    assert spread_of(row) == pytest.approx((0.3, 0.5))  # the larger of x's and y's
    row[35] = math.inf
    assert spread_of(row) is None


class Localiser:
    """Records resets and updates; map -> odom is where it was last reset."""

    def __init__(self) -> None:
        self.calls: list[str] = []
        self.map_to_odom = Pose2D(0.0, 0.0, 0.0)

    def reset(self, at: Pose2D, spread: Spread) -> None:
        self.calls.append(f"reset {at.x:g} {spread[0]:g}")
        self.map_to_odom = at

    def update(self, odom: Pose2D, scan: Any, points: Any = None) -> None:
        self.calls.append("update")


def test_a_placeable_sink_is_placed_at_once_and_reset_before_its_next_scan() -> None:
    localiser = Localiser()
    sink = PlaceableSink(None, localiser)  # type: ignore[arg-type]
    sink(Cycle(0, 0.0, 0.0, Estimate(0.0, 0.5, 0.0, math.pi / 2)))  # odometry: (0.5, 0) facing +y
    sink.place(Pose2D(1.0, 2.0, 0.0), (0.1, 0.1))
    here = sink.pose_now()  # at once, before the localiser's next scan
    assert here is not None and (here.x, here.y, here.theta) == pytest.approx((1.0, 2.0, 0.0))
    assert localiser.calls == []  # the localiser is its worker's: reset before its next scan
    scan = SimpleNamespace(stamp=0.0)
    sink._update(scan, Pose2D(0.5, 0.0, math.pi / 2))  # type: ignore[arg-type]
    sink._update(scan, Pose2D(0.5, 0.0, math.pi / 2))  # type: ignore[arg-type]
    assert localiser.calls == ["reset 1 0.1", "update", "update"]
    assert sink.map_to_odom_now() == Pose2D(1.0, 2.0, 0.0)


@pytest.fixture(scope="module")
def room_map(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("map") / "room.yaml"
    save_map(world_grid(load_world("room")), path)
    return path


def test_an_initial_pose_in_a_wall_is_told_as_the_option_given(
    room_map: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The simulated robot put at ``--initial-pose`` where it cannot stand: the line names the option,
    not the sim:// URL the bridge made of it (the link refuses it before any ROS 2 node is made: this
    test runs outside a private network namespace, so making one fails it instead)."""

    def no_node(*args: Any) -> None:
        raise AssertionError("the bridge made its node: the link accepted a pose in a wall")

    monkeypatch.setattr(omnibot.ros2, "attach", no_node)  # where the bridge makes its node
    assert main(["ros2", "--map", str(room_map), "--initial-pose", "0,0,0"]) == 2
    assert capsys.readouterr().err == (
        "omnibot: error: --initial-pose: start pose (0, 0, 0 deg) overlaps walls[0] of world 'room': the "
        "simulated robot is put at --initial-pose; give a pose inside the world\n"
    )


@pytest.mark.parametrize(
    ("args", "text"),
    [
        (["--initial-pose", "1,1,0"], "--initial-pose places the robot in a --map: give the map"),
        (["--map", "MAP", "--initial-pose", "1,1"], "--initial-pose: expected X,Y,THETA"),
        (["--map", "MAP", "--port", "/dev/ttyUSB0"], "where does the robot stand in the map?"),
        (["--map", "nowhere.yaml"], "nowhere.yaml"),
        (
            [
                "--map",
                "MAP",
                "--port",
                "sim://omni4",
                "--namespace",
                "a",
                "--port",
                "sim://omni3",
                "--namespace",
                "b",
            ],
            "--map localises one robot",
        ),
    ],
)
def test_bad_map_options_are_one_line_and_exit_2(
    room_map: Path, capsys: pytest.CaptureFixture[str], args: list[str], text: str
) -> None:
    argv = ["ros2", *[str(room_map) if a == "MAP" else a for a in args]]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert text in err, err
    assert_one_line_error(err)
