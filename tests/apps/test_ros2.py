"""``omnibot ros2``'s options (:mod:`omnibot.apps.ros2`): bad input is one line, non-zero, before any
robot or DDS is touched; the robots pair up in the order of ``--port``."""

from __future__ import annotations

import sys

import pytest

from omnibot.cli import main
from tests.cli.conftest import assert_one_line_error


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--namespace", "1robot"], "not a valid ROS namespace"),
        (["--namespace", "a//b"], "not a valid ROS namespace"),
        (["--cmd-vel-timeout", "0"], "--cmd-vel-timeout"),
        (["--cmd-vel-timeout", "nan"], "--cmd-vel-timeout"),
        (["--duration", "-1"], "--duration"),
    ],
)
def test_bad_options_are_refused(args: list[str], words: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["ros2", "--port", "sim://omni4", *args]) != 0
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


TWO = ["--port", "sim://omni4", "--namespace", "r1", "--port", "sim://omni3", "--namespace", "r2"]


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (
            ["--port", "sim://omni4", "--port", "sim://omni3", "--namespace", "r1"],
            "2 robots (--port) but 1 --namespace",
        ),
        (["--port", "sim://omni4", "--port", "sim://omni3"], "2 robots (--port) but 0 --namespace"),
        (
            ["--port", "sim://omni4", "--namespace", "r1", "--namespace", "r2"],
            "at most one of each per robot",
        ),
        (
            ["--port", "sim://omni4", "--namespace", "r1", "--port", "sim://omni3", "--namespace", "/r1/"],
            "two robots with the namespace 'r1'",
        ),
        (
            [*TWO, "--frame-prefix", "", "--frame-prefix", ""],
            "two robots with the tf frame prefix '(none)'",
        ),
        (
            [*TWO, "--frame-prefix", "a"],
            "--frame-prefix",
        ),
        (["--port", "sim://omni4", "--frame-prefix", "1x"], "not a valid tf frame prefix"),
        (
            [*TWO, "--log", "x.mcap"],
            "--log and --foxglove record one robot",
        ),
        (["--port", "sim://omni4", "--speed", "0"], "--speed"),
    ],
)
def test_robots_that_do_not_pair_up_are_refused(
    args: list[str], words: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["ros2", *args, "--duration", "1"]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err and len(err.strip().splitlines()) == 1, err


def test_robots_pair_up_in_order() -> None:
    from omnibot.apps.ros2 import robot_specs
    from omnibot.cli import build_parser
    from omnibot.ros2 import RobotSpec

    args = build_parser().parse_args(
        [
            "ros2",
            "--port",
            "sim://a",
            "--namespace",
            "r1",
            "--port",
            "sim://b",
            "--namespace",
            "r2",
            "--frame-prefix",
            "",
            "--frame-prefix",
            "two",
        ]
    )
    assert robot_specs(args) == [RobotSpec("sim://a", "r1", ""), RobotSpec("sim://b", "r2", "two/")]
    one = build_parser().parse_args(["ros2", "--namespace", "/fleet/r1/"])
    assert robot_specs(one) == [RobotSpec(None, "fleet/r1", "fleet/r1/")]


def test_several_robots_take_one_scanner_each_or_none(capsys: pytest.CaptureFixture[str]) -> None:
    two = ["--port", "sim://omni4", "--namespace", "r1", "--port", "sim://omni3", "--namespace", "r2"]
    assert main(["ros2", *two, "--scanner", "/dev/ttyUSB1"]) == 2
    err = capsys.readouterr().err
    assert "2 robots (--port) but 1 --scanner" in err
    assert_one_line_error(err)


def test_without_cyclonedds_it_says_how_to_install(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    for name in [
        m for m in sys.modules if m == "cyclonedds" or m.startswith(("cyclonedds.", "omnibot.ros2."))
    ]:
        parent, _, child = name.rpartition(".")
        if hasattr(sys.modules.get(parent), child):  # the import below binds the new module there:
            monkeypatch.setattr(sys.modules[parent], child, sys.modules[name])  # the old one comes back
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "cyclonedds", None)  # import fails as if not installed
    assert main(["ros2", "--port", "sim://omni4", "--duration", "1"]) != 0
    err = capsys.readouterr().err
    assert "pip install 'omnibot[ros2]'" in err and "Traceback" not in err


@pytest.mark.parametrize(("extra", "floor"), [(["--calibration", "cal.yaml"], "carpet"), ([], None)])
def test_cmd_vel_ramps_within_the_grip_of_a_calibrations_floor(extra: list[str], floor: str | None) -> None:
    from omnibot.apps.ros2 import check
    from omnibot.cli import build_parser

    args = build_parser().parse_args(["ros2", "--ros-backend", "dds", "--surface", "carpet", *extra])
    check(args)
    assert args.ros2_bridge.surface == floor
