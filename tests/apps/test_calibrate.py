"""``omnibot calibrate``: a quick end-to-end run and the errors that exit 2 without a traceback."""

from __future__ import annotations

import io
import json
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from omnibot.apps import calibrate as calibration_cli
from omnibot.apps.calibrate_robots import asked_stand
from omnibot.calibration import (
    ACCEPTANCE,
    load_calibration,
    merge_calibration,
    parse_perturbation,
    perturbed_robot,
)
from omnibot.calibration.accuracy import AccuracyRow
from omnibot.calibration.calfile import parse_calibration
from omnibot.calibration.verdict import NOISE_ROTATE, ROTATE, part_errors
from omnibot.cli import main
from omnibot.errors import ConfigError
from omnibot.robot import RobotDescription, load_robot


class RecordingBar:
    """Stands in for the terminal's progress bar: the runs counted and every total it was given."""

    def __init__(self, total: int) -> None:
        self.n, self.total, self.totals = 0, total, [total]

    def update(self, n: float | None = 1) -> None:
        self.n += int(n or 0)

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        pass

    def refresh(self) -> None:
        self.totals.append(self.total)


@pytest.mark.timeout(600)  # CPU-bound (lockstep simulation): passed the 120 s hang guard beside other suites
def test_quick_run_writes_the_file_and_the_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    bars: dict[str, RecordingBar] = {}

    @contextmanager
    def progress(desc: str, total: int) -> Iterator[RecordingBar]:
        bars[desc] = RecordingBar(total)
        yield bars[desc]

    monkeypatch.setattr(calibration_cli, "tqdm_progress", progress)
    out, report = tmp_path / "cal.yaml", tmp_path / "report"
    # the acceptance robot (tyres +5 %, motors +-10 %) gives the calibration something to correct; with
    # the tyres alone the quick plan's tables were no better than the nominal ones, and were refused.
    # Better on the whole (2.7 -> 0.8 %), these make ROTATE worse (2.0 -> 3.1 %, issue 24): refused,
    # so --force writes them, marked (with the firmware's optional dithering, pwm_dither, ROTATE went
    # 1.0 -> 1.9 % and they were written)
    argv = ["calibrate", "--quick", "--surface", "wood", "--perturb", "acceptance", "--out", str(out)]
    assert main([*argv, "--report", str(report), "--force"]) == 1
    text = capsys.readouterr().out
    assert "before, wood" in text and "after (wood calibration), wood" in text
    assert "worse than before: wood: ROTATE: " in text and "written anyway, --force" in text
    assert out.read_text().startswith("# WORSE THAN BEFORE: wood: ROTATE: ")
    cal = load_calibration(out)
    assert cal.robot == "omni4" and list(cal.surfaces) == ["wood"]
    assert cal.calibration == cal.for_surface("wood")  # one floor: its tables are the file's
    assert (
        cal.calibration is not None
        and cal.calibration.k_l is not None
        and cal.calibration.k_l.courses_deg == (0.0, 45.0)
    )
    assert cal.gyro is not None and cal.odometry is not None
    assert cal.odometry["rotation_scale"] == pytest.approx(1.05, abs=0.01)
    # the floor's wheel slip for driven-wheel odometry (what omnibot follow --calibration applies)
    assert "wheel slip (wood): roll 0.0" in text
    slip = cal.slip_for("wood")
    assert 0.0 < slip.roll < 0.01 and cal.slip_for(None) == slip
    assert slip.scale == pytest.approx(1.05, abs=0.01)  # the true wheels are 5 % larger
    error = cal.slip_error_for("wood")  # the fit's residual over its runs (the SLAM's odometry model)
    assert 0.0 < error.rms <= error.max < 0.01 and error.runs >= 2
    assert f"ramp {slip.ramp:.5f} s^3/m, scale {slip.scale:.4f};" in text
    assert "## Wheel slip (driven-wheel odometry)" in (report / "accuracy.md").read_text()
    assert "| ramp (s^3/m) | scale |" in (report / "accuracy.md").read_text()
    for name in ("fig5_rates.png", "fig6_kt_kr.png", "fig7_kl.png", "accuracy.png", "accuracy.md"):
        assert (report / name).stat().st_size > 0
    data = json.loads((report / "accuracy.json").read_text())
    assert {"before, wood", "after (wood calibration), wood"} <= set(data)
    runs = json.loads((report / "runs.json").read_text())
    # the bar ends counting every run really driven, from an estimate within a fifth of it
    bar = bars["calibrate omni4 on wood"]
    assert bar.n == bar.total == len(runs["surfaces"]["wood"]["runs"])
    assert abs(bar.totals[0] / bar.n - 1) < 0.2
    first_power = next(r for r in runs["surfaces"]["wood"]["runs"] if r["group"].startswith("deadband"))
    assert first_power["command"] == "POWER,500,8,8,8,8"  # rotation's dead band first, from 8 counts
    motors = cal.calibration.motors
    assert motors is not None and len(motors.offset) == 4 and all(o > 20 for o in motors.offset)
    # the file merges into the description it was made for
    merged = merge_calibration("omni4", out)
    assert "k_l:" in merged and f"k: {cal.calibration.k}" in merged


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--surface", "crapet"], "did you mean 'carpet'"),
        (["--truth", "lazer"], "unknown truth strategy"),
        (["--port", "sim://omni4", "--perturb", "radius=1.1"], "need the simulator"),
        (["--perturb", "radius=1.1;torque=1.2"], "did you mean 'torque_constant'"),
        (["--perturb", "radius=1,2"], "one per wheel"),
        (["--courses", "0,60"], "within 0..45"),
        (["--courses", "a,b"], "comma-separated degrees"),
        (["--robot", "omni5"], "unknown robot"),
        (["--move-length", "0"], "positive length"),
    ],
)
def test_bad_input_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    code = main(["calibrate", "--out", str(tmp_path / "c.yaml"), "--report", str(tmp_path / "r"), *args])
    err = capsys.readouterr().err
    assert code == 2
    assert message in err and "Traceback" not in err


