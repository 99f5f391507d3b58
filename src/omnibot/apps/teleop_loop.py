"""Teleop: a pad or the keyboard driving through the runtime, once per command period.

::

    every period (1 / autorepeat_rate, paced in real time by Pacer), one runtime cycle:
      joy = device.read(now)                      # JoyState, or None: no pad attached
      cmd = joy_to_command(config, joy)           # enable / turbo, scales, deadzone
      twist = limit_twist(cmd.twist, limits)      # same direction, within the robot's limits
      action = deadman.update(now, Sample(...))   # PadSource: VEL(twist) / VEL(0) while stopping /
                                                  # nothing
      runtime: arbitrate, client.vel(*twist, timeout=vel_timeout)   # the controller's watchdog
                                                  # stops the robot if teleop goes silent mid-drive

The pad is a :class:`~omnibot.teleop.PadSource` of a
:class:`~omnibot.runtime.runtime.Runtime`, which owns the client (in the caller's thread). A
controller that latched a sonar emergency stop rejects VEL (ERROR 40): teleop says so and releases
the latch (STOP) only on a fresh press of the deadman, never on its own.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Protocol

from omnibot.client import RobotClient
from omnibot.estimation import SlipModel
from omnibot.motion import Twist
from omnibot.robot import RobotDescription
from omnibot.runtime import Counters, Cycle, NoticePrinter, Runtime, RuntimeRecording
from omnibot.teleop import Action, Deadman, JoyState, Pacer, PadSource, Sample, TeleopConfig, TwistLimits

log = logging.getLogger("omnibot.teleop")

__all__ = ["Counters", "Source", "Teleop"]


class Source(Protocol):
    """An input device read once per period (joystick, keyboard, a script in tests)."""

    name: str

    @property
    def quit(self) -> bool:
        """True when the user asked to leave through this source."""
        ...

    def read(self, now: float) -> JoyState | None:
        """The device's state now, or None while there is no device."""
        ...


class Teleop:
    """Drives ``client`` from ``source`` through a runtime; :meth:`step` is one period, :meth:`run`
    loops in real time. ``robot``'s description ramps the twist at its accelerations
    (:class:`~omnibot.teleop.mapping.TwistRamp`); ``wheel_loop`` and ``slip`` are the runtime's (the
    controller's wheel-speed loop closed by default; the floor's wheel slip asked on top); so is
    ``recording`` (the command's ``--log``); ``surface``, the floor's name when known, keeps the ramp
    within its grip (:meth:`~omnibot.teleop.TwistLimits.from_limits`)."""

    def __init__(
        self,
        client: RobotClient,
        config: TeleopConfig,
        source: Source,
        *,
        limits: TwistLimits | None = None,
        pacer: Pacer | None = None,
        on_message: Callable[[str], None] = print,
        robot: RobotDescription | None = None,
        wheel_loop: bool | None = True,
        slip: SlipModel | None = None,
        recording: RuntimeRecording | None = None,
        surface: str | None = None,
    ) -> None:
        self.client = client
        self.config = config
        self.source = source
        self.limits = limits or TwistLimits.from_limits(client.limits, config, robot, surface)
        self.pacer = pacer or Pacer(client, config.period)
        self.on_message = on_message
        self.pad = PadSource(source, config, self.limits)
        self.runtime = Runtime(
            client,
            period=config.period,
            sources=[self.pad],
            sinks=[self._say_stopping, NoticePrinter(on_message)],
            pacer=self.pacer,
            vel_timeout=config.vel_timeout,
            wait_replies=True,
            wheel_loop=wheel_loop,
            slip=slip,
            recording=recording,
        )

    @property
    def deadman(self) -> Deadman:
        """The pad's deadman (its phase says whether teleop drives)."""
        return self.pad.deadman

    @property
    def sent(self) -> Counters:
        """What teleop sent, for status lines and tests."""
        return self.runtime.sent

    @property
    def latched(self) -> bool:
        """True while the controller's emergency stop is latched (only STOP releases it)."""
        return self.runtime.latched

    @property
    def last_twist(self) -> Twist | None:
        """The last twist sent, None before the first."""
        return self.runtime.last_twist

    def sample(self, now: float) -> Sample | None:
        """Read the source and turn its state into a limited twist."""
        return self.pad.read(now)

    def step(self) -> Action:
        """One period: read, map, decide, send."""
        self.runtime.step()
        return self.pad.action

    def run(self, duration: float | None = None) -> None:
        """Step every period until the source asks to quit (or ``duration`` s of wall time), then
        send the stop sequence if the robot was being driven."""
        try:
            self.runtime.run(until=lambda: self.source.quit, duration=duration)
        finally:
            self.finish()

    def finish(self) -> None:
        """Stop driving: the zero commands of the stop sequence, paced (no-op if not driving)."""
        self.pad.closing = True
        try:
            for _ in range(self.config.stop_repeats):
                self.runtime.step()
                if self.pad.action.twist is None:
                    break
                self.pacer.wait()
        finally:
            self.pad.closing = False
            self.runtime.close()

    def _say_stopping(self, cycle: Cycle) -> None:
        if self.pad.action.ended is not None:
            self.on_message(f"stopping: {self.pad.action.ended.value}")
