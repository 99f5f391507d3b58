"""The bridge on a runtime (:func:`omnibot.ros2.assembly.attach`): a robot without a scanner given a
scanner device is refused in one line before any DDS participant is made."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from omnibot.cli import main
from omnibot.robot.description import PRESET_DIR
from tests.cli.conftest import assert_one_line_error


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
