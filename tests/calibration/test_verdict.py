"""The verdict on a calibration, per course and ROTATE: on the checks ``omnibot calibrate`` recorded
when it made a course or ROTATE worse and said nothing (issue 24), and on constructed ones."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from omnibot.calibration.accuracy import AccuracyRow
from omnibot.calibration.verdict import (
    NOISE_MOVE,
    NOISE_ROTATE,
    NOISE_SHARE,
    judge,
    noise,
    part_errors,
    part_of,
)

CHECKS = Path(__file__).resolve().parents[1] / "data" / "calibrate_checks.json"
"""Check rows ([kind, course, speed, commanded, error]) as main recorded them (2026-12, seed 1):
``omnibot calibrate --quick --robot mecanum4 --surface carpet`` (exit 0, file written), the default
``omnibot calibrate`` (omni4, wood and carpet; exit 0) before, after and with the average, and
omni4's carpet tables from that run checked again three times in a row on a fresh robot."""


def recorded(name: str) -> dict[str, dict[str, list[AccuracyRow]]]:
    data: dict[str, dict[str, list[list[Any]]]] = json.loads(CHECKS.read_text())[name]
    return {
        surface: {label: [row(*r) for r in rows] for label, rows in checks.items()}
        for surface, checks in data.items()
    }


def row(kind: str, course: float, speed: float, commanded: float, error: float) -> AccuracyRow:
    return AccuracyRow(kind, course, speed, commanded, commanded * (1.0 + error), error)


def test_each_course_is_judged_both_ways_and_rotate_apart() -> None:
    assert part_of(row("move", 270.0, 0.3, 1.0, 0.0)) == part_of(row("move", 90.0, 0.5, 1.0, 0.0))
    assert part_of(row("move", 90.0, 0.3, 1.0, 0.0)) == "course 90/270 deg"
    assert part_of(row("rotate", 0.0, 90.0, -90.0, 0.0)) == "ROTATE"
    errors = part_errors(
        [row("move", 0, 0.3, 1, 0.02), row("move", 180, 0.3, 1, -0.04), row("rotate", 0, 90, 90, 0.01)]
    )
    assert errors == pytest.approx({"course 0/180 deg": 0.03, "ROTATE": 0.01})


def test_mecanum4_quick_on_carpet_makes_course_0_worse() -> None:
    """Better on the whole (54.9 -> 49.8 %), but forward, folded onto sideways' table, far worse."""
    carpet = recorded("mecanum4 carpet --quick")["carpet"]
    verdict = judge([("carpet", carpet["before"], carpet["after"])])
    assert verdict.better is False and verdict.worst == ""  # not worse on the whole
    assert verdict.summary.endswith("carpet 54.9 % -> 49.8 %")
    (worse,) = verdict.worse
    assert (worse.part, round(100 * worse.before, 1), round(100 * worse.after, 1)) == (
        "course 0/180 deg",
        38.8,
        158.1,
    )
    assert verdict.warning == (
        "WORSE THAN BEFORE: carpet: course 0/180 deg: 38.8 % -> 158.1 % "
        "(worst MOVE course 180 deg at 0.1 m/s: +113.8 % before, +360.4 % after)"
    )


def test_omni4_default_run_makes_rotate_worse_on_both_floors() -> None:
    floors = recorded("omni4")
    verdict = judge([(s, f["before"], f["after"]) for s, f in floors.items()])
    assert verdict.summary.endswith("wood 7.5 % -> 0.8 %, carpet 24.6 % -> 0.8 %")
    assert verdict.better is False and verdict.hint == ""  # worse on both floors
    assert [str(w).split(" (")[0] for w in verdict.worse] == [
        "wood: ROTATE: 1.6 % -> 3.6 %",
        "carpet: ROTATE: 1.8 % -> 3.6 %",
    ]
    assert "(worst ROTATE +90 deg at 90 deg/s: -0.6 % before, -5.2 % after)" in str(verdict.worse[0])
    # the average: worse on the whole on wood (as before), and on five courses there
    average = judge([(s, f["before"], f["average"]) for s, f in floors.items()])
    assert average.worst.startswith("wood: MOVE course 225 deg at 0.3 m/s")
    assert average.warning.startswith("WORSE THAN NO CALIBRATION: wood: MOVE course 225")
    assert sum(w.surface == "wood" and w.part != "ROTATE" for w in average.worse) == 5


@pytest.mark.parametrize(
    "name", ["omni4 carpet tables checked again", "mecanum4 carpet tables checked again"]
)
def test_the_same_tables_checked_again_are_not_worse(name: str) -> None:
    """The margin is the check's scatter: the same tables checked three times in a row (the wheels and
    their rollers start where the check before left them), each pair both ways."""
    checks = recorded(name)["carpet"]
    assert len(checks) == 3
    for before in checks.values():
        for after in checks.values():
            assert judge([("carpet", before, after)]).worse == ()


def checked(course_0: float, rotate: float, course_90: float) -> list[AccuracyRow]:
    """Course 0 both ways off by ``course_0``, course 90 by ``course_90``, a ROTATE by ``rotate``."""
    return [
        row("move", 0.0, 0.3, 1.0, course_0),
        row("move", 180.0, 0.3, 1.0, -course_0),
        row("move", 90.0, 0.3, 1.0, course_90),
        row("rotate", 0.0, 90.0, 90.0, rotate),
    ]


@pytest.mark.parametrize(
    ("before", "after", "worse"),
    [
        ((0.01, 0.01), (0.01 + 0.9 * NOISE_MOVE, 0.01), []),  # within the check's scatter
        ((0.01, 0.01), (0.01 + 1.1 * NOISE_MOVE, 0.01), ["course 0/180 deg"]),
        (
            (0.8, 0.01),
            (0.8 + 0.9 * NOISE_SHARE * 0.8, 0.01),
            [],
        ),  # 5 % of a large error: more than NOISE_MOVE
        ((0.8, 0.01), (0.8 + 1.1 * NOISE_SHARE * 0.8, 0.01), ["course 0/180 deg"]),
        ((0.01, 0.01), (0.01, 0.01 + 0.9 * NOISE_ROTATE), []),
        ((0.01, 0.01), (0.01, 0.01 + 1.1 * NOISE_ROTATE), ["ROTATE"]),
    ],
)
def test_a_part_is_worse_beyond_the_check_scatter(
    before: tuple[float, float], after: tuple[float, float], worse: list[str]
) -> None:
    """Course 90 goes from 10 % short to exact, so the whole check is better in every case."""
    verdict = judge([("wood", checked(*before, course_90=-0.1), checked(*after, course_90=0.0))])
    assert verdict.worst == "" and [w.part for w in verdict.worse] == worse
    assert verdict.better is (not worse) and (verdict.warning != "") is bool(worse)
    assert noise("ROTATE", 0.01) == NOISE_ROTATE and noise("course 0/180 deg", 0.8) == NOISE_SHARE * 0.8
