"""Every command that talks to a robot, on every preset, over ``sim://`` (in-process, ``main(argv)``).

Each is ended normally, by an error, by SIGINT, by SIGTERM, by its link closing and by its cable
pulled; the exit status must match the ending (docs/cli.md's command table), no traceback, and the
simulated controller must be left stopped, with telemetry off, in MODE 0 and the text protocol
(what it started with), except when the link is gone (nobody can reach it then).
"""

from __future__ import annotations

import io
import itertools
from pathlib import Path

import pytest

from omnibot.cli import main
from omnibot.control import standard_path, write_path
from omnibot.protocol import codes
from omnibot.robot import preset_names
from tests.cli.conftest import EXIT, Harness, assert_one_line_error

PRESETS = preset_names()
CONSOLE_INPUT = "MOVE,200,40,0,0\n:wait 1\n:quit\n"
"""A MOVE of 5 s, then :quit while it runs: the console must stop the robot on the way out."""


def argv_for(command: str, robot: str, tmp: Path) -> list[str]:
    line = tmp / "line.csv"
    if not line.exists():
        write_path(standard_path("line", size=0.3), line)
    port = f"sim://{robot}"
    return {
        "follow": ["follow", str(line), "--robot", robot, "--report", str(tmp / "r.json")],
        "follow-port": ["follow", str(line), "--port", port],
        "record": ["record", "--robot", robot, "--shape", "line", "--size", "0.3", "--path", str(tmp / "p.csv")],
        "record-port": [
            "record", "--port", port, "--teach", "drive", "--shape", "line", "--size", "0.3",
            "--path", str(tmp / "d.csv"),
        ],
        "demo": ["demo", "--port", f"{port}?world=room", "--out", str(tmp / "demo")],
        "send": ["send", "--port", port, "MOVE,30,40,0,0", "--wait-idle"],
        "console": ["console", "--port", port],
        "teleop": ["teleop", "--joystick", "--duration", "0.2", "--robot", robot],
        "dashboard": ["dashboard", "--http-port", "0", "--duration", "0.2", "--robot", robot],
        "calibrate": [
            "calibrate", "--robot", robot, "--quick", "--surface", "wood", "--no-check", "--no-slip",
            "--no-rollers", "--no-motor-map", "--out", str(tmp / "cal"),
        ],
    }[command]  # fmt: skip


def run(argv: list[str], monkeypatch: pytest.MonkeyPatch, command: str) -> int:
    if command == "console":
        monkeypatch.setattr("sys.stdin", io.StringIO(CONSOLE_INPUT))
    return main(argv)


NORMAL = ["follow", "follow-port", "record", "record-port", "demo", "send", "console", "teleop", "dashboard"]


@pytest.mark.parametrize("robot", PRESETS)
@pytest.mark.parametrize("command", NORMAL)
def test_normal_end_on_every_preset(
    command: str,
    robot: str,
    tmp_path: Path,
    harness: Harness,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    code = run(argv_for(command, robot, tmp_path), monkeypatch, command)
    out, err = capsys.readouterr()
    assert code == 0, out + err
    assert_one_line_error(err)
    harness.assert_left_as_found()
    if command == "demo" and robot != "omni4":
        assert f"skipped: {robot} has no sonar" in out
    if command == "follow-port":
        assert f"omnibot follow: {robot}," in out  # the robot on the link, not a default


INTERRUPTED = ["follow-port", "record", "record-port", "demo", "send", "console", "calibrate"]
CASES = [
    (command, ending, PRESETS[k % len(PRESETS)])
    for k, (command, ending) in enumerate(
        itertools.product(INTERRUPTED, ("error", "sigint", "sigterm", "link", "unplug"))
    )
]


@pytest.mark.parametrize(("command", "ending", "robot"), CASES)
def test_every_way_out_leaves_the_controller_as_found(
    command: str,
    ending: str,
    robot: str,
    tmp_path: Path,
    harness: Harness,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    harness.ending = ending
    code = run(argv_for(command, robot, tmp_path), monkeypatch, command)
    out, err = capsys.readouterr()
    assert harness.fired, "the command ended before the test could end it"
    assert code == EXIT[ending], out + err
    assert_one_line_error(err)
    if ending in ("sigint", "sigterm"):
        assert f"omnibot: interrupted ({ending.upper()})" in err
    if ending == "unplug":  # why the link broke, not only that its port cannot be opened since
        assert "unplugged by the test" in err, err
    if ending not in ("link", "unplug"):
        harness.assert_left_as_found()


def test_debug_shows_the_traceback(
    tmp_path: Path, harness: Harness, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    harness.ending = "error"
    assert main([*argv_for("send", "omni4", tmp_path), "--debug"]) == 1
    err = capsys.readouterr().err
    assert_one_line_error(err, debug=True)
    assert "injected by the test" in err
    harness.assert_left_as_found()


def test_send_leaves_a_motion_it_was_asked_for_running(
    harness: Harness, capsys: pytest.CaptureFixture[str]
) -> None:
    """send's job is to send: a MOVE without --wait-idle keeps going (the protocol is back to text)."""
    assert main(["send", "--binary", "MOVE,100,40,0,0"]) == 0
    ctl = harness.controller()
    assert ctl.state == codes.STATE_MOVING and not ctl.binary and ctl.mode == 0
