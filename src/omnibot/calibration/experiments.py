"""Seed 000's calibration experiments, driven over the protocol through a RobotClient.

Nothing here knows whether the robot is real or simulated: every run is protocol commands (POWER,
MOVE, ROTATE) and a measurement by the chosen truth strategy, so the same code calibrates a board on
a serial port and the simulator in lockstep.

* :func:`~omnibot.calibration.deadband.find_deadband`: the lowest power that moves the robot (a
  coarse upward sweep, then bisection), per straight course pattern and for rotation.
* :func:`straight_sweep`: straight runs with raw POWER on each calibrated course over a sweep of
  powers, each power for two durations (so the steady speed and the start/stop loss separate),
  chosen so the runs bracket the reference MOVE (a secant step on the first run's distance), on
  several raw courses that fold to the same calibrated course (alternating directions, so the robot
  stays near its start).
* :func:`rotation_sweep`: the same for rotation in place, both directions.
* :func:`turning_runs`: curved MOVEs; the body's turn against the commanded one (for K_t).
* :func:`drive_square`: UMBmark's square, CCW or CW, its telemetry logged (umbmark.py fits it).

What to measure is the :class:`~omnibot.calibration.plan.Plan`; each run's outcome a
:class:`~omnibot.calibration.runs.RunResult`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

from omnibot.calibration.patterns import Geometry, Rate, course_pattern, rotation_pattern, top_power
from omnibot.calibration.plan import Plan, speed_range
from omnibot.calibration.runner import Runner
from omnibot.calibration.runs import ROTATE, SQUARE, STRAIGHT, TURN, RunInfo, RunResult
from omnibot.calibration.umbmark import SquareRun
from omnibot.protocol.messages import Command
from omnibot.robot import MotorMapSpec, RobotDescription


def power_levels(deadband: int, pwm_max: int, levels: int) -> list[int]:
    """``levels`` powers from just above the dead band to ``pwm_max``, denser near the dead band."""
    start = min(max(deadband, 1), pwm_max)
    out: list[int] = []
    for k in range(1, levels + 1):
        p = round(start + (pwm_max - start) * (k / levels) ** 1.5)
        if not out or p > out[-1]:
            out.append(min(p, pwm_max))
    return out


# --------------------------------------------------------------------------- sweeps


@dataclass(frozen=True)
class Target:
    """One raw pattern of a sweep: how to build its powers and describe it."""

    pattern: Callable[[int], list[int]]
    info: Callable[[int, float], RunInfo]
    meta: dict[str, Any]


def _first_duration(
    previous: list[tuple[int, float]],
    power: int,
    deadband: int,
    reference: float,
    t_min: float,
    t_max: float,
    probe: float,
) -> float:
    """First duration of a power level: the time the reference amount takes at the rate expected
    from the levels below (linear from the dead band), or ``probe`` for the first level."""
    if previous:
        p0, rate0 = previous[-1]
        if rate0 > 0 and p0 > deadband:
            guess = rate0 * (power - deadband) / (p0 - deadband)
            return min(max(reference / guess, t_min), t_max)
    return probe


def _second_duration(t1: float, amount: float, reference: float, t_min: float, t_max: float) -> float:
    """Secant step towards the duration that covers the reference amount, at least 30 % away."""
    if amount <= 0:
        t2 = t1 * 2.0
    elif amount < reference:
        t2 = max(t1 * reference / amount, 1.3 * t1)
    else:
        t2 = min(t1 * reference / amount, 0.7 * t1)
    t2 = min(max(t2, t_min), t_max)
    if abs(t2 - t1) < 0.25 * t1:
        t2 = t1 * 0.6 if t1 * 0.6 >= t_min else t1 * 1.5
    return round(t2, 3)


def _sweep(
    runner: Runner,
    plan: Plan,
    group: str,
    targets: list[Target],
    deadband: int,
    reference: float,
    t_max: float,
    stop_rate: float,
    slow: float,
) -> list[RunResult]:
    """Power levels upward; at each, every target for two durations that bracket the reference
    amount (a MOVE or ROTATE of the reference size lasts about as long), until the rate passes
    ``stop_rate``. Levels whose first runs are slower than ``slow`` get one duration only."""
    geo = runner.geometry
    out: list[RunResult] = []
    rates: list[tuple[int, float]] = []
    for power in power_levels(deadband, top_power(runner.motors, geo.pwm_max), plan.levels):
        runner.note(f"{group}: power {power}")
        t1 = round(_first_duration(rates, power, deadband, reference, plan.t_min, t_max, plan.probe), 3)
        first = [_target_run(runner, t, power, t1, group) for t in targets]
        got = [r.amount for r in first if r.amount is not None]
        if not got or sum(got) / len(got) < slow * t1:
            # far below the working range: one duration is enough to anchor the curve
            out += first
            if got:
                rates.append((power, max(sum(got) / len(got) / t1, 0.0)))
            continue
        t2 = _second_duration(t1, sum(got) / len(got), reference, plan.t_min, t_max)
        second = [_target_run(runner, t, power, t2, group) for t in targets]
        out += first + second
        pairs = [(r1.amount, r2.amount) for r1, r2 in zip(first, second, strict=True)]
        a1 = [a for a, _ in pairs if a is not None]
        a2 = [b for _, b in pairs if b is not None]
        if a1 and a2:
            rate = max((sum(a2) / len(a2) - sum(a1) / len(a1)) / (t2 - t1), 0.0)
            rates.append((power, rate))
            if rate > stop_rate:
                break
    return out


def _target_run(runner: Runner, target: Target, power: int, duration: float, group: str) -> RunResult:
    return runner.power_run(
        target.pattern(power), duration, target.info(power, duration), group, power=power, **target.meta
    )


def _straight_info(raw: float, power: int, duration: float) -> RunInfo:
    return RunInfo(
        STRAIGHT, f"straight, course {raw:g} deg, power {power} for {duration:g} s", math.radians(raw)
    )


def _rotation_pattern(
    geo: Geometry, ccw: bool, motors: MotorMapSpec | None, rate: Rate | None, power: int
) -> list[int]:
    return rotation_pattern(geo, power, ccw, motors, rate)


def _rotation_info(ccw: bool, power: int, duration: float) -> RunInfo:
    return RunInfo(ROTATE, f"rotation {'ccw' if ccw else 'cw'}, power {power} for {duration:g} s")


def straight_sweep(runner: Runner, plan: Plan, folded_deg: float, deadband: int) -> list[RunResult]:
    """Straight POWER runs on every raw course folding to ``folded_deg``, powers upward."""
    geo = runner.geometry
    targets = [
        Target(
            pattern=partial(course_pattern, geo, raw, motors=runner.motors, rate=runner.rate),
            info=partial(_straight_info, raw),
            meta={"course_deg": raw, "folded_deg": folded_deg},
        )
        for raw in geo.raw_courses(folded_deg, plan.directions)
    ]
    slow, fast = speed_range(runner.robot, plan.move_length)
    t_max = 1.5 * plan.move_length / slow
    stop = plan.speed_margin * fast
    return _sweep(
        runner, plan, f"course:{folded_deg:g}", targets, deadband, plan.move_length, t_max, stop, 0.3 * slow
    )


def rotation_sweep(runner: Runner, plan: Plan, deadband: int) -> list[RunResult]:
    """Rotation POWER runs, both directions, powers upward."""
    geo = runner.geometry
    targets = [
        Target(
            pattern=partial(_rotation_pattern, geo, ccw, runner.motors, runner.rate),
            info=partial(_rotation_info, ccw),
            meta={"sign": 1 if ccw else -1},
        )
        for ccw in (True, False)
    ]
    t_max = 1.5 * plan.rotate_angle / plan.rotate_rate_min
    stop = plan.speed_margin * runner.robot.limits.angular_speed_max
    return _sweep(
        runner,
        plan,
        "rotation",
        targets,
        deadband,
        plan.rotate_angle,
        t_max,
        stop,
        0.3 * plan.rotate_rate_min,
    )


SLOW = "slow"
"""The group of :func:`slow_moves`' MOVEs."""


