"""The command line: main(argv) called directly."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from omnibot.cli import main
from omnibot.robot.description import load_robot


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


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["kinematics", "--twist", "1,2"], "--twist: expected 3 comma-separated numbers, got '1,2'"),
        (["kinematics", "--twist", "a,b,c"], "expected 3 comma-separated numbers"),
        (["kinematics", "--twist", "1,nan,0"], "expected 3 comma-separated numbers"),
        (
            ["kinematics", "--twist", "1e308,1e308,0"],
            "--twist: the result overflows (it is not a finite number)",
        ),
        (["kinematics", "--twist", "0,0,1e308", "--json"], "--twist: the result overflows"),
        (["kinematics", "--robot", "omni5"], "unknown robot 'omni5'; did you mean 'omni4'?"),
        (["robot", "show", "nope.yaml"], "cannot read robot description nope.yaml"),
    ],
)
def test_bad_input_is_a_clear_error(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("omnibot: error: ") and message in err
    assert "Traceback" not in err


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
