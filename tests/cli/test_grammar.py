"""One grammar: the robot is the one on the link, outputs and files checked before anything moves,
the shared options' defaults, the deprecated spellings, the exit statuses of errors and bugs."""

from __future__ import annotations

from pathlib import Path

import pytest

from omnibot.calibration import merge_calibration
from omnibot.cli import main
from omnibot.control import read_path, standard_path, write_path
from omnibot.errors import ConfigError
from omnibot.robot.description import PRESET_DIR
from tests.cli.conftest import Harness, assert_one_line_error


@pytest.fixture
def line(tmp_path: Path) -> Path:
    path = tmp_path / "line.csv"
    write_path(standard_path("line", size=0.3), path)
    return path


def usage_error(argv: list[str], capsys: pytest.CaptureFixture[str], message: str) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert_one_line_error(err)
    assert message in err, err
    return err


@pytest.mark.parametrize(
    "argv",
    [
        ["follow", "{line}", "--robot", "omni4", "--port", "sim://omni3"],
        ["demo", "--robot", "mecanum4", "--port", "sim://omni4", "--out", "{tmp}"],
        ["send", "--robot", "omni3", "--port", "sim://mecanum4", "STATUS"],
        ["console", "--robot", "omni4", "--port", "sim://omni3"],
        ["record", "--robot", "omni3", "--port", "sim://omni4", "--path", "{tmp}/p.csv"],
        ["calibrate", "--robot", "omni3", "--port", "sim://omni4", "--yes", "--out", "{tmp}"],
        ["teleop", "--joystick", "--robot", "omni3", "--port", "sim://omni4", "--duration", "0.1"],
        ["dashboard", "--robot", "omni3", "--port", "sim://omni4", "--http-port", "0", "--duration", "0.1"],
    ],
)
def test_a_robot_that_is_not_the_one_on_the_link_is_refused(
    argv: list[str], line: Path, tmp_path: Path, harness: Harness, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [a.format(line=line, tmp=tmp_path) for a in argv]
    usage_error(argv, capsys, "but the controller on sim://")
    assert all(d.controller.state != 0 for d in harness.devices)  # nothing moved


def test_a_description_file_of_the_robot_on_the_link_is_accepted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mine = tmp_path / "my_omni3.yaml"
    mine.write_text((PRESET_DIR / "omni3.yaml").read_text())
    assert main(["send", "--robot", str(mine), "--port", "sim://omni3", "STATUS"]) == 0
    other = tmp_path / "not_omni3.yaml"
    other.write_text((PRESET_DIR / "omni3.yaml").read_text().replace("name: omni3", "name: omni3b", 1))
    capsys.readouterr()
    usage_error(
        ["send", "--robot", str(other), "--port", "sim://omni3", "STATUS"], capsys, "is the robot 'omni3b'"
    )
    # sim://FILE needs no --robot FILE besides: it was refused as "not a preset: give its description file"
    assert main(["send", "--port", f"sim://{other}", "STATUS"]) == 0


def test_a_calibration_of_another_robot_is_refused(
    line: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cal = tmp_path / "cal.yaml"
    cal.write_text(
        "robot: omni3\ncalibration: {k: 160.0}\n"
        "surfaces: {wood: {calibration: {k: 160.0}, odometry: {slip: {roll: 0.001, compliance: 0.0, scale: 1.0}}}}\n"
    )
    message = "is a calibration of 'omni3', not of 'omni4'"
    usage_error(["follow", str(line), "--calibration", str(cal), "--surface", "wood"], capsys, message)
    usage_error(
        ["follow", str(line), "--port", "sim://omni4", "--calibration", str(cal), "--surface", "wood"],
        capsys,
        message,
    )
    with pytest.raises(ConfigError, match=message):
        merge_calibration("omni4", cal)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["record", "--path", "{blocker}/p.csv"], "--path: cannot write"),
        (["record", "--path", "{tmp}"], "is a directory"),
        (["follow", "{line}", "--report", "{blocker}/r.json"], "--report: cannot write"),
        (["follow", "{line}", "--plot", "{blocker}/p.png"], "--plot: cannot write"),
        (["follow", "{line}", "--out", "{blocker}/dir"], "--out: cannot make directory"),
        (["demo", "--port", "sim://omni4", "--out", "{blocker}/dir"], "--out: cannot make directory"),
        (["tour", "--robot", "omni4", "--out", "{blocker}/dir"], "--out: cannot make directory"),
        (["calibrate", "--out", "{blocker}/dir"], "--out: cannot make directory"),
        (["calibrate", "--calibration", "{blocker}/c.yaml"], "--calibration: cannot write"),
    ],
)
def test_unwritable_output_is_refused_before_the_robot_moves(
    argv: list[str],
    message: str,
    line: Path,
    tmp_path: Path,
    harness: Harness,
    capsys: pytest.CaptureFixture[str],
) -> None:
    blocker = tmp_path / "a_file"  # a file where a directory should be: unwritable, even for root
    blocker.write_text("x")
    usage_error([a.format(line=line, tmp=tmp_path, blocker=blocker) for a in argv], capsys, message)
    assert not harness.devices or all(d.sim.clock.now() < 1.0 for d in harness.devices)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["follow", "{bad}"], "is not a number"),
        (["follow", "{line}", "--robot", "{bad_robot}"], "bad_robot.yaml"),
        (["follow", "{line}", "--world", "{bad_world}"], "bad_world.yaml"),
        (["follow", "{line}", "--calibration", "{bad}"], "calibration"),
        (["send", "STATUS", "--world", "moon"], "unknown world"),
        (["send", "STATUS", "--surface", "ice"], "unknown surface 'ice'"),
        (["follow", "{line}", "--port", "sim://omni4", "--seed", "3"], "--seed"),
        (["demo", "--port", "sim://omni4", "--world", "room"], "put it in a sim:// URL"),
        (["send", "STATUS", "--port", "/dev/omnibot-no-such-port"], "--port: cannot open"),
        # a negative seed reached numpy's SeedSequence (exit 70) where no sim:// URL checked it
        (["follow", "{line}", "--seed", "-1"], "--seed: expected an integer >= 0"),
        (["tour", "--seed", "-1"], "--seed: expected an integer >= 0"),
        (["sim", "--pty", "--seed", "-1"], "--seed: expected an integer >= 0"),
        (["sim", "--pty", "--robot", "omni4?seed=-1", "--robot", "omni3"], "seed=N (N >= 0)"),
    ],
)
def test_bad_files_and_options_are_one_line_usage_errors(
    argv: list[str], message: str, line: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "bad.csv").write_text("t,x,y,theta\n0,0,0,0\n1,oops,0,0\n")
    (tmp_path / "bad_robot.yaml").write_text("name: x\nwheels: 3\n")
    (tmp_path / "bad_world.yaml").write_text("walls: [1, 2\n")
    names = {
        "line": line,
        "bad": tmp_path / "bad.csv",
        "bad_robot": tmp_path / "bad_robot.yaml",
        "bad_world": tmp_path / "bad_world.yaml",
    }
    usage_error([a.format(**names) for a in argv], capsys, message)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["follow", "{given}", "--truth", "{given}"], "--truth: {given} is also PATH"),
        (["follow", "{given}", "--log", "{given}"], "--log: {given} is also PATH"),
        (
            ["follow", "{out}/follow_truth.csv", "--out", "{out}"],
            "--out: {out}/follow_truth.csv is also PATH",
        ),
        (["follow", "{line}", "--report", "{given}", "--calibration", "{given}"], "is also --calibration"),
        (["record", "--path", "{tmp}/p.csv", "--log", "{tmp}/p.csv"], "--log: {tmp}/p.csv is also --path"),
        (["calibrate", "--robot", "{given}", "--calibration", "{given}"], "is also --robot"),
        (["robot", "urdf", "{robot}", "-o", "{robot}"], "--out: {robot} is also ROBOT"),
        (
            ["follow", "{line}", "--plot", "{tmp}/p.txt"],
            "--plot: {tmp}/p.txt: the plot's format is its extension",
        ),
    ],
)
def test_an_output_that_is_an_input_or_another_output_is_refused(
    argv: list[str],
    message: str,
    line: Path,
    tmp_path: Path,
    harness: Harness,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The user's file was replaced by the result (the path by the truth, the description by the URDF)."""
    out = tmp_path / "out"
    out.mkdir()
    given = tmp_path / "given.csv"
    given.write_text(line.read_text())
    (out / "follow_truth.csv").write_text(line.read_text())
    robot = tmp_path / "robot.yaml"
    robot.write_text((PRESET_DIR / "omni4.yaml").read_text())
    names = {"given": given, "line": line, "tmp": tmp_path, "out": out, "robot": robot}
    usage_error([a.format(**names) for a in argv], capsys, message.format(**names))
    assert given.read_text() == (out / "follow_truth.csv").read_text() == line.read_text()
    assert robot.read_text() == (PRESET_DIR / "omni4.yaml").read_text()
    assert not harness.devices  # refused before any robot was made


def test_deprecated_spellings_still_work(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "old.csv"
    argv = ["record", "--out", str(out), "--fixed-heading", "--shape", "line", "--size", "0.3"]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "--out is deprecated; use --path" in err and "--fixed-heading is deprecated" in err
    path = read_path(out)
    assert len(set(path.theta.tolist())) == 1  # the start heading on every row


def test_an_unexpected_exception_is_one_line_and_exit_70(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def broken(*args: object, **kwargs: object) -> None:
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr("omnibot.robot.summary.describe", broken)
    assert main(["robot", "show", "omni4"]) == 70
    err = capsys.readouterr().err
    assert err.startswith("omnibot: internal error: ZeroDivisionError: a bug") and "Traceback" not in err
    assert main(["robot", "show", "omni4", "--debug"]) == 70
    assert "Traceback" in capsys.readouterr().err
