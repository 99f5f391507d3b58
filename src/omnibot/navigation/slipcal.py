"""Wheel-slip calibration drive: straight runs in every direction, fitted by :func:`fit_slip`.

The robot drives out and back along evenly spaced courses (11.25, 191.25, 33.75, ... degrees, so it ends
near where it started), out at full speed and back at half of it on gentler ramps, with its
wheel-speed loop and its heading held by the gyro, each run from rest to rest. For each run the
encoders' displacement is compared with the truth's (a :class:`RunTruth`: the simulator, or any of
``omnibot calibrate``'s truth sources, e.g. a tape measure typed in), and the floor's wheel slip
(:class:`~omnibot.estimation.slip.SlipParameters`) comes out of one least-squares fit. Runs the
truth cannot measure are left out.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

from omnibot.errors import ConfigError
from omnibot.estimation import SlipLeg, SlipParameters, SlipProbe, fit_slip, leg_error
from omnibot.motion import Twist
from omnibot.navigation.runner import Navigator, ramp_fraction
from omnibot.robot import RobotDescription
from omnibot.robot.kinematics import body_to_world, world_to_body
from omnibot.runtime import ScriptSource


class RunTruth(Protocol):
    """Where a run really went: ``start()`` before it, ``displacement(mark, course)`` after it."""

    live: bool
    """It can also measure while the robot moves (then each speed-up is measured too, which pins
    down the acceleration term)."""

    def start(self) -> object:
        """A mark taken with the robot standing at the start of a run."""

    def displacement(self, mark: object, course: float) -> tuple[float, float] | None:
        """The true (x, y) since ``mark`` in the body frame at the run's start (m), for a run
        commanded along ``course`` (rad, same frame); None if this run cannot be measured."""


HEADING_GAIN = 4.0
"""1/s: heading hold while driving a run."""

RETURN_ACCEL = 0.25
"""The return runs' ramps, a share of the out runs' acceleration. A tyre's creep grows faster than
the force it transmits, so a ramp's creep is more than its drag's and its acceleration's; runs
whose ramps differ tell that excess (``ramp``) from the steady drag (``roll``)."""

SLIP_COURSES = 16
"""Runs of the slip calibration: courses every 22.5 degrees, so that on omni4 they cross the rollers
at 11.25 and 33.75 degrees off the axes (the combined drag's weight 0.38 and 0.92), which tells the
rolling creep from the combined drag's."""


@dataclass
class SlipCalibration:
    """The fitted coefficients and the runs they came from."""

    params: SlipParameters
    legs: list[SlipLeg] = field(default_factory=list)
    """The runs, from rest to rest."""
    courses_deg: list[float] = field(default_factory=list)
    """The course of each run in ``legs``, degrees."""
    robot: RobotDescription | None = None
    speed_ups: list[SlipLeg] = field(default_factory=list)
    """Each run's speed-up alone (only with a live truth): what pins down ``compliance``."""

    def errors(self, corrected: bool) -> list[float]:
        """Per run: |encoder - true displacement| / true distance, raw or with the fit applied."""
        params = self.params if corrected else None
        return [leg_error(leg, params, self.robot) for leg in self.legs]


def course_order(count: int) -> list[float]:
    """``count`` courses (even) evenly over the circle, each followed by its opposite, half a step off
    0 degrees: no course runs along a wheel's axis, so every wheel turns on every run and its rollers'
    drag averages over the wheel's angle, as the model's does (an idle wheel's drag depends on where
    it stopped, up to 2x, which made the fit depend on it)."""
    if count < 2 or count % 2:
        raise ConfigError(f"slip calibration needs an even number of courses >= 2, got {count}")
    half = 360.0 / count
    out = []
    for i in range(count // 2):
        out += [(i + 0.5) * half, (i + 0.5) * half + 180.0]
    return out


def drive_run(
    nav: Navigator,
    course: float,
    speed: float,
    distance: float,
    accel: float,
    at_cruise: Callable[[], object] | None = None,
) -> None:
    """One straight run along ``course`` (rad, body frame at the start) from rest to rest, a script on
    the navigator's runtime (:meth:`~omnibot.navigation.runner.Navigator.drive`); ``at_cruise`` is
    called once, 0.1 s into the cruise (the speed-up's creep then counted)."""
    heading0 = nav.estimator.estimate.theta
    t_acc = speed / accel
    cruise = max(0.0, distance - speed * t_acc) / speed
    total = 2.0 * t_acc + cruise
    cruising = at_cruise

    def run(t: float) -> Twist | str:
        nonlocal cruising
        if t >= total:
            return ScriptSource.END
        if cruising is not None and t >= t_acc + 0.1:
            cruising()
            cruising = None
        v = speed * ramp_fraction(t, total, t_acc)
        err = heading0 - nav.estimator.estimate.theta
        return Twist(v * math.cos(course), v * math.sin(course), HEADING_GAIN * err)

    nav.drive(run, name="slip-run")


def run_profile(index: int, speed: float, accel: float) -> tuple[float, float]:
    """The speed (m/s) and ramp acceleration (m/s^2) of the slip calibration's run ``index``: out
    (even) at ``speed`` and ``accel``, back at half the speed on :data:`RETURN_ACCEL` of the ramp."""
    return (speed, accel) if index % 2 == 0 else (0.5 * speed, RETURN_ACCEL * accel)


def calibrate_slip(
    nav: Navigator,
    truth: RunTruth,
    *,
    courses: int = SLIP_COURSES,
    speed: float = 0.3,
    distance: float = 0.5,
    accel: float = 1.0,
    settle: float = 0.4,
    fit_scale: bool = True,
    progress: Callable[[int, int], object] | None = None,
) -> SlipCalibration:
    """Drive ``courses`` runs of ``distance`` m and fit the floor's slip.

    Each course is driven out at ``speed`` m/s and back at half of it on gentler ramps
    (:func:`run_profile`): a radius error grows with the distance, creep with the time taken, its
    excess under a ramp with the acceleration squared, so the runs tell them apart (``fit_scale``:
    the distance scale too). ``nav`` must be prepared (telemetry on). ``truth`` measures each run;
    a ``live`` one each speed-up too, which pins down ``compliance``. ``progress(done, total)``
    after each run. ConfigError when fewer than two runs could be measured.
    """
    probe = SlipProbe(nav.robot)
    nav.runtime.telemetry_hooks.append(probe.update)
    legs: list[SlipLeg] = []
    speed_ups: list[SlipLeg] = []
    measured: list[float] = []
    order = course_order(courses)

    def world(disp: tuple[float, float], start: int) -> tuple[float, float]:
        x, y, _ = body_to_world((*disp, 0.0), probe.heading(start))
        return (float(x), float(y))

    try:
        for i, deg in enumerate(order):
            nav.client.sleep(settle)
            course = math.radians(deg)
            mark, start = truth.start(), probe.mark()

            def speed_up_done(mark: object = mark, start: int = start, course: float = course) -> None:
                disp = truth.displacement(mark, course)
                if disp is not None:
                    speed_ups.append(probe.leg(start, world(disp, start)))

            run_speed, run_accel = run_profile(i, speed, accel)
            drive_run(nav, course, run_speed, distance, run_accel, speed_up_done if truth.live else None)
            nav.client.sleep(settle)
            disp = truth.displacement(mark, course)
            if disp is not None:
                legs.append(probe.leg(start, world(disp, start)))
                measured.append(deg)
            if progress is not None:
                progress(i + 1, len(order))
    finally:
        nav.runtime.telemetry_hooks.remove(probe.update)
    if len(legs) < 2:
        raise ConfigError(
            f"wheel slip needs at least two measured runs; the truth measured {len(legs)} of {len(order)}"
        )
    params = fit_slip(nav.robot, legs + speed_ups, compliance=bool(speed_ups), scale=fit_scale, ramp=True)
    return SlipCalibration(params, legs, measured, nav.robot, speed_ups)


class SimulatorTruth:
    """The simulator's ground truth as a live :class:`RunTruth`."""

    live = True

    def __init__(self, nav: Navigator) -> None:
        if nav.sim is None:
            raise ConfigError("this link has no simulator ground truth; measure the runs instead")
        self.nav = nav

    def start(self) -> object:
        """Mark where the robot truly is now (the simulator's pose)."""
        return self.nav.truth()

    def displacement(self, mark: object, course: float) -> tuple[float, float] | None:
        """The true displacement since ``mark`` in the body frame of the mark's heading, m; None without
        truth."""
        now = self.nav.truth()
        if now is None or not isinstance(mark, tuple):
            return None
        x0, y0, th0 = mark
        x, y, _ = world_to_body((now[0] - x0, now[1] - y0, 0.0), th0)
        return (float(x), float(y))


def simulate_slip_calibration(
    robot: RobotDescription, surface: str | None = None, *, seed: int = 0, speed: float = 0.3
) -> SlipCalibration:
    """:func:`calibrate_slip` on the simulated robot (lockstep) with the simulator's truth."""
    from omnibot.navigation.session import simulated_client

    with simulated_client(robot, surface=surface, seed=seed) as client:
        nav = Navigator(client, robot)
        try:
            nav.prepare()
            return calibrate_slip(nav, SimulatorTruth(nav), speed=speed)
        finally:
            nav.close()


__all__: Sequence[str] = (
    "SLIP_COURSES",
    "RunTruth",
    "SimulatorTruth",
    "SlipCalibration",
    "calibrate_slip",
    "course_order",
    "drive_run",
    "run_profile",
    "simulate_slip_calibration",
)