def test_perturbation(omni4: RobotDescription) -> None:
    robot = perturbed_robot(omni4, ACCEPTANCE)
    assert [w.radius for w in robot.wheels] == pytest.approx([0.02625] * 4)
    assert [w.motor.torque_constant for w in robot.wheels] == pytest.approx([0.0066, 0.0054, 0.0054, 0.0066])
    assert robot.calibration == omni4.calibration
    assert parse_perturbation(" deadband = 2 ", 4) == {"deadband": [2.0] * 4}
    with pytest.raises(ConfigError, match="key=value"):
        parse_perturbation("radius", 4)


def test_calibration_file_errors(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"calibration\.k: Input should be greater than 0"):
        parse_calibration({"calibration": {"k": -1}})
    with pytest.raises(ConfigError, match=r"calibration\.kk: unknown key"):
        parse_calibration({"calibration": {"k": 100, "kk": 1}})
    with pytest.raises(ConfigError, match="unknown key"):
        parse_calibration({"calibraton": {"k": 100}})
    bare = parse_calibration({"k": 150.0, "k_t": {"x": [0, 255], "y": [1.2, 1.2]}})
    assert bare.for_surface(None).k == 150.0
    with pytest.raises(ConfigError, match="no calibration for surface 'wood'"):
        bare.for_surface("wood")
    with pytest.raises(ConfigError, match="one entry per motor"):
        parse_calibration({"calibration": {"k": 100, "motors": {"offset": [30.0], "gain": []}}})
    with pytest.raises(ConfigError, match="offsets must be >= 0"):
        parse_calibration(
            {"calibration": {"k": 100, "motors": {"offset": [-3], "gain": [{"x": [0], "y": [1]}]}}}
        )
    # the motor model's speed terms: optional (files without them load as before), one per motor
    flat = [{"x": [0], "y": [1.0]}] * 2
    old = parse_calibration({"calibration": {"k": 100, "motors": {"offset": [30.0, 31.0], "gain": flat}}})
    motors = old.for_surface(None).motors
    assert motors is not None and motors.speed is None and motors.speed_term(1) == 0.0
    new: dict[str, Any] = {"k": 100, "motors": {"offset": [30.0, 31.0], "gain": flat, "speed": [21.6, -23.9]}}
    motors = parse_calibration({"calibration": new}).for_surface(None).motors
    assert motors is not None and motors.speed == (21.6, -23.9)
    for speed, message in (
        ([1.0], "speed needs one entry per motor"),
        ([1.0, 5000.0], "speed terms must lie within"),
        (["fast", 1.0], r"calibration\.motors\.speed\.0: Input should be a valid number"),
        ([1.0, ".nan"], "speed"),
    ):
        with pytest.raises(ConfigError, match=message):
            parse_calibration({"calibration": {**new, "motors": {**new["motors"], "speed": speed}}})
    bad = tmp_path / "bad.yaml"
    bad.write_text("calibration: [", encoding="utf-8")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_calibration(bad)
    # a preset's own calibration section is a valid calibration file
    preset = load_robot("omni4")
    assert preset.calibration is not None
    assert parse_calibration(
        {"calibration": preset.calibration.model_dump(exclude_none=True)}
    ).calibration == (preset.calibration)


