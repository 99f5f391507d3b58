"""``omnibot map`` on the simulator: the files it writes read by tools we did not write (Pillow,
YAML, evo), its scores against the truth, and one clear line for every bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from evo.tools import file_interface
from PIL import Image

from omnibot.cli import main
from omnibot.control import Path as RobotPath
from omnibot.control import resample, write_path
from omnibot.mapping import load_map
from omnibot.robot.description import PRESET_DIR as PRESETS
from tests.cli.conftest import assert_one_line_error


def loop(tmp_path: Path, corners: list[tuple[float, float]]) -> Path:
    """A closed path through ``corners`` (room frame, m), written as a path file."""
    pts = np.array([*corners, corners[0]], dtype=float)
    path = tmp_path / "loop.csv"
    write_path(resample(RobotPath.from_points(pts, theta=0.0), 0.01), path)
    return path


@pytest.fixture(scope="module")
def mapped(tmp_path_factory: pytest.TempPathFactory) -> tuple[int, Path, str]:
    tmp = tmp_path_factory.mktemp("map")
    path = loop(tmp, [(1.0, 1.0), (2.6, 1.0), (2.6, 2.4), (1.0, 2.4)])
    out = tmp / "out"
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = main(["map", "--path", str(path), "--world", "room", "--seed", "3", "--out", str(out)])
    return status, out, buf.getvalue()


def test_a_path_in_the_room_gives_a_map_trajectories_and_a_scored_report(
    mapped: tuple[int, Path, str],
) -> None:
    status, out, said = mapped
    assert status == 0, said
    assert "follow completed" in said
    for name in (
        "map.yaml",
        "map.pgm",
        "estimate.tum",
        "odometry.tum",
        "truth.tum",
        "report.json",
        "map.png",
    ):
        assert (out / name).is_file(), name
    meta = yaml.safe_load((out / "map.yaml").read_text())
    assert meta["image"] == "map.pgm" and meta["resolution"] == 0.05 and meta["mode"] == "trinary"
    with Image.open(out / "map.pgm") as image:  # map_server reads it with an image library, as here
        pixels = np.asarray(image)
    grid = load_map(out / "map.yaml")
    assert pixels.shape == grid.shape
    assert {0, 254, 205} >= set(np.unique(pixels).tolist())
    assert np.array_equal(pixels[::-1] == 0, grid.data == 100)  # rows top-down in the image
    estimate = file_interface.read_tum_trajectory_file(str(out / "estimate.tum"))
    truth = file_interface.read_tum_trajectory_file(str(out / "truth.tum"))
    assert estimate.num_poses > 50 and truth.num_poses > estimate.num_poses
    report = yaml.safe_load((out / "report.json").read_text())  # JSON is YAML
    assert report["trajectory"]["estimate"]["ape_rmse_m"] < 0.03
    assert report["map"]["precision"] >= 0.9
    assert report["keyframes"] >= 5


def test_the_estimate_is_the_slams_and_starts_at_the_true_pose(mapped: tuple[int, Path, str]) -> None:
    _, out, _ = mapped
    estimate = file_interface.read_tum_trajectory_file(str(out / "estimate.tum"))
    truth = file_interface.read_tum_trajectory_file(str(out / "truth.tum"))
    assert np.allclose(estimate.positions_xyz[0, :2], truth.positions_xyz[0, :2], atol=0.02)
    assert np.allclose(truth.positions_xyz[0, :2], (1.0, 1.0), atol=0.02)  # the path's start: the map frame


def test_bad_input_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    spec = yaml.safe_load((PRESETS / "omni4.yaml").read_text())
    del spec["scanner"]
    bare = tmp_path / "bare.yaml"
    bare.write_text(yaml.safe_dump(spec))
    path = loop(tmp_path, [(1.0, 1.0), (1.5, 1.0)])
    cases: list[tuple[list[str], str]] = [
        (["map", "--path", "nope.csv", "--out", str(tmp_path / "o")], "--path: cannot read nope.csv"),
        (
            ["map", "--teleop", "keyboard", "--scanner", "/dev/null", "--out", str(tmp_path / "o")],
            "--scanner",
        ),
        (["map", "--path", "x.csv", "--resolution", "0", "--out", str(tmp_path / "o")], "--resolution"),
        (["map", "--path", "x.csv", "--hit-range", "-1", "--out", str(tmp_path / "o")], "--hit-range"),
        (["map", "--path", "x.csv", "--off-path", "0", "--out", str(tmp_path / "o")], "--off-path"),
        (
            [
                "map",
                "--path",
                str(path),
                "--robot",
                str(bare),
                "--world",
                "room",
                "--out",
                str(tmp_path / "o"),
            ],
            "has no scanner",
        ),
    ]
    for argv, text in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert text in err, err
        assert_one_line_error(err)


def test_a_path_that_starts_in_a_wall_is_told_as_the_path_given(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--path`` puts the simulated robot at the path's first pose: where it cannot stand, the line
    names the path and that pose, not a sim:// URL the user never wrote."""
    path = loop(tmp_path, [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)])  # (0, 0) is in the room's corner
    assert main(["map", "--path", str(path), "--world", "room", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err == (
        "omnibot: error: --path: start pose (0, 0, 0 deg) overlaps walls[0] of world 'room': the simulated "
        f"robot is put at the first pose of {path}; give a path that starts inside the world\n"
    )
    assert not (tmp_path / "o").exists()
