"""``omnibot robot`` and ``omnibot kinematics``, called through ``main(argv)``."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from omnibot.cli import main
from omnibot.robot import load_robot


def test_kinematics_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["kinematics", "--robot", "omni4", "--twist", "0.5,0,1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    expected = load_robot("omni4").wheel_matrix @ [0.5, 0, 1]
    np.testing.assert_allclose(out["wheel_speeds"], expected)
    assert out["wheel_names"] == ["m1", "m2", "m3", "m4"]


def test_kinematics_negative_twist_and_forward(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["kinematics", "--robot", "mecanum4", "--twist=-0.2,0.1,0", "--json"]) == 0
    speeds = json.loads(capsys.readouterr().out)["wheel_speeds"]
    assert main(["kinematics", "--robot", "mecanum4", "--wheels", ",".join(map(str, speeds)), "--json"]) == 0
    np.testing.assert_allclose(json.loads(capsys.readouterr().out)["twist"], [-0.2, 0.1, 0], atol=1e-12)


def test_robot_show_and_list(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["robot", "show", "omni3"]) == 0
    out = capsys.readouterr().out
    assert "omni3" in out and "w3" in out and "inverse kinematics" in out
    assert main(["robot", "list"]) == 0
    assert capsys.readouterr().out.count("\n") == 3


def test_robot_urdf_to_file(tmp_path: Path) -> None:
    out = tmp_path / "omni4.urdf"
    assert main(["robot", "urdf", "omni4", "-o", str(out)]) == 0
    assert ET.parse(out).getroot().get("name") == "omni4"


@pytest.mark.parametrize(
    "twist",
    [
        ["--twist", "-0.2", "0.1", "0"],
        ["--twist", "-0.2,0.1,0"],
        ["--twist=-0.2,0.1,0"],
        ["--twist", "-0.2,", "0.1,", "0"],
        ["--twist", "-2e-1", "1e-1", "-0"],
    ],
)
def test_negative_numbers_are_values_in_every_form(
    twist: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["kinematics", "--robot", "mecanum4", *twist, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["twist"] == [-0.2, 0.1, 0.0]
    wheels = [f"{v:.12g}" for v in out["wheel_speeds"]]  # back again
    assert wheels[0].startswith("-")  # the first value is negative: the case argparse refused
    for form in (wheels, [",".join(wheels)]):
        assert main(["kinematics", "--robot", "mecanum4", "--wheels", *form, "--json"]) == 0
        np.testing.assert_allclose(json.loads(capsys.readouterr().out)["twist"], [-0.2, 0.1, 0.0], atol=1e-9)
