"""The executor's commands: VEL, and MOVE, ROTATE, DELTA and POWER as they leave the queue.

Each queued motion has a duration (seed 000: T = L/V, T = A/F, POWER's T), run on the executor's
timeline (or landed: :mod:`~omnibot.firmware.motion_landing`). DELTA repeats ``max(R, 1)`` times;
with R = INF it repeats until a command is queued and then finishes the current repetition. The
remembered MOVE is set when a MOVE or DELTA repetition starts.

A finite MOVE on a robot with encoders is watched through its coast (:mod:`~omnibot.firmware.progress`):
when the wheels stand still short of its distance beyond the tolerance, WARN 17.

An open-loop MOVE (and each DELTA repetition) asked faster than the calibrated reach on its folded
course (:meth:`~omnibot.firmware.calibration.Calibration.reach_at`, uploaded with CAL table 8) runs
at the reach, its distance kept (WARN 18, once a command): faster, the calibration saw such MOVEs fall
short. The remembered MOVE keeps the speed asked.
"""

import math

from omnibot.firmware.calibration import fold_course
from omnibot.firmware.motion_drive import REACHED
from omnibot.firmware.motion_state import MotionState, clamp
from omnibot.firmware.power import SATURATED
from omnibot.protocol import codes

INF = codes.INF
MODE_SIMULATION = codes.MODE_SIMULATION


class Commands(MotionState):
    """The executor's part that starts what a command asks for."""

    def vel(
        self, vx: int, vy: int, w: int, t_ms: int, accel: int = 0, body: "list[int] | None" = None
    ) -> None:
        """Hold a body velocity (cm/s, cm/s, deg/s) for t_ms unless refreshed; clears the queue.

        ``accel`` (version 3): the host's planned rate of change of the translation speed
        hypot(vx, vy), cm/s^2, along (vx, vy) (the turn's is taken as 0). ``body`` (version 4): the
        body's planned acceleration [AX, AY, AW], cm/s^2 along its x and y axes (its centre's in
        the world) and deg/s^2. The closed loop feeds their torque forward (:meth:`_accel`).
        """
        self.queue.clear()
        self.progress.cancel()
        acc = self._acc
        self._acc_turning = body is not None
        if body is not None:
            acc[0] = body[0] * 0.01
            acc[1] = body[1] * 0.01
            acc[2] = math.radians(body[2])
            self._acc_on = True
        else:
            speed = math.sqrt(vx * vx + vy * vy)
            self._acc_on = accel != 0 and speed > 0
            g = accel * 0.01 / speed if self._acc_on else 0.0  # 1/s
            acc[0] = g * vx
            acc[1] = g * vy
            acc[2] = 0.0
        if self.kind != codes.VEL:
            self._warned = 0
        self.kind = codes.VEL
        self._braking = False
        self._slewing = False
        self.infinite = False
        self._land_reset()
        self.watchdog.arm(t_ms)
        self._drive(vx * 0.01, vy * 0.01, math.radians(w), vx == 0 and vy == 0)

    def _start_next(self, carry: int) -> None:
        slot = self.queue.pop()
        kind = slot[0]
        self.kind = kind
        self._warned = 0
        self.progress.cancel()  # a MOVE starts its own watch (_move)
        if kind == codes.MOVE:
            for i in range(4):
                self.remembered[i] = slot[i + 1]
            self._move(carry)
        elif kind == codes.DELTA:
            for i in range(4):
                self._delta[i] = slot[i + 1]
            r = slot[5]
            self._reps_inf = r == INF
            self._reps = 1 if r < 1 else r
            self._repeat(carry)
        elif kind == codes.ROTATE:
            self._rotate(slot[1], slot[2], carry)
        else:  # POWER
            self.infinite = False
            self._land_reset()
            self.remaining = slot[1] * 1000 + carry
            self._feedback = False
            self._drag = False
            for i in range(self.n):
                self.powers[i] = slot[i + 2]
            self.apply()

    def _repeat(self, carry: int) -> None:
        """One DELTA repetition: remembered MOVE += increments (clamped, course wrapped)."""
        if not self._reps_inf:
            self._reps -= 1
        m = self.remembered
        d = self._delta
        lim = self.l_max
        if abs(m[0]) != INF:
            m[0] = clamp(m[0] + d[0], lim)
        v = m[1] + d[1]
        if v != 0 and abs(v) < self.v_min:
            v = math.ceil(self.v_min) * (1 if v > 0 else -1)
        elif abs(v) > self.v_max:
            v = int(self.v_max) * (1 if v > 0 else -1)
            self._warn_once(SATURATED)
        m[1] = v
        c = m[2] + d[2]
        m[2] = c % 360 if c >= 0 else -((-c) % 360)
        m[3] = clamp(m[3] + d[3], self.c_max)
        if self._reps_inf and (m[0] == 0 or m[1] == 0):  # zero-length: would spin without moving
            self._reps_inf = False
            self._reps = 0
        self._move(carry)

    def _move(self, carry: int) -> None:
        L, V, D, C = self.remembered
        self.infinite = abs(L) == INF
        if L == 0 or V == 0:
            self._land_reset()
            self.remaining = carry
            self._drive(0.0, 0.0, 0.0, False)
            return
        speed = abs(V)
        if not self._closed_loop():
            reach = int(self.model.cal.reach_at(fold_course(D, self.model.axes)))
            if 0 < reach < speed:  # the calibration saw faster MOVEs fall short: the distance goes first
                speed = reach
                self._warn_once(REACHED)
        gain = 1.0
        if not self.infinite:  # the rollers' drag also shortens the coast after a finite MOVE of L/V s
            gain = max(0.0, gain + self.model.cal.coast(speed) * speed / abs(L))
        s = speed if (L > 0) == (V > 0) else -speed
        a = math.radians(D)
        u = 1.0 if s > 0 else -1.0
        ux = u * math.cos(a)
        uy = u * math.sin(a)
        if self.infinite:
            self._land_reset()
        else:
            self._land_start(ux, uy, u * C * 0.1, False, abs(L) * 0.01, speed * 0.01)
        self._drive(s * 0.01 * math.cos(a), s * 0.01 * math.sin(a), s * C * 0.001, False, gain)
        if not self.infinite:
            self._timed(_duration(abs(L), speed, self._time_scale), carry)
            if self.kind == codes.MOVE and not self.mode & MODE_SIMULATION:
                self._read_counts()
                self.progress.start(self._counts, ux, uy, abs(L) * 0.01)

    def _rotate(self, A: int, F: int, carry: int) -> None:
        self.infinite = abs(A) == INF
        if A == 0:
            self._land_reset()
            self.remaining = carry
            self._drive(0.0, 0.0, 0.0, True)
            return
        w = math.radians(abs(F))
        u = 1.0 if (A > 0) == (F > 0) else -1.0
        if self.infinite:
            self._land_reset()
        else:
            self._land_start(0.0, 0.0, u, True, math.radians(abs(A)), w)
        self._drive(0.0, 0.0, u * w, True)
        if not self.infinite:
            self._timed(_duration(abs(A), abs(F), self.model.scale), carry)


def _duration(amount: int, rate: int, scale: float) -> int:
    """Microseconds for amount / rate, stretched by 1/scale when the powers were saturated."""
    t = amount * 1000000 // rate
    if scale < 1.0:
        t = int(t / scale)
    return t
