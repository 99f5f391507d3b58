"""The per-surface progress tally: estimates per phase, replaced by the runs really driven."""

from __future__ import annotations

from omnibot.calibration.patterns import Geometry
from omnibot.calibration.plan import Plan
from omnibot.calibration.tally import Tally, expected_runs
from omnibot.robot import load_robot


class Bar:
    def __init__(self, total: int) -> None:
        self.n, self.total, self.shown = 0, total, [total]

    def update(self, n: float | None = 1) -> None:
        self.n += int(n or 0)

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        pass

    def refresh(self) -> None:
        self.shown.append(self.total)


def test_each_phase_end_swaps_its_estimate_for_its_runs() -> None:
    bar = Bar(30)
    tally = Tally(bar, {"dead bands": 10, "sweeps": 20})
    for _ in range(4):
        tally.update()
    tally.done("dead bands")  # 4 runs instead of 10
    assert bar.total == 24
    for _ in range(25):
        tally.update()
    tally.finish()  # 5 more than expected
    assert bar.n == bar.total == tally.runs == 29 and bar.shown == [30, 24, 29]


def test_no_bar_is_fine() -> None:
    tally = Tally(None, {"sweeps": 3})
    tally.update(2)
    tally.finish()
    assert tally.total == tally.runs == 2


def test_phases_that_do_not_run_expect_nothing() -> None:
    robot = load_robot("omni4")
    geometry = Geometry.of(robot)
    full = expected_runs(Plan(), geometry, None, robot)
    assert "before" not in full and "after" not in full  # no accuracy check
    bare = expected_runs(Plan(motor_map=False, roller_rounds=0), geometry, None, robot, upload=False)
    assert set(full) - set(bare) == {"motor map", "roller drag", "turns", "roller gains", "slow end", "reach"}
    assert full["slow end"] == 4 * 4 * Plan().slow_rounds  # every raw course of each calibrated course
    # the reach's first round: every raw course folding onto 0, 15, 30 and 45 degrees (4, 8, 8, 4); --quick
    # 0, 30, 45; with three wheel positions the axes' three times, two ROTATEs between them
    assert full["reach"] == 24 and expected_runs(Plan.quick(), geometry, None, robot)["reach"] == 16
    assert expected_runs(Plan(reach_phases=3), geometry, None, robot)["reach"] == 34
    assert "reach" not in expected_runs(Plan(reach_courses=()), geometry, None, robot)
