"""Driving a twist: the executor's powers for it, through the sonar guard and the power model.

:meth:`Drive._drive` turns a body twist into every wheel's power (the power model, seed 000's
formulas), its feedforward and wheel-speed targets for the closed loop (with a VEL's or a landing's
planned acceleration fed forward), and warns once a command of what limited it.

With a :class:`~omnibot.firmware.safety.SonarGuard` (``guard``), every travelling twist is scaled by
the guard's factor (the sonar stop's speed limit) and a finite motion's time stretched to match, so it
still covers its distance; :meth:`Drive.relimit` re-applies the factor after a new sonar reading.
When the guard says the motion must not go on, the executor stops and leaves the reason in ``halt``
(a protocol code) for the controller to report.
"""

import math

from omnibot.firmware.motion_state import NONE, MotionState
from omnibot.firmware.power import DEADBAND, SATURATED, WEAK
from omnibot.firmware.safety import LIMITED, UNCOVERED
from omnibot.protocol import codes

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any

    from omnibot.firmware.safety import SonarGuard

MODE_CLOSED_LOOP = codes.MODE_CLOSED_LOOP
REACHED = 32  # warning flag: a MOVE asked beyond the calibrated reach (power.py and safety.py own 1..16)


class Drive(MotionState):
    """The executor's twist to powers, the guard's limit and the warnings of what limited them."""

    def _init_drive(self, cfg: "dict[str, Any]") -> None:
        """The planned acceleration's feedforward: each wheel's share of the body's and its own."""
        self._body_ff = cfg.get("body_ff") or [[0.0, 0.0, 0.0]] * self.n  # PWM counts per m/s^2
        self._wheel_ff = cfg.get("wheel_ff") or [0.0] * self.n  # PWM counts per rad/s^2 of a wheel
        self._J = cfg["J"]

    def _drive(self, vx: float, vy: float, w: float, rotate: bool, gain: float = 1.0) -> None:
        """Compute and apply the powers for a twist (m/s, m/s, rad/s); ``gain`` is the roller drag's
        (:meth:`PowerModel.drag`)."""
        n = self._nominal
        n[0] = vx
        n[1] = vy
        n[2] = w
        n[3] = gain
        ls = self._land_scale
        if self.landing.active:  # its plan: the share of the twist asked, and its rate of change
            self._land_accel(vx, vy, w)
            vx *= ls
            vy *= ls
            w *= ls
        k = 1.0
        g = self.guard
        if g is not None and (vx != 0.0 or vy != 0.0):
            k = self._guarded(g, vx, vy)
            if k <= 0.0:
                return
            vx *= k
            vy *= k
            w *= k
        else:
            self._speed = 0.0
            self._coast = 0
        self._k = k
        model = self.model
        model.drag_gain = gain
        model.floor = 0.0
        if (
            self.vel_dead_band
            and self.kind == codes.VEL
            and (vx != 0.0 or vy != 0.0)
            and not self._closed_loop()
        ):
            model.floor = model.cal.start_power()  # open loop: a wheel below it stalls (WARN 12)
        flags = model.compute(vx, vy, w, rotate, self.powers)
        self._time_scale = model.scale * k
        self._warn_once(flags)
        t = self._twist
        t[0] = vx
        t[1] = vy
        t[2] = w
        self._rot = rotate
        if flags & DEADBAND and ls >= 1.0:  # the loop drives a landing's slow end
            for i in range(self.n):
                self._ff[i] = 0.0
                self._target[i] = 0.0
        else:
            self._wheel_targets(vx, vy, w, rotate, k)
        if self.mode & MODE_CLOSED_LOOP and not self._feedback:
            self._start_feedback()
        elif self._feedback:
            self.speedctl.hold(self._ff, self.powers)  # a new command keeps the speed loop's correction
        self._start_drag(flags)
        self.apply()

    def _wheel_targets(self, vx: float, vy: float, w: float, rotate: bool, k: float) -> None:
        """The closed loop's feedforward and wheel-speed targets for the twist driven, ``k`` the
        guard's scale of it."""
        self._feedforward(vx, vy, w, rotate)
        self.model.wheel_speeds(vx, vy, w, self._target)
        if self.landing.active:  # the wheels turn faster by their creep, so the body goes as asked
            over = self._over
            if self.landing.overturn(vx, vy, w, over):
                for i in range(self.n):
                    self._target[i] += over[i]
        if self._acc_on and (self.kind == codes.VEL or self.landing.active):
            self._accel(vx, vy, w, k)

    def _land_accel(self, vx: float, vy: float, w: float) -> None:
        """A landing's planned acceleration of the twist (vx, vy, w) asked: its ramp's rate of change."""
        rate = self.landing.rate / self.landing.nominal  # 1/s
        acc = self._acc
        acc[0] = rate * vx
        acc[1] = rate * vy
        acc[2] = rate * w
        self._acc_on = rate != 0.0
        self._acc_turning = False

    def _guarded(self, g: "SonarGuard", vx: float, vy: float) -> float:
        """The guard's factor for a travel (vx, vy), m/s, warned of and coasted down to; 0 or less:
        the guard stopped the motion (``halt``)."""
        k = g.factor(vx * 100.0, vy * 100.0)
        if k <= 0.0:
            self.halt = g.code
            self.stop()
            return k
        self._warn_once(g.flags)
        sx = vx * k
        sy = vy * k
        self._slow_down(math.sqrt(sx * sx + sy * sy) * 100.0, k < 1.0, g.decel)
        return k

    def _feedforward(self, vx: float, vy: float, w: float, rotate: bool) -> None:
        """Each wheel's feedforward: the power model's power; on the closed loop a wheel whose turn is
        the larger part of its rim speed u gets at least ROTATE's factor at its own speed,
        ``K K_r(K |u|) |u|``.

        The turning part's K_t is one factor for every wheel at the body's largest turning power,
        made for open-loop curved MOVEs (omni4's flat 1.55): omni4's two wheels that only turn the
        body on an arc at 0.3 m/s and 0.5 rad/s (u = 0.049 m/s) got 8-14 counts where 33-37 turn
        them, stood 0.2 s until the integral had wound up, and the turn then overshot. Wheels that
        mostly translate keep K_l's power (K_r is above mecanum4's forward K_l).
        """
        model = self.model
        cal = model.cal
        turning = w != 0.0 and not rotate and self.mode & MODE_CLOSED_LOOP
        for i in range(self.n):
            f = model.raw[i]
            row = model.rim[i]
            t = row[0] * vx + row[1] * vy
            if turning and abs(row[2] * w) > abs(t):
                u = t + row[2] * w
                least = cal.k * cal.k_r(cal.k * abs(u)) * abs(u)
                if abs(f) < least and f * u >= 0.0:
                    f = least if u > 0.0 else -least
            self._ff[i] = f

    def _accel(self, vx: float, vy: float, w: float, k: float) -> None:
        """Add the planned acceleration's power to each wheel's feedforward (the speed loop's), for
        the twist (vx, vy, w) as driven, ``k`` the guard's scale of it (and of its acceleration).

        The body's acceleration (ax, ay, alpha) takes each wheel's share of its force and torque
        (``body_ff``); the wheel's own inertia needs its angular acceleration, the inverse
        kinematics of the rate at which the body-frame twist changes. The body's axes turn with it
        at w, so that rate is (ax + w vy, ay - w vx, alpha): on a circle at a steady speed the
        body accelerates towards the centre (v w) while its twist, and so every wheel's speed,
        stays the same. Version 3's A is the rate along (vx, vy) with no turn: both the same.
        """
        a = self._acc
        ax, ay, aw = a[0] * k, a[1] * k, a[2] * k
        rx, ry = ax, ay
        if self._acc_turning:
            rx = ax + w * vy
            ry = ay - w * vx
        for i in range(self.n):
            b = self._body_ff[i]
            j = self._J[i]
            self._ff[i] += (
                b[0] * ax + b[1] * ay + b[2] * aw + self._wheel_ff[i] * (j[0] * rx + j[1] * ry + j[2] * aw)
            )

    def _slow_down(self, speed: float, limited: bool, decel: float) -> None:
        """When the guard lowers the speed, coast (powers off) until the robot must have slowed to it:
        reduced power alone decelerates far less than the stop deceleration the guard counts on."""
        bound = self._speed + decel * self._coast * 1e-6  # fastest the robot can be going now
        self._speed = speed
        if limited and bound > speed:
            self._coast = int((bound - speed) / decel * 1e6)
        else:
            self._coast = 0

    def relimit(self) -> None:
        """Apply the guard's factor anew (a sonar reading came): re-drive the travel if it changed and
        stretch or shrink a finite motion's remaining time so that it keeps its distance."""
        g = self.guard
        if g is None or not self.travelling:
            return
        n = self._nominal
        ls = self._land_scale
        k = g.factor(n[0] * ls * 100.0, n[1] * ls * 100.0)
        if k == self._k:
            return
        old = self._time_scale
        self._drive(n[0], n[1], n[2], self._rot, n[3])
        if self.kind != NONE and not self.infinite and self.kind != codes.VEL:
            if self.landing.active:  # it ends on its distance: only the time it may take stretches
                self._deadline = int(self._deadline * old / self._time_scale)
            else:
                self.remaining = int(self.remaining * old / self._time_scale)

    def _warn_once(self, flags: int) -> None:
        new = flags & ~self._warned
        self._warned |= flags
        if new & SATURATED:
            self._warn(codes.W_SPEED_REDUCED)
        if new & (DEADBAND | WEAK):
            self._warn(codes.W_POWER_TOO_LOW)
        if new & LIMITED:
            self._warn(codes.W_SONAR_LIMIT)
        if new & UNCOVERED:
            self._warn(codes.W_UNCOVERED)
        if new & REACHED:
            self._warn(codes.W_REACH)
