"""Wheel-slip calibration in the simulator, and following with it (omni4 on carpet)."""

from __future__ import annotations

import numpy as np
import pytest

from omnibot.control.paths import standard_path
from omnibot.errors import ConfigError
from omnibot.navigation.runner import Navigator
from omnibot.navigation.session import FollowOptions, simulate_follow, simulated_client
from omnibot.navigation.slipcal import (
    SimulatorTruth,
    SlipCalibration,
    calibrate_slip,
    course_order,
    simulate_slip_calibration,
)
from omnibot.robot.description import load_robot
from tests.navigation.test_runner import Drivers


class EndPoints:
    """The simulator's truth read only before and after each run (as a tape measure would)."""

    live = False

    def __init__(self, truth: SimulatorTruth) -> None:
        self.truth = truth

    def start(self) -> object:
        return self.truth.start()

    def displacement(self, mark: object, course: float) -> tuple[float, float] | None:
        return self.truth.displacement(mark, course)


@pytest.fixture(scope="module")
def carpet() -> SlipCalibration:
    return simulate_slip_calibration(load_robot("omni4"), "carpet", seed=3)


def test_carpet_creep_is_found_and_removed(carpet: SlipCalibration) -> None:
    raw, corrected = carpet.errors(corrected=False), carpet.errors(corrected=True)
    assert len(raw) == 12 and carpet.courses_deg[:4] == [0.0, 180.0, 30.0, 210.0]
    # carpet: the encoders over-read by several percent on every course
    assert min(raw) > 0.03 and np.mean(raw) > 0.06
    # one coefficient for the floor takes most of it out
    assert np.mean(corrected) < 0.25 * np.mean(raw)
    assert 0.008 < carpet.params.roll < 0.03
    # the simulator's truth is read after each speed-up too, which pins down the acceleration term
    assert len(carpet.speed_ups) == 12 and 0.005 < carpet.params.compliance < 0.05


def test_wood_creeps_an_order_of_magnitude_less_and_end_points_fit_roll_only(
    carpet: SlipCalibration,
) -> None:
    robot = load_robot("omni4")
    with simulated_client(robot, surface="wood", seed=3) as client:
        nav = Navigator(client, robot)
        drivers = Drivers()
        nav.runtime.add_sink(drivers)
        nav.prepare(1.0)
        wood = calibrate_slip(nav, EndPoints(SimulatorTruth(nav)))
        nav.close()
    assert (
        drivers.sources == {"slip-run"} and nav.runtime.sent.errors == 0
    )  # the runs: a script on the runtime
    assert 0.0 < wood.params.roll < 0.25 * carpet.params.roll
    assert wood.params.compliance == 0.0 and not wood.speed_ups


def test_following_on_carpet_with_the_floors_slip_is_more_accurate(carpet: SlipCalibration) -> None:
    robot = load_robot("omni4")
    path = standard_path("circle", size=0.6)
    results = {}
    for label, slip in (("raw", None), ("calibrated", carpet.params)):
        _, report = simulate_follow(
            robot, path, FollowOptions(speed=0.4, slip=slip), surface="carpet", seed=5
        )
        assert report["completed"]
        results[label] = report["rms_cross_track_m"]
    assert results["calibrated"] < 0.5 * results["raw"]
    assert results["calibrated"] < 0.01


def test_course_order_and_truth_need_what_they_need() -> None:
    assert course_order(4) == [0.0, 180.0, 90.0, 270.0]
    with pytest.raises(ConfigError, match="even number of courses"):
        course_order(5)
    robot = load_robot("omni4")
    with simulated_client(robot) as client:
        nav = Navigator(client, robot)
        nav.sim = None  # as on a real link
        with pytest.raises(ConfigError, match="no simulator ground truth"):
            SimulatorTruth(nav)
