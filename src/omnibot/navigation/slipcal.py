"""Wheel-slip calibration drive: straight runs in every direction, fitted by :func:`fit_slip`.

The robot drives out and back along evenly spaced courses (0, 180, 30, 210, ... degrees, so it ends
near where it started) with its wheel-speed loop, heading held by the gyro, each run from rest to
rest with the acceleration limit; for each run the encoders' displacement is compared with the
truth's (the simulator, or a tape measure typed in), and the floor's creep coefficients
(:class:`~omnibot.estimation.slip.SlipParameters`) come out of one least-squares fit.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from omnibot.control.followers.base import Command
from omnibot.errors import ConfigError
from omnibot.estimation.slip import SlipLeg, SlipParameters, SlipProbe, fit_slip, leg_error
from omnibot.navigation.runner import Navigator
from omnibot.robot.description import RobotDescription

TruthProbe = Callable[[], tuple[float, float] | None]
"""The robot's true (x, y) now in the estimator's frame (None: unknown)."""

HEADING_GAIN = 4.0
"""1/s: heading hold while driving a run."""


@dataclass
class SlipCalibration:
    """The fitted coefficients and the runs they came from."""

    params: SlipParameters
    legs: list[SlipLeg] = field(default_factory=list)
    """The runs, from rest to rest."""
    courses_deg: list[float] = field(default_factory=list)
    robot: RobotDescription | None = None
    speed_ups: list[SlipLeg] = field(default_factory=list)
    """Each run's speed-up alone (only with a continuous truth): what pins down ``compliance``."""

    def errors(self, corrected: bool) -> list[float]:
        """Per run: |encoder - true displacement| / true distance, raw or with the fit applied."""
        params = self.params if corrected else None
        return [leg_error(leg, params, self.robot) for leg in self.legs]


def course_order(count: int) -> list[float]:
    """``count`` courses (even) evenly over the circle, each followed by its opposite."""
    if count < 2 or count % 2:
        raise ConfigError(f"slip calibration needs an even number of courses >= 2, got {count}")
    half = 360.0 / count
    out = []
    for i in range(count // 2):
        out += [i * half, i * half + 180.0]
    return out


def drive_run(
    nav: Navigator,
    course: float,
    speed: float,
    distance: float,
    accel: float,
    at_cruise: Callable[[], object] | None = None,
) -> None:
    """One straight run along ``course`` (rad, body frame at the start) from rest to rest;
    ``at_cruise`` is called once, 0.1 s into the cruise (the speed-up's creep then counted)."""
    c = nav.client
    heading0 = nav.estimator.estimate.theta
    period = 0.01
    t_acc = speed / accel
    cruise = max(0.0, distance - speed * t_acc) / speed
    total = 2.0 * t_acc + cruise
    t0 = c.clock.now()
    while (t := c.clock.now() - t0) < total:
        if at_cruise is not None and t >= t_acc + 0.1:
            at_cruise()
            at_cruise = None
        v = speed * min(1.0, t / t_acc, max(0.0, (total - t) / t_acc))
        err = heading0 - nav.estimator.estimate.theta
        nav.send(Command(v * math.cos(course), v * math.sin(course), HEADING_GAIN * err))
        c.sleep(period)
    c.stop()


def calibrate_slip(
    nav: Navigator,
    truth: TruthProbe,
    *,
    courses: int = 12,
    speed: float = 0.3,
    distance: float = 0.5,
    accel: float = 1.0,
    settle: float = 0.4,
    continuous: bool = False,
    progress: Callable[[int, int], object] | None = None,
) -> SlipCalibration:
    """Drive ``courses`` runs of ``distance`` m at ``speed`` m/s and fit the floor's slip.

    ``nav`` must be prepared (telemetry on). ``truth`` gives the true position before and after each
    run; with ``continuous`` (a truth that can be read while moving, like the simulator's) also
    once the speed-up is over, which pins down the acceleration term (``compliance``) as well.
    ``progress(done, total)`` is called after each run.
    """
    probe = SlipProbe(nav.robot)
    nav.client.on_telemetry(probe.update)
    legs: list[SlipLeg] = []
    speed_ups: list[SlipLeg] = []
    order = course_order(courses)
    try:
        for i, deg in enumerate(order):
            nav.client.sleep(settle)
            before, start = truth(), probe.mark()
            if before is None:
                raise ConfigError("slip calibration needs the true position before and after each run")

            def speed_up_done(before: tuple[float, float] = before, start: int = start) -> None:
                now = truth()
                if now is not None:
                    speed_ups.append(probe.leg(start, (now[0] - before[0], now[1] - before[1])))

            drive_run(nav, math.radians(deg), speed, distance, accel, speed_up_done if continuous else None)
            nav.client.sleep(settle)
            after = truth()
            if after is None:
                raise ConfigError("slip calibration needs the true position before and after each run")
            legs.append(probe.leg(start, (after[0] - before[0], after[1] - before[1])))
            if progress is not None:
                progress(i + 1, len(order))
    finally:
        nav.client.remove_listener(probe.update)
    params = fit_slip(nav.robot, legs + speed_ups, compliance=bool(speed_ups))
    return SlipCalibration(params, legs, order, nav.robot, speed_ups)


def simulator_truth(nav: Navigator) -> TruthProbe:
    """The simulator's ground truth as a :data:`TruthProbe` (ConfigError on a link without one)."""
    if nav.sim is None:
        raise ConfigError("this link has no simulator ground truth; measure the runs instead")

    def probe() -> tuple[float, float] | None:
        t = nav.truth()
        return None if t is None else (t[0], t[1])

    return probe


def simulate_slip_calibration(
    robot: RobotDescription, surface: str | None = None, *, seed: int = 0, speed: float = 0.3
) -> SlipCalibration:
    """:func:`calibrate_slip` on the simulated robot (lockstep) with the simulator's truth."""
    from omnibot.navigation.session import simulated_client

    with simulated_client(robot, surface=surface, seed=seed) as client:
        nav = Navigator(client, robot)
        try:
            nav.prepare()
            return calibrate_slip(nav, simulator_truth(nav), speed=speed, continuous=True)
        finally:
            nav.close()


__all__: Sequence[str] = (
    "SlipCalibration",
    "calibrate_slip",
    "course_order",
    "drive_run",
    "simulate_slip_calibration",
    "simulator_truth",
)
