"""What the runtime sends: one VEL per cycle (clamped; a latched stop released first), and the
replies of those not waited for, collected at the next cycle; a failure is told to every front end.
"""

from __future__ import annotations

import math

from omnibot.client import BatteryStopLatched, EmergencyStopLatched, Limits, Pending
from omnibot.client.commands import vel as vel_command
from omnibot.errors import ControllerError, LinkError
from omnibot.estimation import SlipModel
from omnibot.motion import Twist
from omnibot.runtime.core import RuntimeCore
from omnibot.runtime.cycle import Notice
from omnibot.runtime.sources import Source


def clamp_to(limits: Limits, twist: Twist) -> Twist:
    """``twist`` inside what the controller accepts (VEL's bounds just inside, so rounding to 1 cm/s and
    1 degree/s never crosses them): the translation scaled down, the turn rate clipped."""
    vmax = max(0.0, (limits.speed_max_cms - 1.0) / 100.0)
    vx, vy = twist.vx, twist.vy
    speed = math.hypot(vx, vy)
    if speed > vmax:
        vx, vy = vx * vmax / speed, vy * vmax / speed
    wmax = math.radians(max(0.0, limits.rate_max_dps - 1.0))
    return Twist(vx, vy, max(-wmax, min(wmax, twist.w)))


class Sending(RuntimeCore):
    """The runtime's VELs, the replies awaited, the failures told."""

    sources: dict[str, Source]
    slip: SlipModel | None
    closed_loop: bool | None
    vel_timeout: float
    wait_replies: bool
    _pending: list[tuple[Pending, str]]
    _last_error: dict[str, str]

    def discard_pending(self) -> None:
        """Forget the replies still awaited (a run that ended: its STOP follows)."""
        self._pending.clear()

    def _send(self, source: str, twist: Twist, fresh: bool) -> Twist | None:
        client, origin = self.client, self.sources.get(source)
        watchdog = getattr(origin, "watchdog", None) or self.vel_timeout
        # a follower's planned acceleration, for a controller whose wheel loop takes it: the body's
        # whole (version 4) or the speed's along the travel (version 3)
        planned = getattr(origin, "body_accel", None)
        body = planned if client.takes_vel_body_accel else None
        accel = getattr(origin, "accel", 0.0) if client.takes_vel_accel and body is None else 0.0
        try:
            if fresh and self.latched and self.latch_reason == "battery":
                client.stop()  # releases the battery stop only with the voltage back up: telemetry tells
            elif fresh and self.latched:
                client.stop()  # a person let go and pressed again: release the latched stop
                self.latched = False
                self.latch_reason = ""
                self.notify("info", "emergency stop released by a fresh press of the deadman", source)
            sent = clamp_to(client.limits, twist)
            if self.slip is not None and self.closed_loop and not sent.is_zero:
                sent = clamp_to(client.limits, self.slip.commanded(sent, planned or (0.0, 0.0, 0.0)))
            if getattr(origin, "wait_reply", self.wait_replies):
                t0 = client.clock.now()
                client.vel(sent.vx, sent.vy, sent.w, watchdog, accel, body)
                self.rtt = client.clock.now() - t0
            else:
                command = vel_command(client.limits, *sent, watchdog, accel, body)
                self._pending.append((client.submit(command), source))
        except (ControllerError, LinkError, ValueError) as exc:
            self._failed(source, exc)
            return None
        self._last_error.pop(source, None)
        self.last_twist = twist
        if twist.is_zero:
            self.sent.zero += 1
        else:
            self.sent.vel += 1
        return sent

    def _collect(self) -> None:
        keep = []
        for pending, source in self._pending:
            if pending.error is not None:
                self._failed(source, pending.error, pending.line)
            elif not pending.done:
                keep.append((pending, source))
        self._pending = keep

    def _failed(self, source: str, exc: BaseException, line: str = "") -> None:
        self.sent.errors += 1
        for hook in self.error_hooks:
            hook(source, exc)
        if isinstance(exc, EmergencyStopLatched):
            self._latch()  # one notice for everyone; the refused source sees cycle.latched
            return
        if isinstance(exc, BatteryStopLatched):
            self._latch("battery")
            return
        text = f"the controller refused {line}: {exc}" if line else f"command failed: {exc}"
        if self._last_error.get(source) != text:
            self._last_error[source] = text
            self.notify("error", text, source)
        else:
            self._notices.append(Notice("error", text, source))
