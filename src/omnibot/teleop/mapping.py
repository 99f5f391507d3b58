"""Pure mapping from pad axes and buttons to a body twist, and limits that keep its direction.

::

    JoyState(axes, buttons)  -- ROS joy convention: stick up / left = +1, values in [-1, 1]
      -> deadzone(): |a| <= deadzone reads 0, the rest rescaled to reach 1 at full (joy_node)
      -> joy_to_command(): enable / turbo buttons pick the scales (teleop_twist_joy)
           twist = (scale_linear.x * a[axis_linear.x], scale_linear.y * a[axis_linear.y],
                    scale_angular.yaw * a[axis_angular.yaw])
      -> limit_twist(): one factor s <= 1 for the whole twist, so that |(vx, vy)| <= speed and
           |w| <= rate: the robot goes where the stick points, only slower
      -> TwistRamp: while the deadman is held, the twist sent changes by at most the robot's
           acceleration_max (translation) and angular_acceleration_max per second, on a known
           floor times the share its grip leaves at the speed ramped from: a heavy robot ramps
           up, and a tap of a key is a short move

An axis or button index past what the pad has reads 0 / not pressed (as in teleop_twist_joy). The
turbo button is an enable button of its own, with the turbo scales.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from omnibot.client import Limits
from omnibot.control import Grip, grip_share
from omnibot.motion import ZERO, Twist
from omnibot.robot import RobotDescription
from omnibot.teleop.config import TeleopConfig


@dataclass(frozen=True)
class JoyState:
    """One reading of a pad (or of a stand-in: the keyboard, a browser's gamepad).

    ``axes`` follow ROS joy's convention (stick up and left positive), ``buttons`` are 0/1;
    ``time`` is when it was read (the clock of whoever reads it).
    """

    axes: tuple[float, ...] = ()
    buttons: tuple[int, ...] = ()
    time: float = 0.0

    def axis(self, index: int | None) -> float:
        """Axis ``index``'s deflection, 0.0 when unmapped (None) or absent on this pad."""
        if index is None or not 0 <= index < len(self.axes):
            return 0.0
        return self.axes[index]

    def button(self, index: int | None) -> bool:
        """Whether button ``index`` is pressed; False when unmapped (None) or absent on this pad."""
        return index is not None and 0 <= index < len(self.buttons) and bool(self.buttons[index])


@dataclass(frozen=True)
class TeleopCommand:
    """What the pad asks for: ``enabled`` is the deadman (enable or turbo button held)."""

    twist: Twist
    enabled: bool
    turbo: bool = False


def deadzone(value: float, zone: float) -> float:
    """joy_node's deadzone: 0 inside ``zone``, outside it rescaled so that +-1 still reads +-1."""
    v = max(-1.0, min(1.0, value)) if math.isfinite(value) else 0.0
    if abs(v) <= zone:
        return 0.0
    return math.copysign((abs(v) - zone) / (1.0 - zone), v)


def joy_to_command(config: TeleopConfig, joy: JoyState) -> TeleopCommand:
    """The twist a pad reading asks for (not limited yet), and whether the deadman is held."""
    turbo = joy.button(config.turbo_button)
    enabled = turbo or joy.button(config.enable_button) or not config.require_enable_button
    if not enabled:
        return TeleopCommand(ZERO, enabled=False)
    lin = config.scale_linear_turbo if turbo else config.scale_linear
    ang = config.scale_angular_turbo if turbo else config.scale_angular

    def value(index: int | None, scale: float | None, normal: float | None) -> float:
        s = scale if scale is not None else normal  # a turbo scale not given: the normal one
        if index is None or s is None:
            return 0.0
        return s * deadzone(joy.axis(index), config.deadzone)

    axes_l, axes_a = config.axis_linear, config.axis_angular
    twist = Twist(
        value(axes_l.x, lin.x, config.scale_linear.x) + 0.0,
        value(axes_l.y, lin.y, config.scale_linear.y) + 0.0,
        value(axes_a.yaw, ang.yaw, config.scale_angular.yaw) + 0.0,
    )
    return TeleopCommand(twist, enabled=True, turbo=turbo)


@dataclass(frozen=True)
class TwistLimits:
    """The largest planar speed (m/s) and turn rate (rad/s) a twist may have, and how fast a person's
    twist may change: ``accel`` (m/s^2, the translation) and ``angular_accel`` (rad/s^2); inf: at once.
    ``grip``: (speeds m/s, fractions), the share of both accelerations the floor's grip leaves at
    each speed (:func:`~omnibot.control.reach.floor_grip`), interpolated; None: all of them."""

    speed: float
    rate: float
    accel: float = math.inf
    angular_accel: float = math.inf
    grip: Grip | None = None

    @classmethod
    def from_limits(
        cls,
        limits: Limits,
        config: TeleopConfig | None = None,
        robot: RobotDescription | None = None,
        surface: str | None = None,
    ) -> TwistLimits:
        """The controller's VEL bounds (as the client checks them) just inside, so that rounding
        to 1 cm/s and 1 degree/s never crosses them; capped by the config's speed caps. ``robot``'s
        description gives the accelerations (its ``limits.acceleration_max`` and
        ``angular_acceleration_max``); without it a twist changes at once. ``surface``: the floor
        the robot drives on, whose grip shares the accelerations out up to the top speed (as the
        planner's :meth:`~omnibot.control.paths.MotionLimits.grip_at`); None: a floor not known,
        the accelerations whole."""
        speed = max(0.0, limits.speed_max_cms - 1.0) / 100.0
        rate = math.radians(max(0.0, limits.rate_max_dps - 1.0))
        if config is not None:
            if config.speed_max is not None:
                speed = min(speed, config.speed_max)
            if config.angular_speed_max is not None:
                rate = min(rate, config.angular_speed_max)
        if robot is None:
            return cls(speed, rate)
        grip = None
        if surface is not None and speed > 0:
            from omnibot.control import grip_table

            grip = grip_table(robot, surface, speed)
        return cls(speed, rate, robot.limits.acceleration_max, robot.limits.angular_acceleration_max, grip)

    def grip_at(self, speed: float) -> float:
        """The share of the accelerations the floor's grip leaves at ``speed`` m/s (1 without a floor)."""
        return float(grip_share(self.grip, speed))


class TwistRamp:
    """A twist rate-limited to ``limits``' accelerations: :meth:`step` moves the last twist towards
    the one asked by at most ``accel * dt`` (the translation, as a vector: the robot's velocity
    turns as fast as it can) and ``angular_accel * dt`` (the turn rate), both times the share the
    floor's grip leaves at the speed it ramps from (:meth:`TwistLimits.grip_at`).

    :attr:`body_accel` is the body's acceleration of the last step along its own axes and the
    angular one (m/s^2, m/s^2, rad/s^2): the rate of change of the body-frame twist less the turning
    axes' part ``(-w vy, w vx)``, as VEL's version-4 fields carry it, so the controller's wheel-speed
    loop feeds the ramp's force forward."""

    def __init__(self, limits: TwistLimits) -> None:
        self.limits = limits
        self.twist = ZERO
        self.body_accel: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def limited(self) -> bool:
        """The limits ramp anything (a finite acceleration)."""
        return math.isfinite(self.limits.accel) or math.isfinite(self.limits.angular_accel)

    def reset(self, twist: Twist = ZERO) -> None:
        """Start from ``twist`` (a stop: the robot is braked to rest by the controller)."""
        self.twist = twist
        self.body_accel = (0.0, 0.0, 0.0)

    def step(self, target: Twist, dt: float) -> Twist:
        """The twist ``dt`` s after the last one, on its way to ``target``."""
        last = self.twist
        if not dt > 0:
            return last
        dvx, dvy, dw = target.vx - last.vx, target.vy - last.vy, target.w - last.w
        dv = math.hypot(dvx, dvy)
        share = self.limits.grip_at(math.hypot(last.vx, last.vy))
        most = self.limits.accel * share * dt
        if dv > most:
            dvx, dvy = dvx * most / dv, dvy * most / dv
        most = self.limits.angular_accel * share * dt
        dw = max(-most, min(most, dw))
        twist = Twist(last.vx + dvx, last.vy + dvy, last.w + dw)
        self.body_accel = (dvx / dt - twist.w * twist.vy, dvy / dt + twist.w * twist.vx, dw / dt)
        self.twist = twist
        return twist


def limit_twist(twist: Twist, limits: TwistLimits) -> Twist:
    """Scale the whole twist by one factor (<= 1) so it is within ``limits``: same direction, same
    ratio of translation to turning, only slower."""
    k = 1.0
    speed = math.hypot(twist.vx, twist.vy)
    if speed > limits.speed:
        k = min(k, limits.speed / speed)
    if abs(twist.w) > limits.rate:
        k = min(k, limits.rate / abs(twist.w))
    return twist if k >= 1.0 else twist.scaled(k)


def fractions_to_twist(vx: float, vy: float, w: float, limits: TwistLimits) -> Twist:
    """A twist from fractions of the limits (-1..1 each; an on-screen stick or keys), limited."""
    return limit_twist(Twist(vx * limits.speed, vy * limits.speed, w * limits.rate), limits)


def axes_tuple(values: Sequence[float]) -> tuple[float, ...]:
    """Axis values as a tuple of floats clamped to [-1, 1] (NaN reads 0)."""
    return tuple(max(-1.0, min(1.0, float(v))) if math.isfinite(v) else 0.0 for v in values)
