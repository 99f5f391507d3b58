"""A result that did not happen is never reported as success: each command's own check decides its
exit status (a recording too short, a run outside its tolerances, a calibration worse than none)."""

from __future__ import annotations

import math
import re
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any, cast

import pytest

from omnibot.apps import calibrate as calibration_cli
from omnibot.calibration import CalibrationResult, judge_calibration, load_calibration
from omnibot.calibration import write_report as real_write_report
from omnibot.calibration.accuracy import AccuracyRow
from omnibot.calibration.results import SurfaceSession
from omnibot.calibration.verdict import judge_average
from omnibot.cli import build_parser, main
from omnibot.client import RobotClient
from omnibot.control import standard_path, write_path
from omnibot.errors import ConfigError
from omnibot.navigation import Tolerances
from omnibot.navigation.metrics import judge
from omnibot.robot import load_robot
from tests.cli.conftest import Harness, assert_one_line_error


def test_a_recording_too_short_is_not_written(
    tmp_path: Path, harness: Harness, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "p.csv"
    argv = ["record", "--port", "sim://omni3", "--teach", "listen", "--duration", "1", "--path", str(out)]
    assert main(argv) == 1
    text = capsys.readouterr().out
    assert "a path needs at least 10 points and 0.1 m" in text and "nothing written" in text
    assert re.match(r"omnibot record: omni3 listened to: recorded \d+ points, ", text), text  # said once
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


def test_a_follow_pinned_against_the_cabinet_is_not_completed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    into = tmp_path / "into.csv"  # from the room's start straight into its cabinet
    into.write_text("t,x,y,theta\n0,1.0,1.0,0\n5,2.5,1.0,0\n10,4.5,1.0,0\n", encoding="utf-8")
    assert main(["follow", str(into), "--world", "room"]) == 1
    out = capsys.readouterr().out
    assert "omnibot follow: NOT COMPLETED: stalled: the wheels say " in out and "final error 13" in out


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
        ({"follower_done": False, "failure": "stalled: ..."}, False, "stalled: ..."),
    ],
)
def test_follow_verdict(values: dict[str, Any], completed: bool, why: str) -> None:
    judged = judge(report(**values), Tolerances())
    assert judged["completed"] is completed
    assert why in "; ".join(judged["failures"])


def row(course: float, error: float, kind: str = "move") -> AccuracyRow:
    return AccuracyRow(kind, course, 0.3, 1.0, 1.0 + error, error)


def session(surface: str, before: list[float], after: list[float], k: float | None = None) -> SurfaceSession:
    robot = load_robot("mecanum4")
    assert robot.calibration is not None
    return SurfaceSession(
        surface=surface,
        truth="sim",
        fit=cast(Any, SimpleNamespace(deadbands={})),
        spec=robot.calibration if k is None else robot.calibration.model_copy(update={"k": k}),
        runs=[],
        before=[row(45.0 * k, e) for k, e in enumerate(before)],
        after=[row(45.0 * k, e) for k, e in enumerate(after)],
    )


def result(before: list[float], after: list[float]) -> CalibrationResult:
    return CalibrationResult(load_robot("mecanum4"), [session("wood", before, after)])


def two_floors(average: list[float], carpet_after: list[float] | None = None) -> CalibrationResult:
    """Wood and carpet, each floor's own tables better than none unless ``carpet_after`` says
    otherwise; ``average``: the average's errors on wood (on carpet it helps)."""
    wood = session("wood", [-0.03, 0.05], [-0.01, 0.01], k=150.0)
    carpet = session("carpet", [-0.34, -0.30], carpet_after or [-0.05, 0.06], k=190.0)
    made = CalibrationResult(load_robot("mecanum4"), [wood, carpet])
    made.average = carpet.spec.model_copy(update={"k": 170.0})
    made.average_checks = {
        "wood": [row(0.0, average[0]), row(45.0, average[1])],
        "carpet": carpet.after or [],
    }
    verdict = judge_average(made)
    assert verdict is not None
    made.average_better = verdict.better  # as calibrate() sets it
    return made


