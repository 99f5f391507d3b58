"""``--scanner`` on the bridge: one per robot or none, and a robot without a scanner is refused in one
line before any DDS participant is made."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from omnibot.cli import main
from omnibot.robot.description import PRESET_DIR
from tests.cli.conftest import assert_one_line_error


def test_several_robots_take_one_scanner_each_or_none(capsys: pytest.CaptureFixture[str]) -> None:
    two = ["--port", "sim://omni4", "--namespace", "r1", "--port", "sim://omni3", "--namespace", "r2"]
    assert main(["ros2", *two, "--scanner", "/dev/ttyUSB1"]) == 2
    err = capsys.readouterr().err
    assert "2 robots (--port) but 1 --scanner" in err
    assert_one_line_error(err)


def test_a_robot_without_a_scanner_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = yaml.safe_load((PRESET_DIR / "omni4.yaml").read_text())
    del spec["scanner"]
    bare = tmp_path / "bare.yaml"
    bare.write_text(yaml.safe_dump(spec))
    argv = [
        "ros2",
        "--port",
        "sim://omni4",
        "--robot",
        str(bare),
        "--scanner",
        "/dev/null",
        "--duration",
        "1",
    ]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "has no scanner" in err and "--scanner" in err
    assert_one_line_error(err)
