"""Bringing the robot to rest at a goto leg's end, the runtime cycling: braked on its motors, or
its motors cut where its coast stops it as soon.

STOP cuts the motors: the robot coasts, slowed only by its wheels' friction (the description's
``stop_deceleration``: 0.32 m/s^2 for omni3's 30 kg, where its motors brake it at 2.5 m/s^2). A leg
that an obstacle ends at 1.6 m/s, cut, travels 4 m; with goto then waiting blind (no runtime
cycles: no estimate, no scans for the localiser) and planning the next leg from where the robot
was, not where it coasted to, the next leg starts on a stale pose with the robot still moving.

:class:`BrakeSource` is a runtime source that takes the twist last asked of the robot down to rest at
the robot's accelerations (:class:`~omnibot.teleop.TwistRamp`, the ramp teleop's twists take; the
controller's own brake to rest on a VEL let go uses the same limits), then holds a zero twist until
the estimate says the robot is still; the runtime keeps cycling meanwhile, so the estimate and the
localiser follow the robot to where it comes to rest. Where the coast stops the robot nearly as
soon (:func:`coast_excess` within the planner's margin: omni4, whose friction stops it harder than
its motors may, and mecanum4 at its speeds) the motors are better cut: the wheels then roll free
with the body and the encoders count its travel, where braking on them slips (omni4's odometry
0.3-1.6 cm worse at the end of the legs after a re-plan); ``cut=True`` proposes nothing and only
waits, the runtime cycling, for the estimate to say still.
"""

from __future__ import annotations

import math

from omnibot.motion import Twist
from omnibot.robot import RobotDescription
from omnibot.runtime import Cycle, Proposal, must_end
from omnibot.teleop import TwistLimits, TwistRamp

STILL_SPEED = 0.01
"""m/s: slower than this (and :data:`STILL_RATE`) the robot is still."""
STILL_RATE = math.radians(1.0)
"""rad/s: the turn rate below which the robot is still."""
STILL_FOR = 0.1
"""s the estimate must say still before the brake is done."""
BRAKE_PRIORITY = 20
"""The brake's priority: goto's own (above a path follower, below every person and ROS 2's cmd_vel)."""


def coast_excess(robot: RobotDescription, speed: float) -> float:
    """m a coast from ``speed`` (the motors cut: the description's ``stop_deceleration``) carries
    the robot beyond a brake on its motors at its ``acceleration_max`` (<= 0: the coast stops it
    as soon)."""
    return 0.5 * speed * speed * (1.0 / robot.stop_deceleration - 1.0 / robot.limits.acceleration_max)


class BrakeSource:
    """A source: ``start`` (the twist last asked of the robot) ramped to rest at ``robot``'s
    accelerations, then zero until the estimate is still for :data:`STILL_FOR` s (``cut``: the
    motors were cut, it proposes nothing and waits for still alone). :attr:`finished`
    once it is, or after the longest the robot may need (coasting from ``start`` at its stop
    deceleration, plus a second); :attr:`failure` says why it ended early (a refused command, an
    emergency stop, a stall: ``must_end``)."""

    def __init__(
        self,
        robot: RobotDescription,
        start: Twist,
        period: float,
        *,
        name: str = "brake",
        priority: int = BRAKE_PRIORITY,
        watchdog: float = 0.15,
        cut: bool = False,
    ) -> None:
        lim = robot.limits
        self._ramp = TwistRamp(
            TwistLimits(math.inf, math.inf, lim.acceleration_max, lim.angular_acceleration_max)
        )
        self._ramp.reset(start)
        self.limit = math.hypot(start.vx, start.vy) / robot.stop_deceleration + 1.0
        """s the brake waits for the robot to be still at most."""
        self.name, self.priority, self.watchdog = name, priority, watchdog
        self.period = period
        self.timeout = max(2.0 * period, 0.05)
        self.wait_reply = False
        self.cut = cut
        self.finished = False
        self.failure = ""
        self.still = False
        """The estimate said the robot was still when the brake ended."""
        self.accel = 0.0
        """m/s^2: the ramp's rate of change of speed (sent with the VEL to a controller that takes it)."""
        self.body_accel: tuple[float, float, float] | None = None
        """The ramp's body acceleration (sent with the VEL to a controller of version 4)."""
        self._t0 = math.nan
        self._still_since = math.nan

    def propose(self, cycle: Cycle) -> Proposal | None:
        """This cycle's twist on the way to rest; None once finished."""
        if self.finished:
            return None
        why = must_end(cycle, self.name)
        if why:
            self.failure = why
            self.finished = True
            return None
        t = cycle.t
        if math.isnan(self._t0):
            self._t0 = t
        twist = Twist()
        if not self.cut:
            before = self._ramp.twist
            twist = self._ramp.step(twist, self.period)
            self.accel = (math.hypot(*twist[:2]) - math.hypot(*before[:2])) / self.period
            self.body_accel = self._ramp.body_accel
        if twist.is_zero and _still(cycle):
            if math.isnan(self._still_since):
                self._still_since = t
            if t - self._still_since >= STILL_FOR - 1e-9:
                self.still = True
                self.finished = True
        else:
            self._still_since = math.nan
        if t - self._t0 > self.limit:
            self.finished = True
        return None if self.cut else Proposal(twist)


def _still(cycle: Cycle) -> bool:
    """The cycle's estimate says the robot is still (False without one)."""
    body = cycle.achieved
    return body is not None and math.hypot(body.vx, body.vy) < STILL_SPEED and abs(body.w) < STILL_RATE


__all__ = ["BrakeSource", "coast_excess"]
