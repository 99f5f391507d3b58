"""The brake to rest: a VEL let go on the speed loop is slowed to rest, not left to coast.

A VEL whose watchdog runs out on the closed loop (the host let go, or went silent) brakes the robot to
rest (:meth:`Brake.brake_to_rest`): the twist it drove is slewed down to zero at the robot's
acceleration limits (``accel_max_cms2``, ``angular_accel_max_dps2``; the wheels neither lock nor
skid), and the motors go off once the wheels stand still, instead of letting it coast: a 30 kg robot
at 3 m/s coasts for metres. The Mega's firmware takes the same constants (avrgen.py).
"""

import math

from omnibot.firmware.motion_state import MotionState

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any

BRAKE_MAX_US = 3000000  # braking to rest on the speed loop ends by then, whatever the encoders say
REST_WINDOW_US = 50000  # the wheels stand still when none turned more than its rest counts in this long
REST_RAD = 0.2  # rad/s: a wheel turning slower than this (and at least 1 count a window) is at rest


def rest_counts(encoder_cpr: "list[Any]") -> "list[int]":
    """Each wheel's rest counts: the most it may turn in :data:`REST_WINDOW_US` and stand still."""
    return [max(1, int(int(c) * REST_RAD * REST_WINDOW_US * 1e-6 / (2.0 * math.pi))) for c in encoder_cpr]


class Brake(MotionState):
    """The executor's brake to rest and the slew that brings the driven twist down."""

    def _init_brake(self, cfg: "dict[str, Any]") -> None:
        """The slew and the brake to rest: the robot's limits, nothing braking yet."""
        self._radius = cfg["radius"]
        self._stop_decel = float(cfg.get("stop_decel_cms2", 0.0)) * 0.01  # m/s^2
        self._a_max = float(cfg.get("accel_max_cms2", 0.0)) * 0.01  # m/s^2 (0: a brake holds at once)
        self._alpha_max = math.radians(float(cfg.get("angular_accel_max_dps2", 0.0)))  # rad/s^2
        self._goal = [0.0, 0.0, 0.0]  # the twist a slew heads for (rest, when braking), m/s, m/s, rad/s
        self._ref = [0.0, 0.0, 0.0]  # the slewed twist driven now
        self._slewing = False
        self._slew_due = 0
        self._braking = False
        self._brake_us = 0  # time braked so far
        self._brake_min_us = 0  # the body's stopping time from the wheels' speed at the stop deceleration
        self._rest_due = 0
        self._rest_ref = [0] * self.n
        self._rest_counts = rest_counts(cfg["encoder_cpr"])

    def _slew(self, dt_us: int) -> None:
        """Move the slewed twist towards ``_goal`` by at most the acceleration limits over ``dt_us``
        (the translation as a vector) and drive it; the slew ends when it arrives."""
        ref, g = self._ref, self._goal
        dt = dt_us * 1e-6
        dx = g[0] - ref[0]
        dy = g[1] - ref[1]
        dv = math.sqrt(dx * dx + dy * dy)
        most = self._a_max * dt
        if dv > most:
            dx *= most / dv
            dy *= most / dv
        dw = g[2] - ref[2]
        most = self._alpha_max * dt if self._alpha_max > 0.0 else abs(dw)
        dw = most if dw > most else -most if dw < -most else dw
        ref[0] += dx
        ref[1] += dy
        ref[2] += dw
        self._slewing = ref[0] != g[0] or ref[1] != g[1] or ref[2] != g[2]
        self._slew_due = self._drag_period
        # the slew is a planned acceleration: fed forward as a VEL's (the integral then does not
        # store the ramp's torque and carry the wheels past the speed asked), the body's along its
        # axes (the rate of the body-frame twist less the turning axes' part)
        acc = self._acc
        self._acc_on = self._slewing
        self._acc_turning = True
        acc[0] = dx / dt - ref[2] * ref[1] if self._slewing else 0.0
        acc[1] = dy / dt + ref[2] * ref[0] if self._slewing else 0.0
        acc[2] = dw / dt if self._slewing else 0.0
        if self._slewing:
            self.speedctl.rise()
        self._drive(ref[0], ref[1], ref[2], ref[0] == 0.0 and ref[1] == 0.0)

    def brake_to_rest(self) -> None:
        """Bring the robot to rest on the speed loop, then end the motion (IDLE). Closed loop only
        (the caller checks). With acceleration limits the driven twist is slewed down to zero at them;
        without, the wheels are held at rest at once, for at least as long as the body needs to stop
        from the wheels' speed at the robot's stop deceleration. Either way the motion ends once every
        wheel stands still (none turned more than its rest counts in :data:`REST_WINDOW_US`), or
        :data:`BRAKE_MAX_US` after the twist reached zero."""
        self._braking = True
        self._brake_us = 0
        self._rest_due = REST_WINDOW_US
        for i in range(self.n):
            self._rest_ref[i] = self.hal.encoder_count(i)
        nominal = self._nominal  # the twist the VEL asked for (the sonar guard scales what is driven)
        for i in range(3):
            self._ref[i] = nominal[i]
            self._goal[i] = 0.0
        self._acc_on = False
        if self._a_max > 0.0:
            self._brake_min_us = 0
            self._slewing = True  # down from the twist driven now, at the acceleration limits
            self._slew(self._drag_period)
        else:
            fastest = 0.0  # the wheels' rim speed now: how long the body may still need to stop
            for i in range(self.n):
                fastest = max(fastest, abs(self.speedctl.speed[i]) * self._radius[i])
            self._brake_min_us = int(fastest / self._stop_decel * 1e6) if self._stop_decel > 0.0 else 0
            self._drive(0.0, 0.0, 0.0, False)

    def _at_rest(self, dt_us: int) -> bool:
        """While braking: True once the wheels stand still (see :meth:`brake_to_rest`)."""
        self._brake_us += dt_us
        if self._brake_us >= BRAKE_MAX_US:
            return True
        self._rest_due -= dt_us
        if self._rest_due > 0:
            return False
        self._rest_due = REST_WINDOW_US
        still = True
        for i in range(self.n):
            c = self.hal.encoder_count(i)
            if abs(c - self._rest_ref[i]) > self._rest_counts[i]:
                still = False
            self._rest_ref[i] = c
        return still and self._brake_us >= self._brake_min_us
