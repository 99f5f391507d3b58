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
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any

from omnibot.calibration.patterns import Geometry, course_pattern, rotation_pattern, top_power
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.truth import ROTATE, STRAIGHT, TURN, Motion, RunInfo, TruthSource, relative
from omnibot.client.client import RobotClient
from omnibot.client.events import WarnEvent
from omnibot.errors import ConfigError
from omnibot.progress import Progress
from omnibot.protocol import text
from omnibot.protocol.messages import Command
from omnibot.robot.description import MotorMapSpec, RobotDescription

MOVED_DISTANCE = 0.005
"""m: a run that goes less than this did not move the robot (dead band search)."""
MOVED_ANGLE = math.radians(1.0)
"""rad: the same for rotations."""
SHORTEST_MOVE = 1.0
"""s: the calibration covers speeds at which a MOVE of the reference length lasts at least this."""
STILL_TIMEOUT = 5.0
"""s the runner waits at most for the encoders to stop after a run."""


def speed_range(robot: RobotDescription, length: float) -> tuple[float, float]:
    """(slowest, fastest) MOVE speed the calibration and its checks cover for moves of ``length``:
    the robot's limits, the top cut to where such a MOVE still lasts :data:`SHORTEST_MOVE` (a 30 kg
    robot's 5 m/s is not for 1 m moves)."""
    lim = robot.limits
    hi = min(lim.speed_max, length / SHORTEST_MOVE)
    lo = max(lim.speed_min, 0.1 * hi) if lim.speed_min > 0 else 0.2 * hi
    return min(lo, hi), hi


@dataclass(frozen=True)
class Plan:
    """How much to measure. The defaults suit the simulator; :meth:`quick` a real robot and a tape."""

    course_count: int = 4
    """Calibrated courses, evenly from 0 to the robot's largest folded course (omni4: 0, 15, 30, 45)."""
    courses_deg: tuple[float, ...] | None = None
    """Explicit calibrated courses (folded degrees); overrides ``course_count``."""
    directions: int = 4
    """Raw courses per calibrated course (course + each idle axis and its opposite)."""
    probe: float = 1.0
    """s of power of the first run at the lowest power level (later levels: from the rate so far)."""
    t_min: float = 0.15
    """Shortest run, s."""
    rotate_rate_min: float = 0.5
    """rad/s: the slowest rotation the sweep needs to time (sets the longest rotation run)."""
    levels: int = 8
    """Power levels from the dead band to full power (denser near the dead band)."""
    deadband_step: int = 8
    settle: float = 0.4
    """s to wait after a run for the robot to coast to a stop before measuring."""
    speed_margin: float = 1.2
    """A sweep stops above this times the robot's top speed."""
    move_length: float = 1.0
    """m: the MOVE length the translation fit is exact for (start/stop losses are per move)."""
    rotate_angle: float = math.radians(135.0)
    """rad: the ROTATE angle the rotation fit is exact for."""
    turn_courses_deg: tuple[float, ...] = (0.0, 45.0)
    turn_curvatures: tuple[float, ...] = (1.0, 2.0, 4.0, 7.0)
    """1/m, each run with both signs (clipped to the robot's curvature limit)."""
    turn_speed: float | None = None
    """m/s of the curved MOVEs (default: the middle of the robot's speed range)."""
    turn_angle: float = math.radians(120.0)
    """rad the body should turn in one curved MOVE (its length follows, 0.3..1.5 m)."""
    turn_rounds: int = 2
    gyro_still: float = 3.0
    """s of standstill for the gyro bias."""
    rotation_turns: float = 2.0
    """Full turns each way of the rotation test (gyro scale, wheel base)."""
    square_side: float = 1.0
    square_speed: float | None = None
    motor_map: bool = True
    """Fit the motor map (each motor's dead-band offset and gain table) before the sweeps."""
    balance_levels: int = 4
    """Nominal powers of the balance runs, spread over what the speed range needs."""
    roller_rounds: int = 4
    """Rounds of the idle axes at each power for the idle wheels' roller drag (rollers.py; 0: none)."""
    slip: bool = True
    """Drive the wheel-slip runs (12 out-and-back, wheel-speed loop on) and fit the floor's creep."""

    @classmethod
    def quick(cls) -> Plan:
        """Seed 000's own scope: courses 0 and 45 (fold range ends), two directions, fewer powers."""
        return cls(course_count=2, directions=2, levels=6, turn_curvatures=(2.0, 5.0), turn_rounds=1)

    def calibrated_courses(self, geometry: Geometry) -> list[float]:
        top = geometry.fold_max
        if self.courses_deg is not None:
            bad = [c for c in self.courses_deg if not 0.0 <= c <= top + 1e-9]
            if bad or list(self.courses_deg) != sorted(set(self.courses_deg)):
                raise ConfigError(
                    f"calibrated courses must increase strictly within 0..{top:g} degrees for this robot, "
                    f"got {list(self.courses_deg)}",
                    key="courses",
                )
            return [float(c) for c in self.courses_deg]
        n = max(1, self.course_count)
        return [0.0] if n == 1 else [round(top * k / (n - 1), 3) for k in range(n)]


