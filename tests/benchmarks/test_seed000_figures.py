"""Seed 000's Fig. 6 statement on the simulated robot: rotation in place needs more power than a turn
added to a robot already moving (``benchmarks.seed000_figures.turn_against_rotation``); each series'
mean error against the seed (``series_errors``); rotation against the axis in the firmware's terms
(``rotation_against_axis``)."""

from __future__ import annotations

import numpy as np
import pytest
from benchmarks.seed000_figures import (
    AXIS_MM,
    AXIS_OTHER_MM,
    DIAGONAL_MM,
    ROTATION_MS,
    STILL,
    least_power,
    seed_rotation_against_axis,
    series_errors,
    simulated_rotation_against_axis,
    turn_against_rotation,
)


@pytest.mark.parametrize("surface", ["wood", "carpet"])
def test_a_turn_added_to_a_motion_needs_less_power_than_rotation_in_place(surface: str) -> None:
    """Seed 000: "rotation without movement requires more power than turning adjustment" (its K_r above
    its K_t at every power). Added to a robot moving at 100 counts, each of K_t's powers of the default
    calibration (up to 85 counts) turns it faster than it turns the robot at rest: below the wheels'
    start (30 counts) the robot at rest does not turn at all; at 85 counts 1.06x on the axis and 1.32x
    at 45 degrees on wood (1.05x, 1.25x on carpet). A turn larger than the motion itself (120 counts)
    stops some wheels and reverses them, and gets 0.84x / 0.90x: the seed's statement is about
    adjusting a motion."""
    turns = turn_against_rotation(surface, powers=(30, 45, 60, 85))
    rotation = turns["rotation"]
    assert rotation[30] < STILL < rotation[45]
    for course in ("course 0", "course 45"):
        added = turns[course]
        assert all(added[p] > rotation[p] for p in rotation), (course, added, rotation)
    assert turns["course 45"][85] > 1.2 * rotation[85]


def test_series_errors_are_each_series_mean_abs_error_over_the_seeds_powers() -> None:
    """Each axis course against its own data with the one simulated axis series: 10 % longer than course
    90's data is 10 % off there and more on course 0, whose data lie below course 90's. 45 degrees
    against the mean of its runs, rotation against both turns' times (20 % quick: 20 %)."""
    axis = {p: 1.1 * mm for p, mm in AXIS_MM.items()} | {p: 1.1 * mm for p, mm in AXIS_OTHER_MM[90].items()}
    diagonal = {
        p: sum(v for v in runs if v is not None) / sum(v is not None for v in runs)
        for p, runs in DIAGONAL_MM.items()
    }
    rotation = {p: (0.8 * a, 0.8 * b) for p, (a, b) in ROTATION_MS.items()}
    result = {"axis": {"wood": axis}, "diagonal": {"wood": diagonal}, "rotation": {"wood": rotation}}
    errors = series_errors(result, "wood")
    assert list(errors) == [
        "course 0",
        "course 90",
        "course 180",
        "course 270",
        "45 degrees",
        "rotation, 1st turn",
        "rotation, 2nd turn",
    ]
    assert errors["course 90"] == pytest.approx(0.1)
    assert errors["course 0"] > 0.1  # course 90's data, 5-26 % above course 0's, at nine of its powers
    assert errors["45 degrees"] == pytest.approx(0.0)
    assert errors["rotation, 1st turn"] == pytest.approx(0.2)
    assert errors["rotation, 2nd turn"] == pytest.approx(0.2)
    diagonal[80] = 150.0  # the seed's one run at 80 counts: 100 mm
    assert series_errors(result, "wood")["45 degrees"] == pytest.approx(0.5 / len(DIAGONAL_MM))


def test_least_power_reads_the_first_power_that_reaches_a_speed() -> None:
    """The seed's first turn is slower at 120 counts than at 110 (1165 against 1145 ms): a speed is
    read where a series first reaches it, and nowhere outside the series."""
    rates = {50: 0.1, 60: 0.3, 70: 0.25, 80: 0.5}
    got = least_power(rates, (0.2, 0.28, 0.4, 0.05, 0.6))
    assert got[:3] == pytest.approx([55.0, 59.0, 76.0])
    assert np.isnan(got[3:]).all()


def test_the_seeds_rotation_needs_about_what_its_firmware_gives_it_against_the_axis() -> None:
    """OSLL omnibot v0.038 drives a ROTATE with 10 + 0.19 (1 - 10/255) counts per mm/s of wheel path
    and a MOVE on a motor axis with 40 + 0.24 (1 - 40/255): above each one's shift, rotation needs 0.90
    of the axis's power per rim speed. The seed's workbook read the same way (from rest, as its tables
    were taken; its four axis courses, the first and the second turn, 0.3-0.6 m/s) gives 0.88-1.23,
    mean 1.05, with no trend in speed (per speed 0.95-1.23 at 0.3 m/s, 0.88-1.19 at 0.6)."""
    ratio = seed_rotation_against_axis()
    assert ratio.shape == (8, 4) and not np.isnan(ratio).any()
    assert ratio.min() == pytest.approx(0.882, abs=1e-3) and ratio.max() == pytest.approx(1.231, abs=1e-3)
    assert ratio.mean() == pytest.approx(1.046, abs=1e-3)
    firmware = 0.19 * (1 - 10 / 255) / (0.24 * (1 - 40 / 255))
    assert ratio.min() < firmware < ratio.max()


@pytest.mark.xfail(
    strict=True,
    reason="issue 30, the low-power end: the simulated rotation starts at about 45 counts, the seed's "
    "near 23, so at 0.3 m/s it needs 1.33-1.36 of the axis's power in the firmware's terms (the seed's robot at most 1.23)",
)
def test_rotation_against_the_axis_lies_within_the_seeds_spread() -> None:
    """The seed's experiments on the simulated robot (wood), read as the seed's are: at every rim speed
    0.3-0.6 m/s both readings of the turn lie within the seed's range over its courses and readings."""
    seed = seed_rotation_against_axis()
    ratio = simulated_rotation_against_axis("wood")
    assert not np.isnan(ratio).any(), ratio
    assert np.all((ratio >= seed.min()) & (ratio <= seed.max())), ratio
