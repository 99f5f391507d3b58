"""Course folding: the axes K_l's and the reach's courses fold from, and tables moved between them."""

from __future__ import annotations

import pytest

from omnibot.errors import ConfigError
from omnibot.firmware.calibration import Calibration, fold_course
from omnibot.firmware.config import build_config
from omnibot.robot import courses
from omnibot.robot.description import load_robot, parse_description

OLD_MECANUM = {
    "k": 118.8,
    "k_l": {
        "courses_deg": [0, 15, 30, 45],
        "curves": [
            {"x": [10, 100, 255], "y": [5.0, 1.4, 1.2]},
            {"x": [10, 100, 255], "y": [5.2, 1.5, 1.3]},
            {"x": [20, 120, 255], "y": [4.0, 1.6, 1.4]},
            {"x": [10, 100, 255], "y": [6.0, 1.8, 1.5]},
        ],
    },
    "reach": {"courses_deg": [0, 15, 30, 45], "speed": [0.5, 0.6, 0.55, 0.7]},
}
"""A mecanum4 section as files before the fold marker had it: courses from the idle axes (the
diagonals), 0 = a diagonal, 45 = forward and sideways alike."""


def _mecanum(calibration: dict[str, object]) -> dict[str, object]:
    data = load_robot("mecanum4").model_dump(exclude_none=True)
    data["calibration"] = calibration
    return data


@pytest.mark.parametrize(
    ("preset", "axes", "top"),
    [("omni4", [0.0, 90.0], 45.0), ("omni3", [0.0, 60.0, 120.0], 30.0), ("mecanum4", [0.0], 90.0)],
)
def test_course_axes_of_the_presets(preset: str, axes: list[float], top: float) -> None:
    cfg = build_config(load_robot(preset))
    assert cfg["kl_axes"] == axes
    assert courses.fold_max(axes) == top
    assert max(fold_course(c, axes) for c in range(360)) == top


@pytest.mark.parametrize(
    ("course", "folded"), [(0, 0), (45, 45), (90, 90), (135, 45), (180, 0), (-30, 30), (250, 70), (300, 60)]
)
def test_mecanum_courses_fold_by_mirror_symmetry_about_both_axes(course: float, folded: float) -> None:
    """Forward 0, the diagonals 45, sideways 90; 135 is 45 mirrored, 180 is 0 backwards."""
    assert courses.fold(course, [0.0]) == pytest.approx(folded)
    assert fold_course(course, [0.0]) == pytest.approx(folded)


def test_an_old_mecanum_section_is_moved_onto_the_x_axis_exactly() -> None:
    robot = parse_description(_mecanum(OLD_MECANUM))
    cal = robot.calibration
    assert cal is not None and cal.k_l is not None and cal.reach is not None
    assert cal.fold_axes_deg == (0.0,)
    assert cal.k_l.courses_deg == (0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0)
    # forward and sideways (90) both get the old course 45's curve, the diagonal the old course 0's
    assert cal.k_l.curves[0] == cal.k_l.curves[6] and cal.k_l.curves[0].y == (6.0, 1.8, 1.5)
    assert cal.k_l.curves[3].y == (5.0, 1.4, 1.2)
    old = Calibration(
        {
            "k": 118.8,
            "kl_courses": OLD_MECANUM["k_l"]["courses_deg"],  # type: ignore[index]
            "kl_tables": [[c["x"], c["y"]] for c in OLD_MECANUM["k_l"]["curves"]],  # type: ignore[index]
            "kt": [[0], [1.0]],
            "kr": [[0], [1.0]],
            "reach": [[0, 15, 30, 45], [50, 60, 55, 70]],
        }
    )
    cfg = build_config(robot)
    new = Calibration(cfg)
    for course in range(0, 360, 5):
        for power in (5, 10, 15, 55, 100, 110, 200, 255, 300):
            assert new.k_l(power, fold_course(course, cfg["kl_axes"])) == pytest.approx(
                old.k_l(power, fold_course(course, [45.0, 135.0])), abs=1e-9
            )
        assert new.reach_at(fold_course(course, cfg["kl_axes"])) == pytest.approx(
            old.reach_at(fold_course(course, [45.0, 135.0]))
        )


def test_a_section_on_the_robots_axes_is_kept_as_it_is() -> None:
    robot = load_robot("mecanum4")
    assert robot.calibration is not None and robot.calibration.fold_axes_deg == (0.0,)
    assert robot.calibration.k_l is not None and robot.calibration.k_l.courses_deg == (0.0, 45.0, 90.0)
    omni4 = load_robot("omni4")
    assert omni4.calibration is not None and omni4.calibration.fold_axes_deg is None


def test_a_section_that_cannot_be_moved_is_refused_with_a_clear_error() -> None:
    """Eight curves from the diagonals would need fifteen from the x axis: more than the controller holds."""
    many = {
        "k": 118.8,
        "k_l": {
            "courses_deg": [0, 5, 10, 15, 20, 30, 40, 45],
            "curves": [{"x": [10, 255], "y": [2.0 + 0.1 * i, 1.0]} for i in range(8)],
        },
    }
    with pytest.raises(
        ConfigError, match=r"fold_axes_deg.*count from the axes \[45, 135\].*\[0\].*calibrate"
    ):
        parse_description(_mecanum(many))


def test_an_omni_section_marked_with_other_axes_is_refused() -> None:
    """omni4's tables (courses 0 and 45) said to fold from the x axis alone are not a lookup omni4's
    firmware can give (on course 46 they would give course 45's curve, omni4's fold course 44's)."""
    data = load_robot("omni4").model_dump(exclude_none=True)
    data["calibration"]["fold_axes_deg"] = [0.0]
    with pytest.raises(
        ConfigError, match=r"from the axes \[0\] degrees, this robot's from \[0, 90\].*course 46"
    ):
        parse_description(data)


def test_move_curves_reports_where_the_lookups_would_differ() -> None:
    """Onto axes the old lookup is not linear between (a single axis at 10 degrees from two at 0 and
    90): refused, naming a course and a power."""
    curves = [((10.0, 255.0), (2.0, 1.0)), ((10.0, 255.0), (3.0, 1.5))]
    with pytest.raises(ValueError, match=r"course \d+ deg at power"):
        courses.move_curves([0.0, 45.0], curves, [0.0, 90.0], [10.0])
