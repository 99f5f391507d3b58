"""``omnibot teleop``: argument errors exit 2 with one line, and a real terminal drives the robot."""

from __future__ import annotations

import os
import re
import select
import subprocess
import sys
import time
from pathlib import Path

import pytest

from omnibot.cli import main


def test_joystick_waits_for_a_pad_and_keeps_the_robot_still(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["teleop", "--joystick", "--duration", "0.3"]) == 0
    out = capsys.readouterr().out
    assert "no joystick attached yet" in out
    assert "sent 0 VEL, 0 zero VEL" in out
    assert "robot at x=1.00 m y=1.00 m" in out  # the room's start pose: it never moved


def test_a_log_holds_the_robots_telemetry_estimate_and_truth(tmp_path: Path) -> None:
    """``--log``: teleop asks for telemetry, so the log has what the robot did (here: stood still at
    the room's start), not only the commands."""
    from omnibot.logs import topics
    from omnibot.logs.reader import LogFile

    path = tmp_path / "teleop.mcap"
    assert main(["teleop", "--joystick", "--duration", "0.5", "--log", str(path)]) == 0
    messages = LogFile.open(path).read_all()
    counts = {t: sum(m.topic == t for m in messages) for t in (topics.ODOM, topics.ESTIMATE, topics.TRUTH)}
    assert min(counts.values()) >= 5, counts  # telemetry every teleop period (20 Hz) for 0.5 s
    truth = [m for m in messages if m.topic == topics.TRUTH][-1].decode().pose.pose.position
    assert (truth.x, truth.y) == pytest.approx((1.0, 1.0), abs=1e-3)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--duration", "0"], "--duration: expected a positive number of seconds"),
        (["--robot", "omni5"], "unknown robot 'omni5'; did you mean 'omni4'?"),
        (["--port", "sim://omni9"], "omni9"),
        (["--port", "bogus://x"], "bogus"),
    ],
)
def test_bad_arguments_exit_2(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["teleop", "--joystick", "--duration", "0.1", *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("omnibot: error: ") and message in err
    assert "Traceback" not in err


def test_bad_config_file_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    config = tmp_path / "pad.yaml"
    config.write_text("enable_buton: 4\n")
    assert main(["teleop", "--joystick", "--config", str(config)]) == 2
    assert "enable_buton: unknown key; did you mean 'enable_button'?" in capsys.readouterr().err


def test_keyboard_needs_a_terminal(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    monkeypatch.setattr("omnibot.teleop.keyboard.os.isatty", lambda fd: False)
    assert main(["teleop", "--keyboard"]) == 2
    assert "--keyboard: keyboard teleop needs a terminal" in capsys.readouterr().err
    # `run` and `map` name the option as the user gave it there
    for argv in (["run", "--teleop", "keyboard"], ["map", "--teleop", "keyboard", "--out", str(tmp_path)]):
        assert main(argv) == 2
        assert "--teleop keyboard: keyboard teleop needs a terminal" in capsys.readouterr().err


def test_no_pad_and_no_terminal(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(sys.stdin, "isatty", lambda: False)
    assert main(["teleop"]) == 2
    assert "no joystick attached and standard input is not a terminal" in capsys.readouterr().err


def test_keyboard_in_a_real_terminal_drives_the_simulated_robot_in_real_time() -> None:
    """``omnibot teleop --keyboard`` on a pseudo-terminal: hold w for a second (auto-repeat), let go."""
    master, slave = os.openpty()
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "omnibot", "teleop", "--keyboard", "--duration", "3"],
        stdin=slave,
        stdout=slave,
        stderr=slave,
        env=env,
        start_new_session=True,
    )
    os.close(slave)
    out = b""
    try:

        def read_until(pattern: bytes, timeout: float) -> None:
            nonlocal out
            end = time.monotonic() + timeout
            while pattern not in out:
                assert time.monotonic() < end, f"no {pattern!r} in {out!r}"
                if select.select([master], [], [], 0.05)[0]:
                    try:
                        out += os.read(master, 4096)
                    except OSError:  # the child closed the terminal
                        return

        read_until(b"keys: ", 20)
        for _ in range(30):  # a held key: the terminal repeats it every 33 ms
            os.write(master, b"w")
            time.sleep(0.033)
        assert proc.wait(timeout=20) == 0
        read_until(b"failed", 5)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(master)
    text = out.decode(errors="replace")
    assert "stopping: released" in text

    def number(pattern: str) -> float:
        return float(re.search(pattern, text).group(1))  # type: ignore[union-attr]

    x = number(r"robot at x=([-\d.]+) m")
    speed, period = number(r"limits: ([\d.]+) m/s"), number(r"VEL every (\d+) ms") / 1000
    vels = number(r"sent (\d+) VEL")
    # forward (from x = 1.0) at the robot's top speed for as long as it was sent VEL: judged on the
    # count of VEL (one a period of the simulator's time), not on the wall clock, of which a loaded
    # machine gives the simulation less (and the keys arrive bunched); 24-29 VEL, 1.14-1.39 m seen
    # The twist ramps at the robot's 2 m/s^2 both ways (what the ramp up loses the ramp down gives
    # back), and the stop sequence's VELs are on the way down (nonzero): the key held the robot for
    # the VELs before them
    held = (vels - 5) * period  # TeleopConfig().stop_repeats
    assert held > 0.5, text  # the keys held it for a second
    assert abs((x - 1.0) - speed * held) < 0.15, text
