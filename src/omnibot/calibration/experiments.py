"""Seed 000's calibration experiments, driven over the protocol through a RobotClient.

Nothing here knows whether the robot is real or simulated: every run is protocol commands (POWER,
MOVE, ROTATE) and a measurement by the chosen truth strategy, so the same code calibrates a board on
a serial port and the simulator in lockstep.

* :func:`find_deadband`: the lowest power that moves the robot (a coarse upward sweep, then
  bisection), per straight course pattern and for rotation.
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
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any

from omnibot.calibration.patterns import Geometry, Rate, course_pattern, rotation_pattern, top_power
from omnibot.calibration.plan import Plan, speed_range
from omnibot.calibration.runs import ROTATE, SQUARE, STRAIGHT, TURN, RunInfo, RunResult, relative
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.truth import TruthSource
from omnibot.calibration.umbmark import SquareRun
from omnibot.client import RobotClient, WarnEvent
from omnibot.progress import Progress
from omnibot.protocol import text
from omnibot.protocol.messages import Command
from omnibot.robot import MotorMapSpec, RobotDescription

MOVED_DISTANCE = 0.005
"""m: a run that goes less than this did not move the robot (dead band search)."""
MOVED_ANGLE = math.radians(1.0)
"""rad: the same for rotations."""
STILL_TIMEOUT = 5.0
"""s the runner waits at most for the encoders to stop after a run."""


@dataclass
class Runner:
    """Runs one command at a time and measures it (see the module docstring)."""

    client: RobotClient
    robot: RobotDescription
    truth: TruthSource
    tap: TelemetryTap
    settle: float = 0.4
    progress: Progress | None = None
    motors: MotorMapSpec | None = None
    """The motor map the sweeps' patterns go through (the firmware's, mirrored; None: raw)."""
    rate: Rate | None = None
    """The rim speed a nominal power gives, for the map's speed term (the balance runs' measure)."""
    log: list[RunResult] = field(default_factory=list)
    _warns: list[int] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.geometry = Geometry.of(self.robot)
        self.client.on_warn(self._warn)

    def _warn(self, event: WarnEvent) -> None:
        self._warns.append(event.code)

    def close(self) -> None:
        """Stop listening to the client's warnings."""
        self.client.remove_listener(self._warn)

    def run(
        self, info: RunInfo, send: Callable[[], Command | str], duration: float, group: str, **meta: Any
    ) -> RunResult:
        """Mark, ``send()`` (the command, or a text naming what was sent), wait for IDLE and the
        coast-down, measure."""
        mark = self.truth.mark()
        latest = self.tap.latest
        counts = tuple(latest.encoders) if latest is not None and latest.encoders else None
        odo0 = self.tap.odometry_pose
        h0, t0 = self.tap.heading, self._ctime()
        self._warns.clear()
        command = send()
        self.client.wait_idle(timeout=4.0 * duration + 10.0)  # saturation stretches a motion
        self.wait_still()
        truth = self.truth.measure(mark, info) if self.truth.can(info) else None
        odo1, h1, t1 = self.tap.odometry_pose, self.tap.heading, self._ctime()
        odometry = None
        if odo0 is not None and odo1 is not None:
            odometry = relative(odo0.x, odo0.y, odo0.theta, odo1.x, odo1.y, odo1.theta, "encoders")
        result = RunResult(
            kind=info.kind,
            group=group,
            command=command if isinstance(command, str) else text.encode(command).decode("ascii").strip(),
            duration=duration,
            truth=truth,
            odometry=odometry,
            gyro=None if h0 is None or h1 is None else h1 - h0,
            gyro_time=None if t0 is None or t1 is None else t1 - t0,
            warnings=tuple(self._warns),
            counts=counts,
            **meta,
        )
        self.log.append(result)
        if self.progress is not None:
            self.progress.update(1)
        return result

    def move(
        self,
        what: str,
        length: float,
        speed: float,
        course_deg: float,
        group: str,
        detail: str = "",
        **meta: Any,
    ) -> RunResult:
        """A straight MOVE of ``length`` m at ``speed`` m/s on ``course_deg``, run as :meth:`run` (its
        ``course_deg`` in the result); described as ``<what>: move <cm> cm at <speed> m/s on course
        <course> deg<detail>``."""
        course = math.radians(course_deg)
        info = RunInfo(
            STRAIGHT,
            f"{what}: move {100 * length:.0f} cm at {speed:g} m/s on course {course_deg:g} deg{detail}",
            course,
        )
        send = partial(self.client.move, length, speed, course)
        return self.run(info, send, length / speed, group, course_deg=course_deg, **meta)

    def wait_still(self) -> None:
        """Wait ``settle`` s, then until no encoder count moves (a heavy robot coasts for long)."""
        self.client.sleep(self.settle)
        last = self.tap.counts()
        waited = self.settle
        while last is not None and waited < STILL_TIMEOUT:
            self.client.sleep(0.1)
            waited += 0.1
            now = self.tap.counts()
            if now is None or all(abs(a - b) <= 1 for a, b in zip(now, last, strict=True)):
                break
            last = now

    def _ctime(self) -> float | None:
        return self.tap.latest.controller_time if self.tap.latest is not None else None

    def power_run(
        self, powers: Sequence[int], duration: float, info: RunInfo, group: str, **meta: Any
    ) -> RunResult:
        """One POWER run: ``powers`` per motor for ``duration`` s, measured as :meth:`run` does."""
        return self.run(info, lambda: self.client.power(duration, powers), duration, group, **meta)

    def note(self, message: str) -> None:
        """Show what is running next to the progress bar."""
        if self.progress is not None:
            self.progress.set_postfix_str(message)


# --------------------------------------------------------------------------- dead band


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
