"""The idle wheels' roller drag, measured: the drag runs and the MOVEs that tune its coast
(:mod:`omnibot.calibration.rollerfit` fits both).

Runs (:func:`roller_runs`): raw POWER along each idle axis in turn, round the circle (omni4: 0, 90,
180, 270 degrees), at three powers over the working range and two durations each (the second twice
the first). Each run turns the next axis's idle wheels by its whole distance, so their roller
phases come out spread over the pitch; the encoder counts at each run's start give the phases of the
wheels that stand still.

Coast (:func:`tune_coast`): MOVEs round the motor axes with and without the drag term uploaded; the
gain that cancels the drag in them gives the coast table the controller uses.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from omnibot.calibration.experiments import Runner
from omnibot.calibration.patterns import course_pattern, top_power
from omnibot.calibration.plan import Plan
from omnibot.calibration.rollerfit import (
    GROUP,
    CoastTuning,
    RollerFit,
    axis_courses,
    coast_row,
    coast_tuning,
    fit_coast_speed,
)
from omnibot.calibration.runs import STRAIGHT, RunInfo, RunResult
from omnibot.robot.description import CalibrationSpec, PiecewiseLinear

PROBE = 0.6
"""s of each power's first run, which sets the durations of the others."""
SHARES = (0.3, 0.55, 0.8)
"""The runs' powers, as fractions of the way from the axis's dead band to full power."""


def roller_runs(runner: Runner, plan: Plan, deadband: int, rounds: int = 4) -> list[RunResult]:
    """The drag runs (see the module docstring): per power a probe, then ``rounds`` times round the
    axes, alternating the two durations."""
    geo = runner.geometry
    courses = axis_courses(geo)
    top = top_power(runner.motors, geo.pwm_max)

    def run(course: float, power: int, duration: float, group: str) -> RunResult:
        info = RunInfo(
            STRAIGHT,
            f"roller drag, course {course:g} deg, power {power} for {duration:g} s",
            math.radians(course),
        )
        runner.note(f"roller drag: course {course:g}, power {power}")
        pattern = course_pattern(geo, course, power, runner.motors, runner.rate)
        return runner.power_run(
            pattern, duration, info, group, power=power, course_deg=course, folded_deg=0.0
        )

    out = []
    for share in SHARES:
        power = max(1, round(deadband + share * (top - deadband)))
        probe = run(courses[0], power, PROBE, f"{GROUP}:probe")
        speed = max((probe.amount or 0.0) / PROBE, 0.05)
        # the first duration covers about 40 % of the reference move, the second twice that
        first = round(min(max(0.4 * plan.move_length / speed, 0.3), 3.0), 2)
        for k in range(rounds):
            for course in courses:
                out.append(run(course, power, first * (1 + k % 2), GROUP))
    return out


def tune_coast(
    runner: Runner,
    spec: CalibrationSpec,
    fit: RollerFit,
    speeds: Sequence[float],
    length: float,
    rounds: int = 4,
    slow_rounds: int | None = None,
) -> CoastTuning | None:
    """MOVEs of ``length`` round the motor axes at each speed (``rounds`` times round; the slowest
    speed ``slow_rounds`` times, default the same), alternately with and without the drag term of
    ``spec`` uploaded, and the coast table that makes the term cancel the drag in them.

    Per speed, with D_j the drag at the run's phases and g_j the term's gain (0 when off)::

        distance_j = e_course - lambda D_j + mu g_j D_j

    so the gain that cancels it is ``lambda / mu``: the POWER runs' coast times are a first guess,
    but a MOVE drives at the powers K_l gives, where the motors may be current-limited for longer.
    Leaves the controller with ``spec`` uploaded. None when a speed's runs could not tell.
    """
    geo = runner.geometry
    rollers = spec.rollers
    if rollers is None or not fit.kept:
        return None
    off = spec.model_copy(update={"rollers": None})
    courses = axis_courses(geo)
    table = rollers.coast or PiecewiseLinear(x=(0.0,), y=(0.0,))
    found: list[tuple[float, float, float, float]] = []
    ahead: list[tuple[float, float, float]] = []
    runs = 0
    try:
        for speed in speeds:
            gain = 1.0 + table(speed) * speed / length
            rows, b = [], []
            n = slow_rounds if slow_rounds is not None and speed == min(speeds) else rounds
            for k in range(n):
                on = k % 2 == 0
                runner.client.upload_calibration(spec if on else off)
                for course in courses:
                    runner.note(f"roller gain {speed:g} m/s")
                    detail = f" ({'with' if on else 'without'} the term)"
                    r = runner.move("roller drag gain", length, speed, course, f"{GROUP}:gain", detail)
                    runs += 1
                    if r.truth is None or r.truth.distance is None or r.counts is None:
                        continue
                    d = fit.drag(geo, course, r.counts[: geo.motors])
                    rows.append(coast_row(courses, course, d, gain if on else 0.0))
                    b.append(r.truth.distance)
            got = fit_coast_speed(courses, rows, b)
            if got is None:
                return None
            lam, mu, course_ahead = got
            found.append((speed, lam, mu, lam / mu))
            ahead += course_ahead
    finally:
        runner.client.upload_calibration(spec)
    return coast_tuning(found, ahead, runs, length)