@dataclass(frozen=True)
class RunResult:
    """One run: what was commanded, what the truth and the robot's own sensors say it did."""

    kind: str
    group: str
    """``course:<folded deg>``, ``rotation``, ``deadband:...``, ``turn``, ``square``, ``gyro``."""
    command: str
    duration: float
    """s the motors were driven (POWER T, MOVE L/V, ROTATE A/F)."""
    truth: Motion | None
    odometry: Motion | None = None
    gyro: float | None = None
    """Heading change (rad) integrated by the controller from its gyro, bias included."""
    gyro_time: float | None = None
    """Controller seconds between the gyro marks."""
    power: int | None = None
    course_deg: float | None = None
    folded_deg: float | None = None
    sign: int = 1
    commanded: float | None = None
    """Commanded amount of a MOVE (m) or a turn (rad)."""
    p_arg: float | None = None
    """The firmware's power argument of the calibrated part (K times the busiest rim speed)."""
    warnings: tuple[int, ...] = ()
    counts: tuple[int, ...] | None = None
    """The controller's wheel encoder counts at the start (from telemetry), when it has encoders."""
    correction: float = 0.0
    """m added to a straight run's path by a later fit (the idle wheels' roller drag, rollers.py)."""

    @property
    def amount(self) -> float | None:
        """Path length (m, straight: the arc when the body turned, see :attr:`Motion.path`, plus
        :attr:`correction`) or angle (rad, rotations and turns, signed by the command) achieved."""
        if self.truth is None:
            return None
        if self.kind == STRAIGHT:
            path = self.truth.path
            return None if path is None else path + self.correction
        return None if self.truth.theta is None else self.sign * self.truth.theta

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            k: v for k, v in self.__dict__.items() if k not in ("truth", "odometry") and v is not None
        }
        for key in ("truth", "odometry"):
            m = getattr(self, key)
            if m is not None:
                out[key] = {k: v for k, v in m.__dict__.items() if v is not None}
        out["warnings"] = list(self.warnings)
        return out


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
    log: list[RunResult] = field(default_factory=list)
    _warns: list[int] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.geometry = Geometry.of(self.robot)
        self.client.on_warn(self._warn)

    def _warn(self, event: WarnEvent) -> None:
        self._warns.append(event.code)

    def close(self) -> None:
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
        self._settle()
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

    def _settle(self) -> None:
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


def find_deadband(runner: Runner, course_deg: float | None, step: int = 8, duration: float = 0.5) -> Deadband:
    """Lowest moving power for the straight pattern of ``course_deg`` (None: rotation in place)."""
    geo = runner.geometry
    rotation = course_deg is None
    group = "rotation" if rotation else f"course:{geo.fold(course_deg or 0.0):g}"
    flip = [0]

    def attempt(power: int) -> bool:
        flip[0] ^= 1
        if rotation:
            pattern = rotation_pattern(geo, power, ccw=bool(flip[0]), motors=runner.motors)
            info = RunInfo(ROTATE, f"dead band, rotation, power {power}")
        else:
            c = (course_deg or 0.0) + (0.0 if flip[0] else 180.0)
            pattern = course_pattern(geo, c, power, runner.motors)
            info = RunInfo(STRAIGHT, f"dead band, course {c:g} deg, power {power}", math.radians(c))
        runner.note(f"dead band {group}: {power}")
        result = runner.power_run(pattern, duration, info, f"deadband:{group}", power=power)
        return _moved(result, rotation)

    return Deadband(group, lowest_moving(attempt, step, geo.pwm_max))


def lowest_moving(attempt: Callable[[int], bool], step: int, pwm_max: int) -> int:
    """The lowest power for which ``attempt(power)`` (a run) moved the robot: upwards in ``step``
    counts, then bisection to 2 counts; ``pwm_max + 1`` when not even full power moved it."""
    low, high = 0, None
    power = step
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


def _rotation_pattern(geo: Geometry, ccw: bool, motors: MotorMapSpec | None, power: int) -> list[int]:
    return rotation_pattern(geo, power, ccw, motors)


def _rotation_info(ccw: bool, power: int, duration: float) -> RunInfo:
    return RunInfo(ROTATE, f"rotation {'ccw' if ccw else 'cw'}, power {power} for {duration:g} s")


def straight_sweep(runner: Runner, plan: Plan, folded_deg: float, deadband: int) -> list[RunResult]:
    """Straight POWER runs on every raw course folding to ``folded_deg``, powers upward."""
    geo = runner.geometry
    targets = [
        Target(
            pattern=partial(course_pattern, geo, raw, motors=runner.motors),
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
            pattern=partial(_rotation_pattern, geo, ccw, runner.motors),
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


def turn_speed(plan: Plan, robot: RobotDescription) -> float:
    return (
        plan.turn_speed
        if plan.turn_speed is not None
        else round(0.5 * sum(speed_range(robot, plan.move_length)), 2)
    )


def turning_runs(runner: Runner, plan: Plan, k: float) -> list[RunResult]:
    """Curved MOVEs at each curvature and sign on the turn courses; ``p_arg`` is the firmware's K_t
    power argument K * max|rim_w| * |V C| for the K in the controller."""
    robot = runner.robot
    speed = turn_speed(plan, robot)
    c_max = robot.limits.curvature_max
    out: list[RunResult] = []
    rot = runner.geometry.rotation_factor()
    speed = round(speed, 2)  # the protocol's resolution: cm/s, cm, 0.1/m
    for curvature in plan.turn_curvatures:
        c = round(min(curvature, 0.95 * c_max), 1)
        length = round(min(max(plan.turn_angle / c, 0.3), 1.5, 0.95 * robot.limits.distance_max), 2)
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
