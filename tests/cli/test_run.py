"""``omnibot run``: the follower alone in lockstep, its failures, and the dashboard composed with it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from omnibot.apps import run as command
from omnibot.cli import main
from omnibot.control import standard_path, write_path
from tests.cli.conftest import Harness, assert_one_line_error


@pytest.fixture
def circle(tmp_path: Path) -> Path:
    target = tmp_path / "circle.csv"
    write_path(standard_path("circle", size=0.5), target)
    return target


def test_follow_alone_runs_in_lockstep_and_leaves_the_controller_as_found(
    circle: Path, harness: Harness, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["run", "--follow", str(circle), "--port", "spy+faults+sim://omni4?world=empty"]) == 0
    out = capsys.readouterr().out
    assert "run: in control: follower (priority 10)" in out
    # the outcome and accuracy as `omnibot follow` gives them, from the simulator's truth
    assert "run: follow: RMS " in out and "[simulator ground truth]" in out
    assert "run: follow completed (within 15.0 cm of the path's end, never more than 30.0 cm off it)" in out
    assert "stalled" not in out
    harness.assert_left_as_found()


def test_a_follow_pinned_against_the_cabinet_is_stopped_and_status_1(
    tmp_path: Path, harness: Harness, capsys: pytest.CaptureFixture[str]
) -> None:
    # the room's start (1, 1) east to (4.5, 1): the cabinet (3.6, 1.2) stops the robot 1.4 m short,
    # its wheels spin and the estimate believes them (it used to say "follow completed", status 0)
    into = tmp_path / "into.csv"
    into.write_text("t,x,y,theta\n0,1.0,1.0,0\n5,2.5,1.0,0\n10,4.5,1.0,0\n", encoding="utf-8")
    assert main(["run", "--follow", str(into), "--port", "sim://omni4?seed=1&world=room"]) == 1
    out = capsys.readouterr().out
    assert "run: stalled: the wheels say " in out  # every front end is told at once
    verdict = next(line for line in out.splitlines() if line.startswith("run: follow NOT COMPLETED: "))
    assert "stalled: the wheels say " in verdict and "final error 13" in verdict and "> 15.0 cm" in verdict
    assert "run: follow completed" not in out
    harness.assert_left_as_found()


def test_a_follow_that_does_not_complete_is_status_1(
    circle: Path, harness: Harness, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    real = command.compose

    def latching(runtime: Any, robot: Any, args: Any, config: Any, path: Any, *rest: Any) -> command.Parts:
        # the front sonar latches its stop on the room's wall as soon as the robot moves towards it
        runtime.client.sonar(1, period=0.06, stop=5.0)
        return real(runtime, robot, args, config, path, *rest)

    monkeypatch.setattr(command, "compose", latching)
    assert main(["run", "--follow", str(circle), "--port", "sim://omni4?world=room", "--duration", "20"]) == 1
    out = capsys.readouterr().out
    assert "emergency stop latched by the controller (sonar)" in out
    assert "run: follow NOT COMPLETED: emergency stop latched on the controller" in out
    harness.assert_left_as_found()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["run"], "nothing to run: give --teleop, --dashboard, --follow and/or --ros2"),
        (["run", "--follow", "nope.csv"], "--follow: cannot read nope.csv"),
        (["run", "--dashboard", "--duration", "-1"], "--duration: expected a positive number of seconds"),
        (["run", "--follow", "x.csv", "--follower", "magic"], "--follower: unknown follower 'magic'"),
        (["run", "--follow", "x.csv", "--off-path", "nan"], "--off-path: expected a positive number"),
    ],
)
def test_bad_arguments_are_one_line_errors(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert_one_line_error(err)
    assert message in err


def test_the_dashboard_runs_the_follower_in_its_link_thread(
    tmp_path: Path, harness: Harness, capsys: pytest.CaptureFixture[str]
) -> None:
    # the dashboard paces the run to the wall clock, and it keeps serving until --duration: a small
    # circle (about 3 s; the fixture's takes 8 s) and a shorter run, with the same 4 s to spare
    circle = tmp_path / "small_circle.csv"
    write_path(standard_path("circle", size=0.2), circle)
    argv = ["run", "--follow", str(circle), "--dashboard", "--http-port", "0", "--world", "empty"]
    assert main([*argv, "--duration", "10"]) == 0  # 3 s standing still, then the circle
    out = capsys.readouterr().out
    assert "run: dashboard for sim://omni4" in out and "run: follow completed" in out
    # the standstill of `omnibot follow`, on the dashboard's runtime too
    assert "run: nobody drives: follower held by the standstill: the gyro's bias is learned (3 s)" in out
    harness.assert_left_as_found()


CARPET = Path(__file__).parent.parent / "data" / "omni4_carpet_calibration_before_idle_phase.yaml"


def test_a_floors_calibration_and_open_loop_are_taken_as_asked(
    circle: Path, harness: Harness, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--calibration`` names the floor with ``--surface`` (also with ``--port``); ``--open-loop``
    is said once; the controller is left as found (its MODE included)."""
    port = "spy+faults+sim://omni4?world=empty&surface=carpet"
    argv = [
        "run",
        "--follow",
        str(circle),
        "--port",
        port,
        "--calibration",
        str(CARPET),
        "--surface",
        "carpet",
    ]
    assert main([*argv, "--open-loop"]) == 0
    out = capsys.readouterr().out
    assert out.count("run: open loop as asked") == 1 and "run: follow completed" in out
    harness.assert_left_as_found()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--robot", "mecanum4"], f"--calibration: {CARPET} is a calibration of 'omni4', not of 'mecanum4'"),
        (
            ["--surface", "wood"],
            "--surface: " + str(CARPET) + ": no wheel-slip calibration for surface 'wood'",
        ),
    ],
)
def test_a_calibration_of_another_robot_or_floor_is_refused(
    circle: Path, argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["run", "--follow", str(circle), "--calibration", str(CARPET), *argv]) == 2
    err = capsys.readouterr().err
    assert_one_line_error(err)
    assert message in err
