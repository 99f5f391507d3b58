"""A result that did not happen is never reported as success: each command's own check decides its
exit status (a recording too short, a run outside its tolerances, a calibration worse than none)."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace
from typing import Any, cast

import pytest

from omnibot.calibration.accuracy import AccuracyRow
from omnibot.calibration.results import CalibrationResult, SurfaceSession
from omnibot.calibration.verdict import judge_calibration
from omnibot.cli import main
from omnibot.client.client import RobotClient
from omnibot.control.paths.files import write_path
from omnibot.control.paths.standard import standard_path
from omnibot.navigation.metrics import Tolerances, judge
from omnibot.robot.description import load_robot
from tests.cli.conftest import Harness, assert_one_line_error


def test_a_recording_too_short_is_not_written(
    tmp_path: Path, harness: Harness, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "p.csv"
    argv = ["record", "--port", "sim://omni3", "--teach", "listen", "--duration", "1", "--path", str(out)]
    assert main(argv) == 1
    text = capsys.readouterr().out
    assert "a path needs at least 10 points and 0.1 m" in text and "nothing written" in text
    assert not out.exists()
    harness.assert_left_as_found()


def test_a_run_outside_its_tolerances_is_not_completed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    line = tmp_path / "line.csv"
    write_path(standard_path("line", size=0.3), line)
    assert main(["follow", str(line), "--robot", "omni3", "--final-tolerance", "0.0001"]) == 1
    out = capsys.readouterr().out
    assert "NOT COMPLETED: final error" in out and "> 0.0 cm" in out


def report(**values: Any) -> dict[str, Any]:
    base = {"follower_done": True, "final_error_m": 0.01, "max_cross_track_m": 0.02, "duration_s": 5.0}
    return base | values


@pytest.mark.parametrize(
    ("values", "completed", "why"),
    [
        ({}, True, ""),
        ({"follower_done": False}, False, "did not reach the end in 5.0 s"),
        ({"final_error_m": 12.0}, False, "final error 1200.0 cm > 15.0 cm"),
        ({"max_cross_track_m": 0.5}, False, "max cross-track error 50.0 cm > 30.0 cm"),
        ({"final_error_m": math.nan}, False, "final error nan cm"),
    ],
)
def test_follow_verdict(values: dict[str, Any], completed: bool, why: str) -> None:
    judged = judge(report(**values), Tolerances())
    assert judged["completed"] is completed
    assert why in "; ".join(judged["failures"])


def row(course: float, error: float, kind: str = "move") -> AccuracyRow:
    return AccuracyRow(kind, course, 0.3, 1.0, 1.0 + error, error)


def result(before: list[float], after: list[float]) -> CalibrationResult:
    robot = load_robot("mecanum4")
    assert robot.calibration is not None
    session = SurfaceSession(
        surface="wood",
        truth="sim",
        fit=cast(Any, SimpleNamespace(deadbands={})),
        spec=robot.calibration,
        runs=[],
        before=[row(45.0 * k, e) for k, e in enumerate(before)],
        after=[row(45.0 * k, e) for k, e in enumerate(after)],
    )
    return CalibrationResult(robot, [session])


def test_calibration_verdict() -> None:
    worse = judge_calibration(result([-0.03, 0.05], [-0.32, 0.01]))
    assert worse.better is False
    assert worse.worst == "wood: MOVE course 0 deg at 0.3 m/s: -3.0 % before, -32.0 % after"
    assert "wood 4.0 % -> 16.5 %" in worse.summary
    assert judge_calibration(result([-0.03, 0.05], [-0.01, 0.01])).better is True
    averaged = result([-0.03, 0.05], [-0.01, 0.01])
    averaged.average = averaged.sessions[0].spec
    averaged.average_checks = {"wood": [row(0.0, -0.32), row(45.0, 0.01)]}
    refused = judge_calibration(averaged)
    assert refused.better is False and "-32.0 % after" in refused.worst
    assert refused.hint.startswith("each floor's own tables: wood 4.0 % -> 1.0 %")
    unchecked = result([], [])
    unchecked.sessions[0].before = None
    assert judge_calibration(unchecked).better is None


@pytest.fixture
def fake_calibration(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    """``calibrate`` returns a made-up result (the real runs take minutes); uploads are recorded."""
    state: dict[str, Any] = {"after": [-0.32, 0.01], "uploads": []}

    def fake_calibrate(robot: Any, surfaces: list[str], open_client: Any, **kwargs: Any) -> CalibrationResult:
        made = result([-0.03, 0.05], state["after"])
        made.robot = robot
        return made

    def fake_report(result: CalibrationResult, directory: Any) -> list[Path]:
        path = Path(directory) / "accuracy.md"
        path.write_text("report\n")
        return [path]

    def upload(client: RobotClient, spec: Any) -> list[Any]:
        state["uploads"].append(spec)
        return []

    monkeypatch.setattr("omnibot.calibration.session.calibrate", fake_calibrate)
    monkeypatch.setattr("omnibot.calibration.report.write_report", fake_report)
    monkeypatch.setattr(RobotClient, "upload_calibration", upload)
    return state


def test_a_calibration_worse_than_none_is_neither_written_nor_kept(
    tmp_path: Path, fake_calibration: dict[str, Any], harness: Harness, capsys: pytest.CaptureFixture[str]
) -> None:
    cal = tmp_path / "cal.yaml"
    argv = [
        "calibrate",
        "--port",
        "sim://mecanum4",
        "--yes",
        "--out",
        str(tmp_path / "r"),
        "--calibration",
        str(cal),
    ]
    assert main(argv) == 1
    out, err = capsys.readouterr()
    assert_one_line_error(err)
    assert (
        "WORSE THAN NO CALIBRATION: wood: MOVE course 0 deg at 0.3 m/s: -3.0 % before, -32.0 % after" in out
    )
    assert "not written" in out and not cal.exists()
    # the board gets back the tables it was built with, not the worse ones
    assert fake_calibration["uploads"] == [load_robot("mecanum4").calibration]
    harness.assert_left_as_found()

    assert main([*argv, "--force"]) == 1
    assert "written anyway, --force" in capsys.readouterr().out
    assert cal.read_text().startswith("# WORSE THAN NO CALIBRATION: wood: MOVE course 0")


def test_a_calibration_better_than_none_is_written_and_kept(
    tmp_path: Path, fake_calibration: dict[str, Any], capsys: pytest.CaptureFixture[str]
) -> None:
    fake_calibration["after"] = [-0.01, 0.01]
    assert main(["calibrate", "--port", "sim://mecanum4", "--yes", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert f"calibration: {tmp_path / 'calibration.yaml'}" in out
    assert "wood 4.0 % -> 1.0 %" in out
    assert (tmp_path / "calibration.yaml").read_text().startswith("# omnibot calibrate: mecanum4")


def test_the_old_calibrate_spelling_still_works(
    tmp_path: Path, fake_calibration: dict[str, Any], capsys: pytest.CaptureFixture[str]
) -> None:
    fake_calibration["after"] = [-0.01, 0.01]
    cal, report_dir = tmp_path / "cal.yaml", tmp_path / "report"
    assert main(["calibrate", "--out", str(cal), "--report", str(report_dir), "--robot", "omni3"]) == 0
    err = capsys.readouterr().err
    assert "--out CAL.yaml is deprecated" in err and "--report is deprecated" in err
    assert cal.exists() and (report_dir / "accuracy.md").exists()


def test_a_demo_whose_sonar_approach_found_no_wall_is_not_done(
    tmp_path: Path, harness: Harness, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["demo", "--port", "sim://omni4", "--out", str(tmp_path)]) == 1  # the empty world
    out = capsys.readouterr().out
    assert "NO emergency stop, no echo: nothing ahead of the robot" in out
    assert out.rstrip().endswith("NOT DONE: sonar approach, emergency stop")
    harness.assert_left_as_found()
