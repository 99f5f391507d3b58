"""``omnibot goto`` on the simulator: localised in a saved map, it arrives (by the simulator's truth);
a bad map or goal is one line and exit 2 before the robot moves."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from omnibot.cli import main
from omnibot.mapping import save_map
from omnibot.mapping.score import world_grid
from omnibot.sim import load_world
from tests.cli.conftest import assert_one_line_error


@pytest.fixture(scope="module")
def room_map(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("map") / "room.yaml"
    save_map(world_grid(load_world("room"), 0.05, 0.3), path)
    return path


def test_it_arrives_localised_in_the_map(room_map: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["goto", "3.0,2.8,90", "--map", str(room_map), "--world", "room", "--seed", "2"]) == 0
    out = capsys.readouterr().out
    assert "localising in the map with the scanner" in out and "goto: arrived at (3.00, 2.80)" in out
    truth = re.search(r"the simulator's truth: ([\d.]+) cm, ([\d.]+) degrees", out)
    assert truth is not None, out
    assert float(truth.group(1)) <= 5.0 and float(truth.group(2)) <= 5.0


def test_from_an_initial_pose_given_by_hand(room_map: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["goto", "1.2,1.0", "--map", str(room_map), "--world", "room", "--initial-pose", "2.5,2.0,180"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "from (2.50, 2.00, 180 deg) to (1.20, 1.00, 180 deg)" in out  # no THETA: the start's heading


@pytest.mark.parametrize(
    ("argv", "text"),
    [
        (["goto", "3.6,1.2"], "is inside a wall or obstacle"),  # the cabinet
        (["goto", "30,1"], "is off the map"),
        (["goto", "3,x"], "goal: expected X,Y[,THETA]"),
        (["goto", "3,1", "--initial-pose", "1,1"], "--initial-pose: expected X,Y,THETA"),
        (["goto", "3,1", "--tolerance", "0"], "--tolerance"),
        (["goto", "3,1", "--scanner", "/dev/ttyUSB1"], "--scanner goes with --port"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    room_map: Path, capsys: pytest.CaptureFixture[str], argv: list[str], text: str
) -> None:
    assert main([*argv, "--map", str(room_map), "--world", "room"]) == 2
    err = capsys.readouterr().err
    assert text in err, err
    assert_one_line_error(err)


def test_a_real_robot_is_placed_by_hand(room_map: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["goto", "3,1", "--map", str(room_map), "--port", "/dev/ttyUSB0"]) == 2
    err = capsys.readouterr().err
    assert "where does the robot stand in the map? give --initial-pose X,Y,THETA" in err, err
    assert_one_line_error(err)


def test_a_map_that_does_not_load_is_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("image: missing.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    assert main(["goto", "1,1", "--map", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.yaml" in err
    assert_one_line_error(err)


def test_an_initial_pose_in_a_wall_is_told_as_the_option_given(
    room_map: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--initial-pose`` puts the simulated robot there: where it cannot stand, the line names the
    option, not a sim:// URL the user never wrote."""
    assert main(["goto", "3,2.8", "--map", str(room_map), "--initial-pose", "0,0,0"]) == 2
    assert capsys.readouterr().err == (
        "omnibot: error: --initial-pose: start pose (0, 0, 0 deg) overlaps walls[0] of world 'room': the "
        "simulated robot is put at --initial-pose; give a pose inside the world\n"
    )
