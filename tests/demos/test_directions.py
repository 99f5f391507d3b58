"""Seed 003's main directions on the simulated presets."""

from __future__ import annotations

from pathlib import Path

import pytest

from omnibot.cli import main
from omnibot.demos.directions import run_direction, wheel_pattern
from omnibot.robot import load_robot


def test_mecanum4_wheel_patterns_are_seed003s() -> None:
    robot = load_robot("mecanum4")
    assert wheel_pattern(robot, (1, 0, 0), 200) == [200, 200, 200, 200]  # Fig. 4(a): all forward
    assert wheel_pattern(robot, (0, 1, 0), 200) == [-200, 200, -200, 200]
    assert wheel_pattern(robot, (1, 1, 0), 200) == [0, 200, 0, 200]  # diagonal: one pair idle


@pytest.mark.parametrize("preset", ["omni4", "mecanum4"])
@pytest.mark.parametrize(
    ("name", "twist", "direction"), [("forward", (1, 0, 0), 0.0), ("left", (0, 1, 0), 90.0)]
)
def test_symmetric_robots_go_where_they_are_sent(
    preset: str, name: str, twist: tuple[float, float, float], direction: float
) -> None:
    run = run_direction(load_robot(preset), name, twist, power=180, duration=0.5, surface="wood", seed=0)
    assert run.commanded_deg == direction
    assert run.achieved_deg == pytest.approx(direction, abs=2.0)
    assert run.distance > 0.2
    assert abs(run.heading_change_deg) < 2.0


def test_rotation_turns_in_place() -> None:
    run = run_direction(
        load_robot("omni4"), "rotate ccw", (0, 0, 1), power=150, duration=0.5, surface="wood", seed=0
    )
    assert run.commanded_deg is None and run.heading_change_deg > 45 and run.distance < 0.01


def test_tour_cli_writes_plots(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "new" / "out"  # made when the plot is written
    assert main(["tour", "--robot", "omni4", "--duration", "0.3", "--out", str(out)]) == 0
    assert (out / "directions_omni4.png").stat().st_size > 10_000
    said = capsys.readouterr().out
    assert "forward-left" in said and "rotate cw" in said


def test_tour_bad_input(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tour", "--surface", "ice"]) == 2
    assert "unknown surface 'ice'" in capsys.readouterr().err
    assert main(["tour", "--power", "300"]) == 2
    assert "--power" in capsys.readouterr().err
