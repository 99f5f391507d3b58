"""``omnibot record``: teach by pushing (seed 002) or by driving, then repeat."""

from __future__ import annotations

from pathlib import Path as FsPath

import pytest

from omnibot.cli import main
from omnibot.control.paths import read_path


def test_record_by_pushing_then_follow_with_seed002(
    tmp_path: FsPath, capsys: pytest.CaptureFixture[str]
) -> None:
    taught = tmp_path / "taught.csv"
    argv = [
        "record",
        "--path",
        str(taught),
        "--robot",
        "omni3",
        "--shape",
        "line",
        "--size",
        "0.5",
        "--store-speed",
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "pushed by hand along line" in out and "from the true end" in out
    path = read_path(taught)
    assert path.v is not None and path.length == pytest.approx(1.0, abs=0.05)
    assert main(["follow", str(taught), "--robot", "omni3", "--follower", "seed002"]) == 0
    assert "seed002" in capsys.readouterr().out


def test_record_by_driving_and_by_time(tmp_path: FsPath) -> None:
    taught = tmp_path / "driven.csv"
    argv = [
        "record",
        "--path",
        str(taught),
        "--teach",
        "drive",
        "--shape",
        "circle",
        "--size",
        "0.4",
        "--sample-time",
        "0.1",
    ]
    assert main(argv) == 0
    path = read_path(taught)
    assert path.t is not None and path.t[1] == pytest.approx(0.1, abs=0.011)
    assert path.length == pytest.approx(1.26, rel=0.1)