def test_calibration_verdict() -> None:
    worse = judge_calibration(result([-0.03, 0.05], [-0.32, 0.01]))
    assert worse.better is False
    assert worse.worst == "wood: MOVE course 0 deg at 0.3 m/s: -3.0 % before, -32.0 % after"
    assert "wood 4.0 % -> 16.5 %" in worse.summary
    assert judge_calibration(result([-0.03, 0.05], [-0.01, 0.01])).better is True
    # the average over the floors is judged on its own: worse than none on wood, it is not kept,
    # while each floor's own tables are
    refused = judge_calibration(two_floors([-0.32, 0.01]))
    assert refused.better is True and refused.summary.endswith("wood 4.0 % -> 1.0 %, carpet 32.0 % -> 5.5 %")
    assert refused.average is not None and refused.average.better is False
    assert "wood: MOVE course 0 deg at 0.3 m/s: -3.0 % before, -32.0 % after" in refused.average.worst
    kept = judge_calibration(two_floors([-0.02, 0.01]))
    assert kept.better is True and kept.average is not None and kept.average.better is True
    # a floor whose own tables are worse than none makes the calibration worse than none
    bad = judge_calibration(two_floors([-0.02, 0.01], carpet_after=[-0.5, -0.5]))
    assert bad.better is False and bad.worst.startswith("carpet: MOVE")
    assert bad.hint == "better than none on wood: calibrate that floor alone (--surface NAME)"
    unchecked = result([], [])
    unchecked.sessions[0].before = None
    assert judge_calibration(unchecked).better is None


