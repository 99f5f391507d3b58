"""The progress of one surface's calibration: the runs each phase is expected to take and a bar's
total kept true as the phases end."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager

from omnibot.calibration.accuracy import (
    AccuracyPlan,
)
from omnibot.calibration.motorfit import (
    STAND_POWERS,
    balance_courses,
)
from omnibot.calibration.motors import MODEL_ROUNDS
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.plan import Plan
from omnibot.calibration.reachmoves import phase_count
from omnibot.calibration.rollerfit import axis_courses
from omnibot.calibration.rollers import SHARES
from omnibot.progress import Progress
from omnibot.robot import RobotDescription

ProgressFactory = Callable[[str, int], AbstractContextManager[Progress | None]]
"""(description, expected runs) -> a context giving a progress bar (or None)."""


@contextmanager
def no_progress(desc: str, total: int) -> Iterator[Progress | None]:
    """A progress context that shows nothing (yields None)."""
    yield None


def accuracy_runs(accuracy: AccuracyPlan, robot: RobotDescription) -> int:
    """The runs of one accuracy check (:func:`~omnibot.calibration.check.run_accuracy`)."""
    moves = len(accuracy.courses_deg) * len(accuracy.move_speeds(robot)) * (2 if accuracy.back else 1)
    return moves + 2 * len(accuracy.rotations)


DEADBAND_RUNS = 10
"""Runs a dead-band search takes, about (a sweep upward in ``deadband_step`` counts, then bisection)."""
DEADBAND_AGAIN = 5
"""Runs a dead band takes at each further wheel position, about (the ROTATE and a bracketed search)."""


def expected_runs(
    plan: Plan,
    geometry: Geometry,
    accuracy: AccuracyPlan | None,
    robot: RobotDescription,
    upload: bool = True,
) -> dict[str, int]:
    """The runs each phase of one surface is expected to take, in the order they come (for the
    progress bar). Exact where a phase's count is fixed; the dead-band searches and the sweeps
    adapt to the robot, so theirs are estimates the bar corrects as each phase ends (:class:`Tally`)."""
    courses = len(plan.calibrated_courses(geometry))
    checks = accuracy_runs(accuracy, robot) if accuracy is not None else 0
    powers = max(1, plan.balance_levels)
    # each power through the offsets and once per motor (its Jacobian), then each Gauss-Newton step
    balance = len(balance_courses(geometry)) * ((1 + geometry.motors) * powers + MODEL_ROUNDS * powers)
    balance += len(STAND_POWERS) if robot.has_wheel_encoders else 0  # the stand test, where it can run
    rollers = plan.roller_rounds > 0 and all(geometry.roller_pitch)
    axes = len(axis_courses(geometry))
    again = (max(1, plan.deadband_positions) - 1) * DEADBAND_AGAIN  # each further wheel position
    phases = {
        "before": checks,
        "motor map": (1 + geometry.motors) * (DEADBAND_RUNS + again) + balance if plan.motor_map else 0,
        "dead bands": (courses + 1) * ((3 if plan.motor_map else DEADBAND_RUNS) + again),
        "sweeps": courses * plan.levels * plan.directions * 2,
        "roller drag": len(SHARES) * (1 + plan.roller_rounds * axes) if rollers else 0,
        "rotation sweep": plan.levels * 2 * 2,
        # each MOVE and the ROTATE before it that sets the idle wheels' phase (most MOVEs need one)
        "roller gains": 2 * (3 * plan.roller_rounds + plan.coast_slow_rounds) * axes
        if rollers and upload
        else 0,
        "slow end": courses * plan.directions * plan.slow_rounds if upload else 0,
        "reach": sum(
            (len(geometry.every_raw_course(f)) + 1) * phase_count(geometry, f, plan) - 1
            for f in plan.reach_folds(geometry)
        )
        if upload
        else 0,
        "turns": plan.turn_rounds * len(plan.turn_curvatures) * len(plan.turn_courses_deg) * 2
        if upload
        else 0,
        "rotation test": 2,
        "squares": 2,
        "after": checks if upload else 0,
    }
    return {name: n for name, n in phases.items() if n}


class Tally:
    """Keeps a progress bar's total true: the runs done plus the runs the phases still to come are
    expected to take. Each phase's end (:meth:`done`) replaces its estimate by what it really took, so
    when the last one ends the total is the number of runs driven."""

    def __init__(self, bar: Progress | None, phases: dict[str, int]) -> None:
        self.bar = bar
        self.left = dict(phases)
        self.runs = 0
        """Runs counted so far (the bar's n)."""

    @property
    def total(self) -> int:
        """The bar's total: runs done plus the runs still expected of the phases to come."""
        return self.runs + sum(self.left.values())

    def update(self, n: float | None = 1) -> bool | None:
        """Count ``n`` runs done."""
        self.runs += int(n or 0)
        return self.bar.update(n) if self.bar is not None else None

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """Show ``s`` after the bar."""
        if self.bar is not None:
            self.bar.set_postfix_str(s, refresh)

    def done(self, *phases: str) -> None:
        """These phases have ended (or will not run): their runs are all counted."""
        for phase in phases:
            self.left.pop(phase, None)
        self.recount()

    def finish(self) -> None:
        """Every phase has ended: the total is the runs driven."""
        self.left.clear()
        self.recount()

    def recount(self) -> None:
        """Give the bar its current :attr:`total` and redraw it."""
        if self.bar is not None and hasattr(self.bar, "total"):
            self.bar.total = self.total
            refresh = getattr(self.bar, "refresh", None)
            if refresh is not None:
                refresh()
