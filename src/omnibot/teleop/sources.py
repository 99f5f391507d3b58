"""A person's sources of the runtime: teleop's mapping and deadman on :class:`~omnibot.runtime.Runtime`.

* :class:`DeadmanSource`: a person's input with teleop's deadman (drive while enabled, then
  ``stop_repeats`` zero twists, then silence); the dashboard sets :attr:`DeadmanSource.sample` from
  the page's stick, keys and browser gamepad. A fresh press of the deadman asks the runtime to
  release a latched emergency stop (:attr:`Proposal.fresh <omnibot.runtime.Proposal.fresh>`): a
  person who let go and pressed again.
* :class:`PadSource`: a joystick or the keyboard (a :class:`JoySource`) through teleop's mapping and
  limits (``omnibot teleop``, ``omnibot run --teleop``).
* :class:`RampedTwist`: a source's twists ramped at the robot's accelerations (a person's, ROS 2's
  ``cmd_vel``).
"""

from __future__ import annotations

from typing import Protocol

from omnibot.motion import ZERO, Twist
from omnibot.runtime import Cycle, Proposal
from omnibot.teleop.config import TeleopConfig
from omnibot.teleop.deadman import Action, Deadman, Phase, Sample, Why
from omnibot.teleop.mapping import JoyState, TwistLimits, TwistRamp, joy_to_command, limit_twist


class RampedTwist:
    """A source's twists ramped at the robot's accelerations (:class:`~omnibot.teleop.mapping.TwistRamp`
    on the link clock, the robot's own: a simulator paced to the wall clock falls behind it on a
    loaded machine, and a ramp timed on the wall would reach the robot steeper than its limits;
    ``limits`` None or without finite accelerations: passed through). A drive
    starts from the robot's twist as the runtime estimates it (at rest without an estimate) and ends
    when the source falls silent (None); :attr:`body_accel` is the last step's planned acceleration,
    which the runtime sends with the VEL so the controller's wheel-speed loop feeds it forward."""

    def __init__(self, limits: TwistLimits | None, period: float) -> None:
        ramp = TwistRamp(limits) if limits is not None else None
        self.ramp = ramp if ramp is not None and ramp.limited else None
        self.period = period
        self.body_accel: tuple[float, float, float] | None = None
        self._last: float | None = None  # the cycle time of the last step (None: not driving)

    def __call__(self, cycle: Cycle, twist: Twist | None) -> Twist | None:
        """This cycle's twist on its way to ``twist`` (None: the source is silent)."""
        self.body_accel = None
        ramp = self.ramp
        if ramp is None or twist is None:
            self._last = None
            return twist
        if self._last is None:
            ramp.reset(cycle.estimate.body_twist if cycle.estimate is not None else ZERO)
            self._last = cycle.t - self.period
        out = ramp.step(twist, cycle.t - self._last)
        self._last = cycle.t
        self.body_accel = ramp.body_accel
        return out

    def reset(self) -> None:
        """Forget the drive: the next twist starts a new one."""
        self._last = None
        self.body_accel = None


class DeadmanSource:
    """A person's input through teleop's deadman; set :attr:`sample` (the newest input) from outside,
    or override :meth:`read`. With ``limits`` of finite accelerations (the robot's, through
    :meth:`TwistLimits.from_limits`) the twist ramps while the deadman is held
    (:class:`~omnibot.teleop.mapping.TwistRamp`, its planned acceleration sent with the VEL as
    :attr:`body_accel`), the stop sequence too: it ramps down for its ``stop_repeats`` periods, and a
    controller on its wheel-speed loop brakes on at the same limits when its VEL watchdog runs out
    (:meth:`~omnibot.firmware.motion.Executor.brake_to_rest`). A drive starts from the robot's
    estimated twist when the runtime has an estimate."""

    def __init__(
        self,
        name: str,
        config: TeleopConfig,
        *,
        priority: int = 100,
        timeout: float | None = None,
        limits: TwistLimits | None = None,
    ) -> None:
        self.name = name
        self.priority = priority
        self.timeout = config.input_timeout if timeout is None else timeout
        self.watchdog = config.vel_timeout
        self.wait_reply = True  # a person's 20 Hz: a refusal is known at once
        self.config = config
        self.deadman = Deadman(config.input_timeout, config.stop_repeats)
        self.sample: Sample | None = None
        self.action = Action(None)
        """The deadman's action of the last cycle."""
        self.ended: Why | None = None
        """Why driving ended on the last cycle it did (None otherwise)."""
        self.twist: Twist | None = None
        """The twist of the last proposal (None when silent)."""
        self.ramped = RampedTwist(limits, config.period)

    def read(self, now: float) -> Sample | None:
        """The newest input at ``now`` (None: no input device)."""
        return self.sample

    @property
    def held(self) -> bool:
        """The deadman is held (driving)."""
        return self.deadman.phase is Phase.DRIVING

    def propose(self, cycle: Cycle) -> Proposal | None:
        """The deadman's twist for this cycle (None while idle)."""
        action = self.deadman.update(cycle.now, self.read(cycle.now))
        self.action = action
        self.ended = action.ended
        twist = self.ramped(cycle, action.twist)
        self.twist = twist
        if twist is None:
            return None
        return Proposal(twist, fresh=action.started)

    def reset(self) -> None:
        """Forget the drive and the input (after an emergency stop): silent until a fresh input."""
        self.sample = None
        self.deadman.reset()
        self.twist = None
        self.ramped.reset()

    @property
    def body_accel(self) -> tuple[float, float, float] | None:
        """The ramp's planned acceleration of the last proposal (None: no ramp, or silent)."""
        return self.ramped.body_accel


class JoySource(Protocol):
    """A pad, the keyboard, or a script standing in for them (teleop's input devices)."""

    name: str

    @property
    def quit(self) -> bool:
        """True when the user asked to leave through this device."""

    def read(self, now: float) -> JoyState | None:
        """The device's state now, or None while there is no device."""


class PadSource(DeadmanSource):
    """A joystick or the keyboard (``device``) through teleop's mapping and limits."""

    def __init__(
        self,
        device: JoySource,
        config: TeleopConfig,
        limits: TwistLimits,
        *,
        name: str | None = None,
        priority: int = 100,
    ) -> None:
        super().__init__(name or device.name, config, priority=priority, limits=limits)
        self.device = device
        self.limits = limits
        self.closing = False
        """Set when teleop ends: the pad reads as gone, so the deadman sends its stop sequence."""

    @property
    def quit(self) -> bool:
        """True when the user asked to leave through the device."""
        return self.device.quit

    def read(self, now: float) -> Sample | None:
        """The device's state mapped and limited as teleop maps it (None: no device, or closing)."""
        if self.closing:
            return None
        joy = self.device.read(now)
        if joy is None:
            return None
        cmd = joy_to_command(self.config, joy)
        return Sample(limit_twist(cmd.twist, self.limits), cmd.enabled, joy.time)
