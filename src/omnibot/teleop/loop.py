"""The teleop loop: input source -> mapping -> limits -> deadman -> VEL, once per command period.

::

    every period (1 / autorepeat_rate, paced in real time by Pacer):
      joy = source.read(now)                      # JoyState, or None: no pad attached
      cmd = joy_to_command(config, joy)           # enable / turbo, scales, deadzone
      twist = limit_twist(cmd.twist, limits)      # same direction, within the robot's limits
      action = deadman.update(now, Sample(...))   # VEL(twist) / VEL(0) while stopping / nothing
      client.vel(*twist, timeout=vel_timeout)     # the controller's watchdog stops the robot if
                                                  # teleop goes silent mid-drive

All of it runs in the caller's thread, which owns the client. A controller that latched a sonar
emergency stop rejects VEL (ERROR 40): teleop says so and releases the latch (STOP) only on a
fresh press of the deadman, never on its own.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from omnibot.client.client import RobotClient
from omnibot.client.errors import EmergencyStopLatched
from omnibot.errors import ControllerError, LinkError
from omnibot.motion import Twist
from omnibot.teleop.config import TeleopConfig
from omnibot.teleop.deadman import Action, Deadman, Sample
from omnibot.teleop.mapping import JoyState, TwistLimits, joy_to_command, limit_twist
from omnibot.teleop.pacing import Pacer

log = logging.getLogger("omnibot.teleop")


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


@dataclass
class Counters:
    """What teleop sent, for status lines and tests."""

    vel: int = 0
    zero: int = 0
    errors: int = 0


class Teleop:
    """Drives ``client`` from ``source``; :meth:`step` is one period, :meth:`run` loops in real time."""

    def __init__(
        self,
        client: RobotClient,
        config: TeleopConfig,
        source: Source,
        *,
        limits: TwistLimits | None = None,
        pacer: Pacer | None = None,
        on_message: Callable[[str], None] = print,
    ) -> None:
        self.client = client
        self.config = config
        self.source = source
        self.limits = limits or TwistLimits.from_limits(client.limits, config)
        self.pacer = pacer or Pacer(client, config.period)
        self.deadman = Deadman(config.input_timeout, config.stop_repeats)
        self.on_message = on_message
        self.sent = Counters()
        self.last_twist: Twist | None = None
        self.latched = False
        self._last_error = ""

    def sample(self, now: float) -> Sample | None:
        """Read the source and turn its state into a limited twist."""
        joy = self.source.read(now)
        if joy is None:
            return None
        cmd = joy_to_command(self.config, joy)
        return Sample(limit_twist(cmd.twist, self.limits), cmd.enabled, joy.time)

    def step(self) -> Action:
        """One period: read, map, decide, send."""
        now = self.pacer.now()
        action = self.deadman.update(now, self.sample(now))
        if action.ended is not None:
            self.on_message(f"stopping: {action.ended.value}")
        if action.twist is not None:
            self._send(action.twist, action.started)
        return action

    def run(self, duration: float | None = None) -> None:
        """Step every period until the source asks to quit (or ``duration`` s of wall time), then
        send the stop sequence if the robot was being driven."""
        start = self.pacer.now()
        try:
            while not self.source.quit and (duration is None or self.pacer.now() - start < duration):
                self.step()
                self.pacer.wait()
        finally:
            self.finish()

    def finish(self) -> None:
        """Stop driving: the zero commands of the stop sequence, paced (no-op if not driving)."""
        for _ in range(self.config.stop_repeats):
            action = self.deadman.update(self.pacer.now(), None)
            if action.twist is None:
                break
            self._send(action.twist, False)
            self.pacer.wait()

    def _send(self, twist: Twist, started: bool) -> None:
        try:
            if started and self.latched:
                self.client.stop()  # a fresh press of the deadman releases the emergency stop
                self.latched = False
                self.on_message("emergency stop released by a fresh press of the deadman")
            self.client.vel(twist.vx, twist.vy, twist.w, self.config.vel_timeout)
        except EmergencyStopLatched:
            self.sent.errors += 1
            if not self.latched:
                self.latched = True
                self.on_message(
                    "emergency stop latched by the controller (sonar): let go and press again to release"
                )
            return
        except (ControllerError, LinkError, ValueError) as exc:
            self.sent.errors += 1
            text = str(exc)
            if text != self._last_error:
                self._last_error = text
                self.on_message(f"command failed: {text}")
            return
        self._last_error = ""
        self.last_twist = twist
        if twist.is_zero:
            self.sent.zero += 1
        else:
            self.sent.vel += 1
