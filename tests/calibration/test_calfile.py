"""The calibration file's reach: written, read back, and a file from before it (no reach); a file
edited by hand that gives a key twice is refused; the fold marker of a mecanum file, and older mecanum
files moved onto the x axis or refused; the slip fit's residual, read for the SLAM's odometry model."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from omnibot.calibration.calfile import (
    describe_spec,
    dumps,
    floor_calibration,
    load_calibration,
    merge_calibration,
    parse_calibration,
)
from omnibot.errors import ConfigError
from omnibot.estimation import SlipError
from omnibot.robot import ReachSpec, load_robot
from tests.calibration.conftest import sim_client

DATA = Path(__file__).resolve().parents[1] / "data"
OLD = DATA / "omni4_acceptance_wood_calibration.yaml"
"""A calibration file written before the reach (2026-12-02)."""


def test_the_reach_round_trips(tmp_path: Path) -> None:
    spec = load_calibration(OLD).for_surface("wood")
    reach = ReachSpec(courses_deg=(0.0, 15.0, 30.0, 45.0), speed=(1.0, 0.76, 0.63, 0.76))
    doc = {
        "robot": "omni4",
        "surfaces": {"wood": {"calibration": describe_spec(spec.model_copy(update={"reach": reach}))}},
    }
    path = tmp_path / "cal.yaml"
    path.write_text(dumps(doc), encoding="utf-8")
    assert (
        "reach:\n        courses_deg: [0.0, 15.0, 30.0, 45.0]\n        speed: [1.0, 0.76, 0.63, 0.76]\n"
        in path.read_text()
    )
    back = load_calibration(path).for_surface("wood")
    assert back.reach == reach and back.model_copy(update={"reach": None}) == spec


def test_a_file_without_the_reach_loads_and_clears_the_controllers() -> None:
    """An older file has no reach: it loads as before, and its upload leaves the controller without one
    (CAL,8,0,0,0), so every MOVE runs as asked, as before the reach, whatever an earlier upload held."""
    assert "reach" not in yaml.safe_load(OLD.read_text())["surfaces"]["wood"]["calibration"]
    spec = load_calibration(OLD).for_surface("wood")
    assert spec.reach is None
    robot = load_robot("omni4")
    with sim_client(robot, "wood") as client:
        cal = client.link.device.controller.calibration  # type: ignore[attr-defined]
        reach = ReachSpec(courses_deg=(0.0, 45.0), speed=(0.5, 0.4))
        client.upload_calibration(spec.model_copy(update={"reach": reach}))
        assert cal.reach_at(0.0) == 50.0 and client.takes_reach
        sent = client.upload_calibration(spec)
        assert sent[-1].params() == (8, 0, 0, 0) and cal.reach_at(0.0) == 0.0


@pytest.mark.parametrize(
    ("reach", "message"),
    [
        ({"courses_deg": [0.0, 45.0], "speed": [0.9]}, "same, non-zero length"),
        ({"courses_deg": [30.0, 15.0], "speed": [0.9, 0.8]}, "increase strictly"),
        ({"courses_deg": [0.0, 120.0], "speed": [0.9, 0.8]}, "within 0..90"),
        ({"courses_deg": [0.0], "speed": [0.0]}, "speeds must be > 0"),
        ({"courses_deg": [0.0], "speeds": [0.9]}, r"calibration\.reach\.speeds: unknown key"),
    ],
)
def test_bad_reach_is_a_one_line_error(reach: dict[str, list[float]], message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        parse_calibration({"calibration": {"k": 150.0, "reach": reach}})


def test_a_key_given_twice_is_refused_naming_its_place_and_lines(tmp_path: Path) -> None:
    """A hand edit that adds a line instead of changing one: ``k`` again under wood's calibration."""
    lines = OLD.read_text().splitlines()
    wood = lines.index("  wood:")
    k = next(i for i in range(wood, len(lines)) if lines[i].startswith("      k: "))
    lines.insert(k + 1, "      k: 150.0")
    path = tmp_path / "cal.yaml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        load_calibration(path)
    assert str(info.value) == (
        f"invalid calibration file {path}: surfaces.wood.calibration.k: duplicate key on line {k + 2} "
        f"(first on line {k + 1})"
    )
    path.write_text(OLD.read_text() + "robot: omni3\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r": robot: duplicate key on line \d+ \(first on line 9\)$"):
        load_calibration(path)


OLD_MECANUM = """\
robot: mecanum4
surfaces:
  carpet:
    calibration:
      k: 118.8
      k_l:
        courses_deg: [0.0, 45.0]
        curves:
        - {x: [10, 100, 255], y: [3.0, 1.5, 1.2]}
        - {x: [10, 100, 255], y: [4.0, 2.0, 1.6]}
      reach: {courses_deg: [0.0, 45.0], speed: [0.4, 0.6]}
    odometry: {slip: {roll: 0.01, compliance: 0.0}}
"""
"""A mecanum4 file from before the fold marker: courses from the diagonals (0: a diagonal, 45:
forward and sideways on one curve)."""


def test_an_old_mecanum_file_is_moved_onto_the_x_axis(tmp_path: Path) -> None:
    path = tmp_path / "old.yaml"
    path.write_text(OLD_MECANUM, encoding="utf-8")
    robot = load_robot("mecanum4")
    raw = load_calibration(path).for_surface("carpet")
    assert raw.fold_axes_deg is None  # as written: the idle axes
    tables, _ = floor_calibration(path, robot, "carpet")
    assert tables is not None and tables.k_l is not None and tables.reach is not None
    assert tables.fold_axes_deg == (0.0,)
    assert tables.k_l.courses_deg == (0.0, 45.0, 90.0)
    assert [c.y[0] for c in tables.k_l.curves] == [4.0, 3.0, 4.0]  # forward, diagonal, sideways
    assert tables.reach.speed == (0.6, 0.4, 0.6)
    merged = yaml.safe_load(merge_calibration("mecanum4", path, "carpet"))
    assert merged["calibration"]["fold_axes_deg"] == [0.0]
    assert merged["calibration"]["k_l"]["courses_deg"] == [0.0, 45.0, 90.0]


def test_a_mecanum_file_that_cannot_be_moved_is_refused(tmp_path: Path) -> None:
    curves = "".join(f"        - {{x: [10, 255], y: [{2 + i / 10:.1f}, 1.0]}}\n" for i in range(8))
    text = OLD_MECANUM.replace("courses_deg: [0.0, 45.0]\n", "courses_deg: [0, 5, 10, 15, 20, 30, 40, 45]\n")
    text = text.replace(
        "        - {x: [10, 100, 255], y: [3.0, 1.5, 1.2]}\n        - {x: [10, 100, 255], y: [4.0, 2.0, 1.6]}\n",
        curves,
    )
    path = tmp_path / "old.yaml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(
        ConfigError, match=r"old.yaml: fold_axes_deg: .*\[45, 135\].*\[0\].*calibrate the robot again"
    ):
        floor_calibration(path, load_robot("mecanum4"), "carpet")


