"""Exploring the room until no frontier is left (lockstep)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from omnibot.cli import main
from omnibot.navigation.explore import exploring_speed
from omnibot.robot import load_robot


def test_the_robot_explores_at_4_cm_per_scan() -> None:
    assert exploring_speed(load_robot("omni4")) == pytest.approx(0.4)  # its A1 turns at 10 Hz
    assert exploring_speed(load_robot("omni3")) == pytest.approx(0.4)


@pytest.mark.timeout(600)  # about 40 s of one core: 43 s simulated at the exploring speed
def test_explore_maps_the_room_by_itself(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    assert (
        main(["map", "--explore", "--world", "room", "--seed", "1", "--duration", "120", "--out", str(out)])
        == 0
    )
    said = capsys.readouterr().out
    assert "exploring ended: no frontier left" in said, said
    report = json.loads((out / "report.json").read_text())
    assert report["map"]["precision"] >= 0.95 and report["map"]["recall"] >= 0.95
    assert report["trajectory"]["estimate"]["ape_rmse_m"] <= 0.03