def test_a_real_robot_is_asked_onto_the_stand_and_back() -> None:
    """The motor map's stand test on a robot without a simulator behind its link: the person lifts
    it (every wheel off the floor) and puts it back (``--yes``: nobody is asked, no speed terms)."""
    prompts: list[str] = []

    def ask(prompt: str) -> str:
        prompts.append(prompt)
        return ""

    lift = asked_stand(ask)
    lift(None, True)  # type: ignore[arg-type]
    lift(None, False)  # type: ignore[arg-type]
    assert prompts[0].startswith("Lift the robot onto a stand") and "back on the floor" in prompts[1]


@pytest.mark.timeout(600)  # CPU-bound, deterministic: 87 s beside two busy loops
def test_a_port_with_two_floors_asks_between_them(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from omnibot.apps.calibrate import run
    from omnibot.cli import build_parser

    prompts: list[str] = []
    files = ["--out", str(tmp_path / "cal.yaml"), "--report", str(tmp_path / "r")]
    port = [
        "--port",
        "sim://omni4?surface=wood",
        "--surface",
        "lab,hall",
        "--quick",
        "--no-check",
        "--no-motor-map",
        "--no-rollers",
    ]
    args = build_parser().parse_args(["calibrate", *port, *files])

    def ask(prompt: str) -> str:
        prompts.append(prompt)
        return ""

    assert run(args, ask=ask) == 0
    assert [p.split(" with")[0] for p in prompts] == ["Put the robot on lab", "Put the robot on hall"]
    cal = load_calibration(tmp_path / "cal.yaml")
    assert list(cal.surfaces) == ["lab", "hall"]  # the same floor twice here: nearly the same tables
    assert cal.calibration is not None  # no check (--no-check): the average is kept unjudged
    assert cal.calibration.motors is None and cal.calibration.rollers is None
    assert set(cal.slip) == {"lab", "hall"}
    assert cal.surfaces["lab"].k == pytest.approx(cal.surfaces["hall"].k, rel=0.05)
    assert "truth sim" in capsys.readouterr().out


class NotATerminal(io.StringIO):
    """Standard input from a pipe or /dev/null: empty, and not a terminal."""

    def isatty(self) -> bool:
        return False


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--port", "sim://omni4"], "needs a terminal to ask you to put the robot on floor"),
        (
            ["--truth", "tape", "--surface", "wood"],
            "needs a terminal to ask you to measure every run (tape truth)",
        ),
        (["--port", "sim://omni4", "--yes", "--truth", "tape"], "measure every run"),
        (["--port", "sim://omni4", "--yes", "--surface", "lab,hall"], "--yes: several surfaces need someone"),
        (["--yes"], "--yes: only for a robot on --port"),
    ],
)
def test_an_operator_is_asked_for_only_on_a_terminal(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    args: list[str],
    message: str,
) -> None:
    """Refused in one line before anything moves, instead of an EOFError half-way."""
    monkeypatch.setattr(sys, "stdin", NotATerminal())
    code = main(
        [
            "calibrate",
            "--quick",
            "--calibration",
            str(tmp_path / "c.yaml"),
            "--out",
            str(tmp_path / "r"),
            *args,
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1
    assert not (tmp_path / "c.yaml").exists()


def test_yes_runs_unattended_on_a_port(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(sys, "stdin", NotATerminal())
    port = ["--port", "sim://omni4?surface=wood", "--yes", "--quick", "--no-check", "--no-motor-map"]
    skip = ["--no-rollers", "--no-slip"]
    files = ["--out", str(tmp_path / "cal.yaml"), "--report", str(tmp_path / "r")]
    assert main(["calibrate", *port, *skip, *files]) == 0
    assert "omni4 on floor (truth sim)" in capsys.readouterr().out
    assert list(load_calibration(tmp_path / "cal.yaml").surfaces) == ["floor"]


def test_the_terminal_ending_is_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    from omnibot.apps.calibrate_robots import terminal_ask

    monkeypatch.setattr(sys, "stdin", NotATerminal())
    with pytest.raises(ConfigError, match="standard input ended while asking: 'Put the robot on lab'"):
        terminal_ask("Put the robot on lab ")


def test_a_file_of_floors_without_an_average_names_them() -> None:
    """Several floors whose average was worse than none: each keeps its tables, none is for every
    floor, and asking for that says which there are."""
    cal = parse_calibration({"robot": "omni4", "surfaces": {"wood": {"calibration": {"k": 150.0}}}})
    assert cal.calibration is None and cal.for_surface("wood").k == 150.0
    with pytest.raises(ConfigError, match=r"tables for each floor \(wood\).*say which floor"):
        cal.for_surface(None)
    with pytest.raises(ConfigError, match="no 'calibration' section"):
        parse_calibration({"robot": "omni4", "surfaces": {}})


@pytest.mark.timeout(1800)  # CPU-bound (lockstep simulation): about 70 s alone, 6-15 min on a loaded machine
def test_the_default_run_on_omni4_improves_every_part_and_exits_0(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The default command on seed 000's own robot (omni4, wood and carpet, seed 1): each floor's tables
    better than before on the whole and on every course, ROTATE not worse (the verdict's margin), so
    the file is written and the command exits 0. Before the rotation curve started where its levels
    say, issue 24's verdict refused them: ROTATE 1.6 -> 3.6 % (90 degrees at 90 degrees/s -0.6 ->
    -5.2 %: 61 counts where it needs 62). Measured now: ROTATE 1.6 -> 1.3 % on wood, 1.8 -> 2.5 % on
    carpet (at 90 degrees/s one PWM count is 4.7 % of the rate; carpet's offsets, 41.9 and 42.1,
    give two motors 61 counts and two 62: -3.1 %). With the rate curve's first count (2026-12-06
    19:30): ROTATE 1.6 -> 1.3 % on wood, 1.8 -> 1.3 % on carpet."""
    out = tmp_path / "out"
    assert main(["calibrate", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "worse than before" not in text and "calibration: " + str(out / "calibration.yaml") in text
    summary = {k: v["summary"] for k, v in json.loads((out / "accuracy.json").read_text()).items()}
    for floor in ("wood", "carpet"):
        before, after = summary[f"before, {floor}"], summary[f"after ({floor} calibration), {floor}"]
        assert after["distance_mean"] < 0.25 * before["distance_mean"], floor
        assert after["rotate_mean"] < before["rotate_mean"] + NOISE_ROTATE, floor
    assert summary["after (wood calibration), wood"]["rotate_mean"] < summary["before, wood"]["rotate_mean"]
    cal = load_calibration(out / "calibration.yaml")
    assert list(cal.surfaces) == ["wood", "carpet"]


@pytest.mark.timeout(2400)  # CPU-bound (lockstep simulation): about 160 s alone, 12 min on a loaded machine
def test_the_default_run_on_mecanum4_improves_every_course_and_exits_0(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The default command on mecanum4 (wood and carpet, seed 1, courses 0..90 every 15 degrees, issue
    24): on each floor every course of the check, both ways, lands closer with the floor's own tables
    than with the preset's, ROTATE is not worse (the verdict's margin), the file is written and the
    command exits 0. Before the rate curve started at its first count's speed it exited 1: wood's
    ROTATE 1.4 -> 3.0 % (90 degrees at 90 degrees/s +0.4 -> -4.0 %: 66.45 counts asked, 66 sent).
    Measured (2026-12-06 19:30, the firmware rounding its powers): wood 15.5 -> 0.4 %, ROTATE 1.4 ->
    1.2 %; carpet 48.3 -> 1.4 %, ROTATE 38.2 -> 1.9 %; every course better on both floors. With carpet
    at 1.8x wood's roller drag (f88055f): wood the same, carpet 20.3 -> 0.6 %, ROTATE 11.0 -> 2.3 %."""
    out = tmp_path / "out"
    assert main(["calibrate", "--robot", "mecanum4", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "worse than before" not in text and "calibration: " + str(out / "calibration.yaml") in text
    checks = json.loads((out / "accuracy.json").read_text())
    courses = [f"course {c}/{c + 180} deg" for c in range(0, 91, 15)]
    for floor in ("wood", "carpet"):
        before, after = (
            part_errors([AccuracyRow(**r) for r in checks[name]["rows"]])
            for name in (f"before, {floor}", f"after ({floor} calibration), {floor}")
        )
        assert sorted(before) == sorted(after) == sorted([*courses, ROTATE]), floor
        for course in courses:  # the per-course table: every course both ways closer than before
            assert after[course] < before[course], (floor, course, before[course], after[course])
        assert after[ROTATE] < before[ROTATE] + NOISE_ROTATE, floor
    cal = load_calibration(out / "calibration.yaml")
    assert list(cal.surfaces) == ["wood", "carpet"]
    assert all(cal.for_surface(s).fold_axes_deg == (0.0,) for s in cal.surfaces)