def test_a_mecanum_section_writes_its_fold_marker(tmp_path: Path) -> None:
    spec = load_robot("mecanum4").calibration
    assert spec is not None
    path = tmp_path / "cal.yaml"
    path.write_text(dumps({"robot": "mecanum4", "calibration": describe_spec(spec)}), encoding="utf-8")
    assert "fold_axes_deg: [0.0]" in path.read_text()
    assert load_calibration(path).for_surface(None) == spec


def test_the_slip_fits_residual_is_read_for_its_floor(tmp_path: Path) -> None:
    path = tmp_path / "cal.yaml"
    path.write_text(
        OLD_MECANUM.replace(
            "    odometry: {slip: {roll: 0.01, compliance: 0.0}}",
            "    odometry: {slip: {roll: 0.01, compliance: 0.0}, error: {rms: 0.0012, max: 0.0021, runs: 16}}",
        )
    )
    cal = load_calibration(path)
    assert cal.slip_error_for("carpet") == SlipError(0.0012, 0.0021, 16) == cal.slip_error_for(None)
    with pytest.raises(ConfigError, match="no wheel-slip calibration for surface 'wood'"):
        cal.slip_error_for("wood")


def test_a_file_without_the_residual_or_with_a_bad_one_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "old.yaml"
    path.write_text(OLD_MECANUM)  # the slip fit, from before its residual was written
    cal = load_calibration(path)
    assert cal.slip_for("carpet").roll == 0.01  # what reads only the fit loads it as before
    with pytest.raises(ConfigError, match=r"surfaces\.carpet\.odometry has wheel slip but no 'error'"):
        cal.slip_error_for(None)
    path.write_text(
        OLD_MECANUM.replace(
            "    odometry: {slip: {roll: 0.01, compliance: 0.0}}",
            "    odometry: {slip: {roll: 0.01, compliance: 0.0}, error: {rms: 0.0012, runs: 16}}",
        )
    )
    with pytest.raises(
        ConfigError, match=r"surfaces\.carpet\.odometry\.error: expected a mapping with exactly rms"
    ):
        load_calibration(path)
