"""Calibration power patterns and course folding against seed 000's section IV."""

from __future__ import annotations

import pytest

from omnibot.calibration.patterns import Geometry, course_pattern, rotation_pattern, scaled_pattern
from omnibot.calibration.plan import Plan
from omnibot.robot import RobotDescription, load_robot


@pytest.fixture(scope="module")
def geo(omni4: RobotDescription) -> Geometry:
    return Geometry.of(omni4)


def test_seed000_patterns(geo: Geometry) -> None:
    # course 0: two opposite motors at +P and -P, the other two unpowered (m2 +P, m4 -P on omni4)
    assert course_pattern(geo, 0.0, 120) == [0, 120, 0, -120]
    assert course_pattern(geo, 90.0, 120) == [120, 0, -120, 0]
    assert course_pattern(geo, 180.0, 120) == [0, -120, 0, 120]
    # course 45: the same power on all motors, even and odd motors in opposite directions
    p45 = course_pattern(geo, 45.0, 120)
    assert [abs(p) for p in p45] == [120] * 4
    assert p45[0] * p45[2] < 0 and p45[1] * p45[3] < 0
    # rotation: all motors the same direction (positive turns omni4 counter-clockwise)
    assert rotation_pattern(geo, 90) == [90, 90, 90, 90]
    assert rotation_pattern(geo, 90, ccw=False) == [-90, -90, -90, -90]


def test_busiest_motor_gets_the_power(geo: Geometry) -> None:
    for course in (0.0, 10.0, 30.0, 60.0, 135.0, 200.0):
        assert max(abs(p) for p in course_pattern(geo, course, 200)) == 200
    with pytest.raises(ValueError, match="turns"):
        scaled_pattern([0.0, 0.0], 100)


@pytest.mark.parametrize(
    ("preset", "fold_max", "counts"),
    [("omni4", 45.0, (4, 4, 4)), ("omni3", 30.0, (4, 4, 4)), ("mecanum4", 90.0, (2, 4, 2))],
)
def test_fold_range_and_raw_courses(preset: str, fold_max: float, counts: tuple[int, int, int]) -> None:
    """mecanum4 folds from its x axis alone (0..90): forward and sideways are only themselves and
    their opposites, a diagonal its mirror images too."""
    geo = Geometry.of(load_robot(preset))
    assert geo.fold_max == pytest.approx(fold_max)
    for folded, count in zip((0.0, 0.5 * fold_max, fold_max), counts, strict=True):
        raws = geo.raw_courses(folded, 4)
        assert len(raws) == len(set(raws)) == count
        assert all(geo.fold(c) == pytest.approx(folded, abs=1e-6) for c in raws)


def test_mecanum_raw_courses_and_plan() -> None:
    geo = Geometry.of(load_robot("mecanum4"))
    assert geo.idle_axes == (45.0, 135.0) and geo.fold_axes == (0.0,) and geo.fold_marker == (0.0,)
    assert geo.raw_courses(30.0, 4) == [30.0, 210.0, 330.0, 150.0]
    assert geo.raw_courses(30.0, 2) == [30.0, 210.0]  # out and back
    assert Plan().calibrated_courses(geo) == [0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0]
    assert Plan.quick().calibrated_courses(geo) == [0.0, 45.0, 90.0]  # the diagonal is a course of its own
    assert Plan.quick().reach_folds(geo) == [0.0, 30.0, 45.0, 60.0, 90.0]
    omni4 = Geometry.of(load_robot("omni4"))
    assert omni4.fold_marker is None and Plan.quick().calibrated_courses(omni4) == [0.0, 45.0]
    assert Plan.quick().reach_folds(omni4) == [0.0, 30.0, 45.0]


def test_raw_courses_alternate_directions(geo: Geometry) -> None:
    assert geo.raw_courses(15.0, 4) == [15.0, 105.0, 195.0, 285.0]
    assert geo.raw_courses(15.0, 2) == [15.0, 195.0]  # out and back


def test_power_arguments(geo: Geometry) -> None:
    # the firmware's K_l argument: K * |busiest rim speed|, V for course 0, V cos 45 for course 45
    assert geo.translation_factor(0.0) == pytest.approx(1.0)
    assert geo.translation_factor(45.0) == pytest.approx(0.5**0.5)
    assert geo.rotation_factor() == pytest.approx(0.096)


@pytest.mark.parametrize(
    ("preset", "counts"), [("omni4", (4, 8, 4)), ("omni3", (6, 12, 6)), ("mecanum4", (2, 4, 2))]
)
def test_every_raw_course_of_a_folded_course(preset: str, counts: tuple[int, int, int]) -> None:
    """The reach MOVEs' courses: every raw course that folds onto it, mirror images too (a
    current-limited pair of unequal motors loses one way only), each half returning to its start."""
    geo = Geometry.of(load_robot(preset))
    for folded, count in zip((0.0, 0.5 * geo.fold_max, geo.fold_max), counts, strict=True):
        raws = geo.every_raw_course(folded)
        assert len(raws) == len(set(raws)) == count
        assert all(geo.fold(c) == pytest.approx(folded, abs=1e-6) for c in raws)
        assert all(round((c + 180.0) % 360.0, 6) in raws for c in raws)
    omni4 = Geometry.of(load_robot("omni4"))
    assert omni4.every_raw_course(30.0) == [30.0, 120.0, 210.0, 300.0, 330.0, 60.0, 150.0, 240.0]
