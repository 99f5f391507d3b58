"""``goal_pose`` without DDS: which goals are taken and which refused (one line each), the diagnostic
status, and ``omnibot ros2 --map``'s bad options (one line, exit 2, before any participant).
(tests/ros2/test_rclpy_goal_pose.py drives the robot there from a genuine rclpy.)"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

from omnibot.cli import main
from omnibot.logs import schemas
from omnibot.logs.recorder import header
from omnibot.mapping.mapfile import save_map
from omnibot.mapping.score import world_grid
from omnibot.motion import Pose2D
from omnibot.robot.description import load_robot
from omnibot.ros2.goal import GOAL_TYPE, GoalPoseSource
from omnibot.sim.world import load_world
from tests.cli.conftest import assert_one_line_error
from tests.ros2.test_path import Node, pose_message


def goal(x: float, y: float, yaw: float | None, frame: str = "map") -> Any:
    """A geometry_msgs/PoseStamped in ``frame`` (yaw None: an all-zero quaternion)."""
    return schemas.new(GOAL_TYPE, header=header(0, frame), pose=pose_message(x, y, yaw))


@pytest.fixture
def source() -> tuple[GoalPoseSource, list[tuple[str, str]]]:
    said: list[tuple[str, str]] = []
    made = GoalPoseSource(
        Node(),  # type: ignore[arg-type]
        load_robot("omni4"),
        world_grid(load_world("room")),
        0.02,
        lambda: Pose2D(1.0, 1.0, 0.0),
        map_frame="r1/map",
        notify=lambda level, text: said.append((level, text)),
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
    assert goals.receive(message) is False
    assert len(said) == 1 and said[0][0] == "warn" and said[0][1].startswith(text), said
    assert not goals.goto.active
    status = goals.status()
    assert status.level == 1 and status.name == "omnibot: goal"
    assert {kv.key: kv.value for kv in status.values}["refused"] == said[0][1]


def test_a_goal_is_taken_and_a_new_one_replaces_it(
    source: tuple[GoalPoseSource, list[tuple[str, str]]],
) -> None:
    goals, said = source
    assert goals.receive(goal(2.5, 1.8, math.pi / 2, "/r1/map"))
    assert goals.receive(goal(2.0, 2.0, 0.0, "r1/map"))
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


@pytest.fixture(scope="module")
def room_map(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("map") / "room.yaml"
    save_map(world_grid(load_world("room")), path)
    return path


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
