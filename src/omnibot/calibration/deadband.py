"""The dead band: the lowest power that moves the robot (a coarse upward sweep, then bisection), per
straight course pattern and for rotation, the mean over several wheel positions."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

from omnibot.calibration.patterns import course_pattern, rotation_pattern
from omnibot.calibration.runner import Runner
from omnibot.calibration.runs import ROTATE, STRAIGHT, RunInfo, RunResult

MOVED_DISTANCE = 0.005
"""m: a run that goes less than this did not move the robot (dead band search)."""
MOVED_ANGLE = math.radians(1.0)
"""rad: the same for rotations."""


@dataclass(frozen=True)
class Deadband:
    """The lowest power (PWM counts of the busiest motor) that moved the robot, per pattern."""

    group: str
    power: int
    """pwm_max + 1 when nothing moved the robot."""


def _moved(result: RunResult, rotation: bool) -> bool:
    m = result.truth
    if m is None:
        return False
    if rotation:
        return m.theta is not None and abs(m.theta) >= MOVED_ANGLE
    d = m.distance
    return d is not None and d >= MOVED_DISTANCE


def find_deadband(
    runner: Runner, course_deg: float | None, step: int = 8, duration: float = 0.5, positions: int = 1
) -> Deadband:
    """Lowest moving power for the straight pattern of ``course_deg`` (None: rotation in place), the
    mean over ``positions`` wheel positions (:func:`spread_deadband`)."""
    geo = runner.geometry
    rotation = course_deg is None
    group = "rotation" if rotation else f"course:{geo.fold(course_deg or 0.0):g}"
    flip = [0]

    def attempt(power: int) -> bool:
        flip[0] ^= 1
        if rotation:
            pattern = rotation_pattern(geo, power, ccw=bool(flip[0]), motors=runner.motors, rate=runner.rate)
            info = RunInfo(ROTATE, f"dead band, rotation, power {power}")
        else:
            c = (course_deg or 0.0) + (0.0 if flip[0] else 180.0)
            pattern = course_pattern(geo, c, power, runner.motors, runner.rate)
            info = RunInfo(STRAIGHT, f"dead band, course {c:g} deg, power {power}", math.radians(c))
        runner.note(f"dead band {group}: {power}")
        result = runner.power_run(pattern, duration, info, f"deadband:{group}", power=power)
        return _moved(result, rotation)

    return Deadband(group, spread_deadband(runner, attempt, step, positions))


def spread_deadband(runner: Runner, attempt: Callable[[int], bool], step: int, positions: int) -> int:
    """The dead band of ``attempt``'s pattern as the mean over ``positions`` wheel positions.

    Near the dead band a run barely turns the wheels, so where they stand decides how hard their
    rollers drag (seed 000: up to twice) and a single search lands several counts off the power a
    motion that turns the wheels through every position needs. The first search runs from zero;
    before each further one a ROTATE (:func:`turn_wheels`) turns every wheel on by ``1 +
    1 / positions`` roller pitches, and the search brackets the first result (a few runs)."""
    pwm_max = runner.geometry.pwm_max
    first = lowest_moving(attempt, step, pwm_max)
    found = [first]
    if first <= pwm_max:
        for _ in range(1, positions):
            turn_wheels(runner, 1.0 + 1.0 / positions)
            found.append(lowest_moving(attempt, step, pwm_max, near=first))
    return round(sum(found) / len(found))


TURN_RATE = math.radians(60.0)
"""rad/s of the ROTATEs that move the wheels on between dead-band searches."""


def turn_wheels(
    runner: Runner, pitches: float, group: str = "deadband:turn", what: str = "dead band"
) -> RunResult:
    """ROTATE in place so that every wheel turns by about ``pitches`` of its roller pitch (the
    described radius and roller count; counter-clockwise for ``pitches`` > 0, the direction in which
    omni4's wheels count up). The robot stays where it is; only its heading changes."""
    robot, geo = runner.robot, runner.geometry
    pitch = max(2.0 * math.pi * w.radius / w.rollers.count for w in robot.wheels)  # m of rim per roller
    angle = pitches * pitch / min(abs(v) for v in geo.rotation_rim())
    info = RunInfo(ROTATE, f"wheels on: rotate {math.degrees(angle):.1f} deg")
    runner.note(f"{what}: wheels on")
    return runner.run(info, partial(runner.client.rotate, angle, TURN_RATE), abs(angle) / TURN_RATE, group)


def lowest_moving(attempt: Callable[[int], bool], step: int, pwm_max: int, near: int | None = None) -> int:
    """The lowest power for which ``attempt(power)`` (a run) moved the robot: upwards in ``step``
    counts, then bisection to 2 counts; ``pwm_max + 1`` when not even full power moved it. ``near``:
    an earlier search's result; the search then starts ``step`` below it in half steps."""
    low, high = 0, None
    power = step
    if near is not None:
        low = max(0, min(near, pwm_max) - step)
        step = max(2, step // 2)
        power = low + step
    while power <= pwm_max:
        if attempt(power):
            high = power
            break
        low = power
        power += step
    if high is None:
        if low < pwm_max and attempt(pwm_max):
            high = pwm_max
        else:
            return pwm_max + 1
    while high - low > 2:
        mid = (low + high) // 2
        if attempt(mid):
            high = mid
        else:
            low = mid
    return high