@pytest.fixture
def fake_calibration(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    """``calibrate`` returns a made-up result (the real runs take minutes); uploads are recorded."""
    state: dict[str, Any] = {"after": [-0.32, 0.01], "uploads": []}

    def fake_calibrate(robot: Any, surfaces: list[str], open_client: Any, **kwargs: Any) -> CalibrationResult:
        made = state["result"] if "result" in state else result([-0.03, 0.05], state["after"])
        made.robot = robot
        return made

    def fake_report(result: CalibrationResult, directory: Any) -> list[Path]:
        path = Path(directory) / "accuracy.md"
        path.parent.mkdir(parents=True, exist_ok=True)  # as write_report makes --out DIR
        path.write_text("report\n")
        return [path]

    def upload(client: RobotClient, spec: Any) -> list[Any]:
        state["uploads"].append(spec)
        return []

    monkeypatch.setattr("omnibot.calibration.session.calibrate", fake_calibrate)
    monkeypatch.setattr("omnibot.calibration.report.write_report", fake_report)
    monkeypatch.setattr(RobotClient, "upload_calibration", upload)
    return state


def _calibrate_argv(tmp_path: Path, cal: Path) -> list[str]:
    """``calibrate`` of the simulated mecanum4, unattended, its report and file in ``tmp_path``."""
    return [
        "calibrate",
        "--port",
        "sim://mecanum4",
        "--yes",
        "--out",
        str(tmp_path / "r"),
        "--calibration",
        str(cal),
    ]


def test_a_calibration_worse_than_none_is_neither_written_nor_kept(
    tmp_path: Path, fake_calibration: dict[str, Any], harness: Harness, capsys: pytest.CaptureFixture[str]
) -> None:
    cal = tmp_path / "cal.yaml"
    argv = _calibrate_argv(tmp_path, cal)
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


def test_a_calibration_that_makes_rotate_worse_says_so_and_is_not_kept(
    tmp_path: Path, fake_calibration: dict[str, Any], capsys: pytest.CaptureFixture[str]
) -> None:
    """Better on the whole, but ROTATE worse than before (omni4's default run, issue 24): refused."""
    made = result([-0.10, 0.05], [-0.01, 0.01])
    wood = made.sessions[0]
    assert wood.before is not None and wood.after is not None
    wood.before.append(row(0.0, -0.016, "rotate"))
    wood.after.append(row(0.0, -0.036, "rotate"))
    fake_calibration["result"] = made
    cal = tmp_path / "cal.yaml"
    argv = _calibrate_argv(tmp_path, cal)
    assert main(argv) == 1
    out = capsys.readouterr().out
    assert "wood 5.5 % -> 1.9 %" in out  # better on the whole
    assert "worse than before: wood: ROTATE: 1.6 % -> 3.6 % (worst ROTATE +1 deg at 0.3 deg/s" in out
    assert (
        "not written, not kept on the controller: WORSE THAN BEFORE: wood: ROTATE" in out and not cal.exists()
    )
    assert fake_calibration["uploads"] == [load_robot("mecanum4").calibration]  # the tables it was built with
    assert main([*argv, "--force"]) == 1
    assert "written anyway, --force" in capsys.readouterr().out
    assert cal.read_text().startswith("# WORSE THAN BEFORE: wood: ROTATE: 1.6 % -> 3.6 %")
    assert load_calibration(cal).calibration is not None


def test_two_floors_keep_their_own_tables_when_their_average_is_worse_than_none(
    tmp_path: Path, fake_calibration: dict[str, Any], capsys: pytest.CaptureFixture[str]
) -> None:
    fake_calibration["result"] = two_floors([-0.32, 0.01])
    cal = tmp_path / "calibration.yaml"
    port = ["calibrate", "--port", "sim://mecanum4", "--surface", "wood,carpet", "--out", str(tmp_path)]
    assert calibration_cli.run(build_parser().parse_args(port), ask=lambda prompt: "") == 0
    out = capsys.readouterr().out
    assert "check: mean abs error of the accuracy check: wood 4.0 % -> 1.0 %, carpet 32.0 % -> 5.5 %" in out
    assert "average over the floors: wood 4.0 % -> 16.5 %, carpet 32.0 % -> 5.5 %: not kept" in out
    assert f"calibration: {cal} (tables per floor: wood, carpet;" in out
    loaded = load_calibration(cal)
    assert loaded.calibration is None and "not kept" in cal.read_text()
    assert (loaded.for_surface("wood").k, loaded.for_surface("carpet").k) == (150.0, 190.0)
    with pytest.raises(ConfigError, match="say which floor the robot is on"):
        loaded.for_surface(None)
    # the board keeps the tables of the floor it stands on at the end: carpet's
    assert [spec.k for spec in fake_calibration["uploads"]] == [190.0]
    assert "controller: carpet's tables uploaded (CAL)" in out


def test_an_average_better_than_none_everywhere_is_the_files_calibration(
    tmp_path: Path, fake_calibration: dict[str, Any], capsys: pytest.CaptureFixture[str]
) -> None:
    fake_calibration["result"] = two_floors([-0.02, 0.01])
    assert main(["calibrate", "--surface", "wood,carpet", "--out", str(tmp_path)]) == 0
    assert "carpet 32.0 % -> 5.5 %: kept as the file's calibration" in capsys.readouterr().out
    loaded = load_calibration(tmp_path / "calibration.yaml")
    assert loaded.calibration is not None and loaded.calibration.k == 170.0


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
    assert main(["demo", "--port", "sim://omni4?world=empty", "--out", str(tmp_path)]) == 1
    out = capsys.readouterr().out
    assert "NO emergency stop, no echo: nothing ahead of the robot" in out
    assert out.rstrip().endswith("NOT DONE: sonar approach, emergency stop")
    harness.assert_left_as_found()


def test_a_calibration_without_matplotlib_keeps_its_report_and_file(
    tmp_path: Path,
    fake_calibration: dict[str, Any],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The figures need the [plots] extra; the tables, the raw runs and the calibration file do not:
    a run of many minutes on a board with ``[control]`` only is not lost at its end."""
    monkeypatch.setattr("omnibot.calibration.report.write_report", real_write_report)
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    made = result([-0.03, 0.05], [-0.01, 0.01])
    fit: dict[str, Any] = dict(deadbands={}, balance=None, rollers=None, coast=None, anchors={}, points={})
    made.sessions[0].fit = cast(
        Any, SimpleNamespace(**fit, k=150.0, move_length=1.0)
    )  # what the report reads
    fake_calibration["result"] = made
    cal = tmp_path / "cal.yaml"
    assert main(_calibrate_argv(tmp_path, cal)) == 0
    out = capsys.readouterr().out
    assert f"report: {tmp_path / 'r'} (accuracy.md, accuracy.json, runs.json)" in out
    assert "report: figures left out: 'matplotlib' is not installed" in out and "omnibot[plots]" in out
    assert sorted(p.name for p in (tmp_path / "r").iterdir()) == ["accuracy.json", "accuracy.md", "runs.json"]
    assert cal.exists()