def slow_moves(runner: Runner, plan: Plan, speed: float) -> list[RunResult]:
    """MOVEs of the reference length at ``speed`` on every raw course of each calibrated course,
    ``plan.slow_rounds`` times round, through the tables in the controller (what
    :func:`~omnibot.calibration.fits.anchor_slow_end` needs)."""
    geo, length = runner.geometry, round(plan.move_length, 2)
    speed = round(speed, 2)  # the protocol's resolution: cm/s
    out: list[RunResult] = []
    for _ in range(plan.slow_rounds):
        for folded in plan.calibrated_courses(geo):
            for raw in geo.raw_courses(folded, plan.directions):
                runner.note(f"slow end: course {raw:g}")
                out.append(
                    runner.move("slow end", length, speed, raw, SLOW, folded_deg=folded, commanded=length)
                )
    return out


def turn_speed(plan: Plan, robot: RobotDescription) -> float:
    """The speed of the curved MOVEs, m/s: the plan's, else the middle of the robot's speed range."""
    return (
        plan.turn_speed
        if plan.turn_speed is not None
        else round(0.5 * sum(speed_range(robot, plan.move_length)), 2)
    )


def turning_runs(runner: Runner, plan: Plan, k: float) -> list[RunResult]:
    """Curved MOVEs at each curvature and sign on the turn courses, each of the reference length
    (``plan.move_length``, K_l's); ``p_arg`` is the firmware's K_t power argument K * max|rim_w| *
    |V C| for the K in the controller.

    One length for every curvature, as K_l and K_r are fitted for one reference amount: a MOVE's turn
    starts from rest with it, and the share of the turn that start loses grows as the MOVE shortens
    (a fixed turn of 120 degrees made the MOVEs at 7/m 0.3 m long, 0.46 s, where omni4 on course 45
    turned 0.78 of what a 1.2 m MOVE of the same tables turned, 1.15), so K_t at high power carried
    the start of the shortest MOVEs."""
    robot = runner.robot
    speed = turn_speed(plan, robot)
    c_max = robot.limits.curvature_max
    out: list[RunResult] = []
    rot = runner.geometry.rotation_factor()
    speed = round(speed, 2)  # the protocol's resolution: cm/s, cm, 0.1/m
    length = round(min(plan.move_length, 0.95 * robot.limits.distance_max), 2)
    for curvature in plan.turn_curvatures:
        c = round(min(curvature, 0.95 * c_max), 1)
        for course in plan.turn_courses_deg:
            for sign in (1, -1):
                cc = sign * c
                info = RunInfo(
                    TURN, f"curved move, course {course:g} deg, {length:.2f} m at {speed:g} m/s, C {cc:g}/m"
                )
                runner.note(f"turn C {cc:g}")

                def send(course: float = course, cc: float = cc, length: float = length) -> Command:
                    return runner.client.move(length, speed, math.radians(course), cc)

                r = runner.run(
                    info,
                    send,
                    length / speed,
                    "turn",
                    course_deg=course,
                    sign=sign,
                    commanded=length * c,
                    p_arg=k * rot * speed * c,
                )
                out.append(r)
    return out


def drive_square(runner: Runner, side: float, speed: float, rate: float, ccw: bool) -> SquareRun:
    """Four legs on course 0 with a +-90 degree ROTATE after each, each from rest; logged."""
    client = runner.client
    turn = math.pi / 2 if ccw else -math.pi / 2
    side, speed = round(side, 2), round(speed, 2)
    duration = 4 * (side / speed + abs(turn) / rate)
    direction = "ccw" if ccw else "cw"

    def send() -> str:
        for _ in range(4):  # each motion from rest, as UMBmark stops at the corners
            client.move(side, speed)
            client.wait_idle(timeout=side / speed + 10.0)
            client.sleep(runner.settle)
            client.rotate(turn, rate)
            client.wait_idle(timeout=abs(turn) / rate + 10.0)
            client.sleep(runner.settle)
        return f"square {direction}: 4 x (MOVE {side:g} m at {speed:g} m/s; ROTATE {math.degrees(turn):+.0f} deg)"

    runner.tap.record()
    info = RunInfo(SQUARE, f"square {direction}, side {100 * side:.0f} cm")
    result = runner.run(info, send, duration, "square", sign=1 if ccw else -1, commanded=side)
    return SquareRun(ccw, side, result, runner.tap.take_log())
