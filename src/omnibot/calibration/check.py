"""The before/after accuracy check, driven: every MOVE and ROTATE of an
:class:`~omnibot.calibration.accuracy.AccuracyPlan`, measured by the runner's truth."""

from __future__ import annotations

import math
from functools import partial

from omnibot.calibration.accuracy import AccuracyPlan, AccuracyRow
from omnibot.calibration.runner import Runner
from omnibot.calibration.runs import ROTATE, RunInfo
from omnibot.protocol import codes


def _wrap_deg(a: float) -> float:
    return (a + 180.0) % 360.0 - 180.0


def move_row(
    runner: Runner, what: str, length: float, speed: float, course: float, group: str
) -> AccuracyRow:
    """One straight MOVE (``runner.move``) as an accuracy row: its errors by the runner's truth and the
    controller's warnings."""
    r = runner.move(what, length, speed, course, group)
    m = r.truth
    d = None if m is None else m.distance
    direction = None if m is None else m.direction
    return AccuracyRow(
        kind="move",
        course_deg=course,
        speed=speed,
        commanded=length,
        achieved=d,
        error=None if d is None else d / length - 1.0,
        course_error_deg=None if direction is None else _wrap_deg(math.degrees(direction) - course),
        heading_error_deg=None if m is None or m.theta is None else math.degrees(m.theta),
        source="" if m is None else m.source,
        saturated=codes.W_SPEED_REDUCED in r.warnings,
        short=codes.W_SHORT in r.warnings,
        clamped=codes.W_REACH in r.warnings,
    )


def run_accuracy(runner: Runner, plan: AccuracyPlan) -> list[AccuracyRow]:
    """Every MOVE and ROTATE of the plan, measured by the runner's truth."""
    client, robot = runner.client, runner.robot
    rows: list[AccuracyRow] = []
    length = round(plan.length, 2)
    for speed in plan.move_speeds(robot):
        for course in plan.courses_deg:
            for c in (course, course + 180.0) if plan.back else (course,):
                runner.note(f"check course {c:g} at {speed:g}")
                rows.append(move_row(runner, "check", length, speed, c, "check"))
    for angle, rate in plan.rotations:
        for sign in (1, -1):
            a = sign * angle
            info = RunInfo(ROTATE, f"check: rotate {a:g} deg at {rate:g} deg/s")
            runner.note(f"check rotate {a:g}")
            r = runner.run(
                info,
                partial(client.rotate, math.radians(a), math.radians(rate)),
                angle / rate,
                "check",
            )
            m = r.truth
            got = None if m is None or m.theta is None else math.degrees(m.theta)
            rows.append(
                AccuracyRow(
                    kind="rotate",
                    course_deg=0.0,
                    speed=rate,
                    commanded=a,
                    achieved=got,
                    error=None if got is None else got / a - 1.0,
                    heading_error_deg=None if got is None else got - a,
                    source="" if m is None else m.source,
                    saturated=codes.W_SPEED_REDUCED in r.warnings,
                )
            )
    return rows
