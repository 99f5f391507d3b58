"""Landing the executor's finite motions in closed loop (:mod:`~omnibot.firmware.landing` plans them).

In closed loop (MODE bit 1, an encoder on every wheel, not simulating) a finite MOVE, each DELTA
repetition and a ROTATE do not run on the timeline: they *land*, ending when the encoders say the
body went its distance (angle), with the speed ramped up from rest and down to what the command
queued behind keeps (0 for none), and a deadline of twice their time (and their ramps) and a second
after which they end short. The queue's semantics stay: the command behind starts when the motion
lands, an infinite DELTA finishes the repetition running when a command comes. Open loop and
simulation keep seed 000's timeline.
"""

import math

from omnibot.firmware.motion_state import NONE, MotionState, clamp
from omnibot.protocol import codes

MODE_SIMULATION = codes.MODE_SIMULATION
CHAIN_GUARD = 64  # DELTA repetitions looked ahead at most when the landing plans its ramp


class LandingMotion(MotionState):
    """The executor's part that starts, advances and ends a landing motion."""

    def _lands(self) -> bool:
        """A finite motion started now ends on its encoders (landing.py): closed loop, not simulating."""
        return self._closed_loop() and self.landing.available and not self.mode & MODE_SIMULATION

    def _land_reset(self) -> None:
        """The motion starting is not landed: full speed, on the timeline."""
        self.landing.active = False
        self._land_scale = 1.0

    def _land_start(self, ux: float, uy: float, uw: float, rotate: bool, goal: float, nominal: float) -> None:
        """Land the motion starting now (if :meth:`_lands`): twist (ux, uy, uw) per unit of its speed
        (:meth:`Landing.start`); its plan set before it is driven."""
        if not self._lands():
            self._land_reset()
            return
        self._read_counts()
        wheels = self.speedctl.speed if self._feedback else None  # a motion that was not landed ran
        t = self._unit
        t[0] = ux
        t[1] = uy
        t[2] = uw
        self.landing.start(self._counts, t, rotate, goal, nominal, wheels, self._land_us)
        self._land_us = 0
        self._land_scale = self._land_profile(0)

    def _timed(self, duration: int, carry: int) -> None:
        """A finite motion's time: on the timeline, or (landing) a deadline of twice it with its ramps
        and a second, after which it ends short (WARN 17 for a MOVE), its end left to :meth:`_land_step`."""
        land = self.landing
        if land.active:
            a = land.accel_w if land.rotate else land.accel
            self._deadline = 2 * (duration + int(2e6 * land.nominal / a)) + 1000000
            self.remaining = self.landing.time_left(self._period)
        else:
            self.remaining = duration + carry

    def _land_step(self) -> None:
        """One control period of a landing motion: its travel, its end, its ramp."""
        land = self.landing
        dt = self._land_us
        land.update(self._counts, dt)
        self._land_us = 0
        self.remaining = 0 if self._deadline <= 0 else land.time_left(self._period)
        rate = land.rate
        scale = self._land_profile(dt)
        if scale != self._land_scale or land.rate != rate:
            self._land_scale = scale
            n = self._nominal
            self._drive(n[0], n[1], n[2], self._rot, n[3])

    def _land_off(self) -> None:
        """Back to the timeline mid-motion (open loop or simulation now): the rest at the speed asked."""
        land = self.landing
        left = land.left
        self._land_reset()
        self.remaining = int(left / land.nominal * 1e6) if left > 0.0 else 0
        if self.kind != NONE:
            n = self._nominal
            self._drive(n[0], n[1], n[2], self._rot, n[3])

    def _land_profile(self, dt_us: int) -> float:
        """Advance the landing motion's plan by ``dt_us`` (:meth:`Landing.replan`): the share of the
        asked speed to drive now; its rate of change is fed forward as a planned acceleration."""
        land = self.landing
        need = land.braking()
        rest = self._chain_rest(need) if self.kind == codes.DELTA else 0.0
        v_exit = 0.0 if rest >= need else self._exit_speed()
        return land.replan(rest, v_exit, dt_us)

    def _chain_rest(self, need: float) -> float:
        """The path (m) of this DELTA's repetitions still to come, counted up to ``need``."""
        if self._reps_inf:
            return need if len(self.queue) == 0 else 0.0
        m = self.remembered
        d = self._delta
        L = m[0]
        total = 0.0
        k = self._reps
        guard = CHAIN_GUARD
        while k > 0 and total < need:
            guard -= 1
            if guard <= 0:
                return need
            L = clamp(L + d[0], self.l_max)
            total += abs(L) * 0.01
            k -= 1
        return total

    def _exit_speed(self) -> float:
        """The speed the command queued behind keeps along this motion's direction (m/s or rad/s,
        0 when it goes elsewhere, turns the other way or nothing is queued)."""
        slot = self.queue.peek()
        if slot is None:
            return 0.0
        land = self.landing
        kind = slot[0]
        if land.rotate:
            if kind != codes.ROTATE or slot[1] == 0:
                return 0.0
            sign = 1.0 if (slot[1] > 0) == (slot[2] > 0) else -1.0
            v = sign * land.uw * math.radians(abs(slot[2]))
        elif kind in (codes.MOVE, codes.DELTA):
            L, V, D = slot[1], slot[2], slot[3]
            if kind == codes.DELTA:
                m = self.remembered
                L, V, D = m[0] + L, m[1] + V, m[2] + D
            if L == 0 or V == 0:
                return 0.0
            s = abs(V) * 0.01 if (L > 0) == (V > 0) else -abs(V) * 0.01
            a = math.radians(D)
            v = s * (math.cos(a) * land.ux + math.sin(a) * land.uy)
        else:
            return 0.0
        return v if v > 0.0 else 0.0
