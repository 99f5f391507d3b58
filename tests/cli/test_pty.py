"""The commands as a user runs them: subprocesses over the pty emulator (``omnibot sim --pty``),
ended normally, by SIGINT, by SIGTERM, by SIGHUP and by the emulator dying. Afterwards a second connection
asks the controller for STATUS: it must answer in text, idle, in MODE 0 (slow: marked, run in CI).
"""

from __future__ import annotations

import signal
import time
from pathlib import Path

import pytest

from omnibot.control import standard_path, write_path
from omnibot.protocol import codes
from tests.cli.conftest import Command, PtyRobot, assert_one_line_error, controller_state

# real-time runs of whole commands (a Python start each): far slower than the 120 s hang guard allows
# for on a loaded machine's busiest moments
pytestmark = [pytest.mark.slow, pytest.mark.timeout(300)]


def assert_left_as_found(path: str) -> None:
    state, mode = controller_state(path)
    assert state == codes.STATE_IDLE and mode == 0, (state, mode)


def test_record_then_follow_leave_the_text_protocol_and_mode_0(pty_robot: PtyRobot, tmp_path: Path) -> None:
    taught = tmp_path / "taught.csv"
    record = Command(
        "record", "--port", pty_robot.path, "--teach", "drive", "--shape", "line", "--size", "0.3",
        "--path", str(taught),
    )  # fmt: skip
    code, out, err = record.finish()
    assert code == 0, err
    assert_left_as_found(pty_robot.path)  # record switched to binary and closed-loop MODE
    follow = Command("follow", str(taught), "--port", pty_robot.path, "--speed", "0.3")
    code, out, err = follow.finish()
    assert code == 0, out + err
    assert "omnibot follow: omni4, tracker" in out
    assert_left_as_found(pty_robot.path)


@pytest.mark.parametrize(
    ("signum", "status"), [(signal.SIGINT, 130), (signal.SIGTERM, 143), (signal.SIGHUP, 129)]
)
def test_a_signal_during_a_move_stops_the_robot(pty_robot: PtyRobot, signum: int, status: int) -> None:
    """SIGHUP is the terminal or SSH session closing: it left the robot driving before."""
    if signum == signal.SIGHUP and signal.getsignal(signal.SIGHUP) == signal.SIG_IGN:
        pytest.skip("the suite runs under nohup: the command inherits an ignored SIGHUP and runs on")
    send = Command("send", "--port", pty_robot.path, "--binary", "MOVE,300,40,0,0", "--wait-idle")
    send.wait_for("<- OK")
    send.signal(signum)
    code, _out, err = send.finish()
    assert code == status, err
    assert_one_line_error(err)
    assert f"omnibot: interrupted ({signal.Signals(signum).name})" in err
    assert_left_as_found(pty_robot.path)


def test_quitting_the_console_during_a_move_stops_the_robot(pty_robot: PtyRobot) -> None:
    console = Command("console", "--port", pty_robot.path, stdin=True)
    assert console.proc.stdin is not None
    console.proc.stdin.write("MOVE,300,40,0,0\n")
    console.proc.stdin.flush()
    console.wait_for("<- OK")
    code, _out, err = console.finish(stdin=":quit\n")
    assert code == 0, err
    assert_left_as_found(pty_robot.path)


def test_an_interrupted_follow_gives_the_controller_back_in_mode_0(
    pty_robot: PtyRobot, tmp_path: Path
) -> None:
    line = tmp_path / "line.csv"
    write_path(standard_path("line", size=0.5), line)
    trace = tmp_path / "trace.txt"
    follow = Command("follow", str(line), "--port", f"spy+{pty_robot.path}?file={trace}")
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:  # telemetry streaming, the wheel loop on (MODE 2)
        if trace.exists() and trace.read_text(errors="replace").count(" RX ") > 40:
            break
        time.sleep(0.1)
    follow.signal(signal.SIGINT)
    code, _out, err = follow.finish()
    assert code == 130, err
    assert_one_line_error(err)
    assert_left_as_found(pty_robot.path)


def test_the_link_dying_is_one_line_and_exit_1(pty_robot: PtyRobot) -> None:
    send = Command("send", "--port", pty_robot.path, "MOVE,300,40,0,0", "--wait-idle")
    send.wait_for("<- OK")
    pty_robot.kill()
    code, _out, err = send.finish()
    assert code == 1, err
    assert_one_line_error(err)
    assert err.startswith("omnibot: error:")


@pytest.mark.parametrize("command", ["dashboard", "run"])
def test_the_link_dying_ends_the_dashboard_with_exit_1(pty_robot: PtyRobot, command: str) -> None:
    """It served the dead robot until --duration and exited 0 before."""
    argv = ["dashboard"] if command == "dashboard" else ["run", "--dashboard"]
    dash = Command(*argv, "--port", pty_robot.path, "--http-port", "0", "--duration", "60")
    dash.wait_for("Ctrl-C stops it")
    pty_robot.kill()
    code, _out, err = dash.finish()
    assert code == 1, err
    assert f"omnibot {command}: the robot link ended: serial port {pty_robot.path} failed" in err
    assert "Traceback" not in err


@pytest.mark.parametrize(
    ("argv", "ready", "signum", "status"),
    [
        (["teleop", "--joystick", "--robot", "omni3"], "limits:", signal.SIGINT, 130),
        (["dashboard", "--http-port", "0", "--robot", "mecanum4"], "Ctrl-C stops it", signal.SIGTERM, 143),
    ],
)
def test_commands_that_run_until_stopped_exit_with_the_signal(
    argv: list[str], ready: str, signum: int, status: int
) -> None:
    command = Command(*argv)
    command.wait_for(ready)
    command.signal(signum)
    code, out, err = command.finish()
    assert code == status, out + err
    assert_one_line_error(err)
    assert f"omnibot: interrupted ({signal.Signals(signum).name})" in err
