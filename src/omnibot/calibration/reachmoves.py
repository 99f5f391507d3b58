"""The calibrated reach from MOVEs: the fastest open-loop MOVE that really lands, per folded course.

:func:`~omnibot.calibration.accuracy.reach_speed` computes how fast the tables can power a MOVE of
the reference length without a motor's PWM saturating. The drivers' current limit and the floor's
grip come first on some courses (docs/calibration.md, "The reach from MOVEs"): next to the diagonals a
current-limited pair of unequal motors turns the body and the MOVE falls short one way; on a soft
floor the two driven wheels of an axis course slip under the whole load. Neither saturates a PWM, and
the slip hides from the encoders too. So on each of :meth:`~omnibot.calibration.plan.Plan.reach_folds`
(omni4: 0, 15, 30, 45 degrees) :func:`measure_reach` drives MOVEs of the reference length on every
raw course that folds onto it, at the computed reach of that course (at most the top of the speed
range), measured by the calibration's truth as the check measures them. Where one does not land
(its distance off by more than ``Plan.reach_goal``, or the controller warned 11 or 17), it and its
opposite course (so the robot stays near its start) are driven again ``Plan.reach_step`` slower,
until they land. A course that landed at a speed is taken to land slower too (the current drawn and
the load the wheels push against grow with speed). On a course where wheels stand idle (omni4's
axes) each round is driven at ``Plan.reach_phases`` wheel positions, n (a ROTATE in place moves every
wheel on by 1 + 1/n roller pitches between them): the idle wheels' rollers drag with where they
stand, and near the floor's grip that decides whether the two driven wheels slip, so one position
could land where another falls 10 % short.
"""

from __future__ import annotations

from omnibot.calibration.accuracy import AccuracyRow, ReachMeasure, reach_speed
from omnibot.calibration.check import move_row
from omnibot.calibration.deadband import turn_wheels
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.plan import Plan, speed_range
from omnibot.calibration.runner import Runner
from omnibot.robot import CalibrationSpec

REACH = "reach"
"""The group of the reach MOVEs."""


def lands(row: AccuracyRow, goal: float) -> bool:
    """A reach MOVE landed: within ``goal`` of its length and no warning 11 or 17 (one the truth could not
    measure counts as landed: nothing says otherwise)."""
    return not row.warned and (row.error is None or abs(row.error) <= goal)


def slower(speed: float, step: float) -> float:
    """The next speed down, m/s: ``step`` of it slower, at least 1 cm/s (the protocol's resolution)."""
    return round(min(speed - 0.01, speed * (1.0 - step)), 2)


def phase_count(geometry: Geometry, folded: float, plan: Plan) -> int:
    """Wheel positions a round of reach MOVEs on ``folded`` is driven at: ``plan.reach_phases`` where
    wheels stand idle on it (their rollers' drag depends on where they stand, and near the floor's
    grip that decides whether the driven wheels slip), else 1 (every wheel turns through the MOVE)."""
    return max(1, plan.reach_phases) if geometry.idle_wheels(folded) else 1


def measure_reach(runner: Runner, spec: CalibrationSpec, plan: Plan) -> ReachMeasure:
    """Drive the reach MOVEs through the tables in the controller (``spec``, without a reach) on every
    course of ``plan.reach_folds`` (module docstring)."""
    robot, geo = runner.robot, runner.geometry
    length = round(plan.move_length, 2)
    bottom, top = speed_range(robot, plan.move_length)
    out = ReachMeasure()
    for folded in plan.reach_folds(geo):
        raw = geo.every_raw_course(folded)
        computed = reach_speed(robot, spec, plan.move_length, raw)
        out.computed[folded] = computed
        speed = None if computed is None else round(min(computed, top), 2)
        pending = raw
        phases = phase_count(geo, folded, plan)
        while speed is not None and pending:
            rows = []
            for k in range(phases):
                if k:
                    turn_wheels(runner, 1.0 + 1.0 / phases, f"{REACH}:turn", REACH)
                for course in pending:
                    runner.note(f"reach: course {course:g} at {speed:g}")
                    rows.append(move_row(runner, "reach", length, speed, course, REACH))
            out.rows += rows
            missed = {r.course_deg for r in rows if not lands(r, plan.reach_goal)}
            if not missed:
                break
            # again, slower: each course that missed and its opposite (the robot stays near its start)
            pending = [c for c in pending if c in missed or (c + 180.0) % 360.0 in missed]
            speed = slower(speed, plan.reach_step)
            if speed < bottom - 1e-9:
                speed = None
        out.measured[folded] = speed
    return out
