"""The motion executor: runs queued MOVE/ROTATE/DELTA/POWER commands and VEL on a timeline.

Each motion has a duration (seed 000: T = L/V, T = A/F, POWER's T). Time is kept as the remaining
microseconds of the current motion; a motion that ends mid-poll hands its overshoot to the next one,
so a run of queued motions keeps its timeline (37 moves of 50 ms take 1850 ms, whatever the poll
rate). Infinite motions (L or A = +-INF) and VEL end as soon as a command is queued behind them.
A VEL whose watchdog runs out on the closed loop (the host let go, or went silent) brakes the robot to
rest (:meth:`Executor.brake_to_rest`): the twist it drove is slewed down to zero at the robot's
acceleration limits (``accel_max_cms2``, ``angular_accel_max_dps2``; the wheels neither lock nor
skid), and the motors go off once the wheels stand still, instead of letting it coast: a 30 kg robot
at 3 m/s coasts for metres.
DELTA repeats ``max(R, 1)`` times; with R = INF it repeats until a command is queued and then
finishes the current repetition. The remembered MOVE is set when a MOVE or DELTA repetition starts.

With a :class:`~omnibot.firmware.safety.SonarGuard` (``guard``), every travelling twist is scaled by
the guard's factor (the sonar stop's speed limit) and a finite motion's time stretched to match, so it
still covers its distance; :meth:`Executor.relimit` re-applies the factor after a new sonar reading.
When the guard says the motion must not go on, the executor stops and leaves the reason in ``halt``
(a protocol code) for the controller to report.

In closed loop (MODE bit 1, an encoder on every wheel, not simulating) a finite MOVE, each DELTA
repetition and a ROTATE do not run on the timeline: they *land* (:mod:`~omnibot.firmware.landing`),
ending when the encoders say the body went its distance (angle), with the speed ramped up from rest
and down to what the command queued behind keeps (0 for none), and a deadline of twice their time
(and their ramps) and a second after which they end short. The queue's semantics stay: the command
behind starts when the motion lands, an infinite DELTA finishes the repetition running when a
command comes. Open loop and simulation keep seed 000's timeline.

A finite MOVE on a robot with encoders is watched through its coast (:mod:`~omnibot.firmware.progress`):
when the wheels stand still short of its distance beyond the tolerance, WARN 17.

An open-loop MOVE (and each DELTA repetition) asked faster than the calibrated reach on its folded
course (:meth:`~omnibot.firmware.calibration.Calibration.reach_at`, uploaded with CAL table 8) runs
at the reach, its distance kept (WARN 18, once a command): faster, the calibration saw such MOVEs fall
short. The remembered MOVE keeps the speed asked.
"""

import math

from omnibot.firmware.calibration import fold_course
from omnibot.firmware.landing import Landing
from omnibot.firmware.power import DEADBAND, SATURATED, WEAK, PowerModel
from omnibot.firmware.progress import COASTING, ProgressWatch
from omnibot.firmware.safety import LIMITED, UNCOVERED
from omnibot.firmware.speedctl import SpeedControl
from omnibot.firmware.watchdog import Watchdog
from omnibot.protocol import codes

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any

    from omnibot.firmware.hal import HAL
    from omnibot.firmware.queue import CommandQueue
    from omnibot.firmware.safety import SonarGuard

INF = codes.INF
MODE_SIMULATION = codes.MODE_SIMULATION
MODE_CLOSED_LOOP = codes.MODE_CLOSED_LOOP
NONE = 0  # no motion (kinds are the command ids of protocol/codes.py otherwise)
BRAKED = 1 << 20  # applied-power marker of a braked motor: any power written next releases it
LOOP_GUARD = 16  # motions started in one step at most (zero-length moves), keeps a poll short
CHAIN_GUARD = 64  # DELTA repetitions looked ahead at most when the landing plans its ramp
REACHED = 32  # warning flag: a MOVE asked beyond the calibrated reach (power.py and safety.py own 1..16)
BRAKE_MAX_US = 3000000  # braking to rest on the speed loop ends by then, whatever the encoders say
REST_WINDOW_US = 50000  # the wheels stand still when none turned more than its rest counts in this long
REST_RAD = 0.2  # rad/s: a wheel turning slower than this (and at least 1 count a window) is at rest


class Executor:
    """Owns the current motion, its powers, the remembered MOVE and the mode bits."""

    def __init__(
        self,
        cfg: "dict[str, Any]",
        hal: "HAL",
        queue: "CommandQueue",
        model: PowerModel,
        warn: "Callable[[int], None]",
        on_idle: "Callable[[], None]",
    ) -> None:
        self.hal = hal
        self.queue = queue
        self.model = model
        self.n = model.n
        self._warn = warn
        self._on_idle = on_idle
        self.l_max = float(cfg["distance_max_cm"])
        self.v_min = float(cfg["speed_min_cms"])
        self.v_max = float(cfg["speed_max_cms"])
        self.c_max = float(cfg["curvature_max"])
        self.vel_dead_band = bool(cfg.get("vel_dead_band", True))
        self._init_motion()
        self._init_ramps(cfg)
        self._init_loops(cfg)
        for i in range(self.n):
            hal.set_power(i, 0)

    def _init_motion(self) -> None:
        """The state of the current motion, its powers and the remembered MOVE: none yet."""
        self.kind = NONE
        self.infinite = False
        self.remaining = 0
        self.powers = [0] * self.n
        self.pwm_max = int(self.model.pwm_max)
        self.power_cap = self.pwm_max  # the battery's power limit (controller.py): largest power applied
        self.mode = 0
        self.remembered = [0, 0, 0, 0]
        self.watchdog = Watchdog()
        self.guard: SonarGuard | None = None
        self.halt = 0
        self._k = 1.0
        self._time_scale = 1.0
        self._speed = 0.0  # translation speed last commanded, cm/s
        self._coast = 0  # us left of coasting down to a speed the guard lowered
        self._nominal = [0.0, 0.0, 0.0, 0.0]
        self._applied = [0] * self.n
        self._delta = [0, 0, 0, 0]
        self._reps = 0
        self._reps_inf = False
        self._warned = 0
        self._twist = [0.0, 0.0, 0.0]
        self._rot = False
        self._ff = [0.0] * self.n
        self._target = [0.0] * self.n

    def _init_ramps(self, cfg: "dict[str, Any]") -> None:
        """A VEL's planned acceleration and its feedforward, the slew, the brake to rest."""
        self._acc = [0.0, 0.0, 0.0]  # a VEL's planned body acceleration, m/s^2, m/s^2, rad/s^2
        self._acc_on = False  # the VEL carries one
        self._acc_turning = False  # version 4's: the wheels' part takes the turning axes' term (_accel)
        self._body_ff = cfg.get("body_ff") or [[0.0, 0.0, 0.0]] * self.n  # PWM counts per m/s^2
        self._wheel_ff = cfg.get("wheel_ff") or [0.0] * self.n  # PWM counts per rad/s^2 of a wheel
        self._J = cfg["J"]
        self._counts = [0] * self.n
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
        self._rest_counts = [
            max(1, int(int(c) * REST_RAD * REST_WINDOW_US * 1e-6 / (2.0 * math.pi)))
            for c in cfg["encoder_cpr"]
        ]

    def _init_loops(self, cfg: "dict[str, Any]") -> None:
        """The closed loops: the drag term, the progress watch, the landing and the speed loop."""
        self._feedback = False
        self._drag = False
        period_us = int(cfg["control_period_ms"]) * 1000
        self._drag_period = period_us
        self._drag_due = 0
        self.progress = ProgressWatch(cfg)
        self._watch_due = 0
        self.landing = Landing(cfg)
        self._land_scale = 1.0  # the landing's ramp: share of the asked speed driven now
        self._land_us = 0  # us since the landing's last update
        self._deadline = 0  # us a landing motion may still take before it ends short
        self._period = period_us
        self._unit = [0.0, 0.0, 0.0]
        self._over = [0.0] * self.n
        self.speedctl = SpeedControl(
            [int(c) for c in cfg["encoder_cpr"]],
            float(cfg["speed_kp"]),
            float(cfg["speed_ki"]),
            period_us,
            self.model.pwm_max,
            float(cfg.get("speed_band", 0.0)),
            float(cfg.get("speed_ki_steady", 0.0)),
        )

    # ------------------------------------------------------------------ state

    @property
    def moving(self) -> bool:
        """True while a motion runs (idle otherwise)."""
        return self.kind != NONE

    @property
    def travelling(self) -> bool:
        """A MOVE, DELTA or VEL that translates the body (what the sonar guard limits)."""
        n = self._nominal
        return self.kind in (codes.MOVE, codes.DELTA, codes.VEL) and (n[0] != 0.0 or n[1] != 0.0)

    def set_mode(self, mode: int) -> None:
        """Change the mode bits; switching the closed loop re-plans the current motion's powers."""
        old = self.mode
        self.mode = mode
        if mode & MODE_SIMULATION:
            self.progress.cancel()  # no power applied: nothing to measure
        if self.landing.active and not self._lands():
            self._land_off()
        if (old ^ mode) & MODE_CLOSED_LOOP:
            if mode & MODE_CLOSED_LOOP:
                self._start_feedback()
            else:
                self._feedback = False
                if self.kind not in (NONE, codes.POWER):
                    t = self._twist
                    flags = self.model.compute(t[0], t[1], t[2], self._rot, self.powers)
                    self._start_drag(flags)
        self.apply()

    def apply(self) -> None:
        """Send the powers to the motors (zeros in simulation mode), only where they changed."""
        sim = self.mode & MODE_SIMULATION or self._coast > 0
        cap = self.power_cap
        peak = cap
        if cap < self.pwm_max:  # the battery limits power: scale every wheel alike, keeping the course
            for p in self.powers:
                peak = max(peak, abs(p))
        for i in range(self.n):
            p = 0 if sim else self.powers[i]
            if peak > cap:
                p = int(p * cap / peak)
            if p != self._applied[i]:
                self._applied[i] = p
                self.hal.set_power(i, p)

    # ------------------------------------------------------------------ commands

    def stop(self) -> bool:
        """Motors off, queue cleared, motion cancelled; True if something was moving."""
        was = self.kind != NONE
        self.queue.clear()
        self.kind = NONE
        self.watchdog.disarm()
        self._feedback = False
        self._braking = False
        self._slewing = False
        self._drag = False
        self._coast = 0
        self._speed = 0.0
        self.progress.cancel()
        self.landing.rest()
        self._land_scale = 1.0
        for i in range(self.n):
            self.powers[i] = 0
        self.apply()
        return was

    def brake(self) -> bool:
        """Brake every motor where the HAL can (``hal.brake``), after :meth:`stop`; the next power
        written releases it. True if every motor brakes."""
        every = True
        for i in range(self.n):
            if self.hal.brake(i):
                self._applied[i] = BRAKED
            else:
                every = False
        return every

    def reset_move(self) -> None:
        """Zero the remembered MOVE that DELTA adds to."""
        for i in range(4):
            self.remembered[i] = 0

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

    # ------------------------------------------------------------------ timeline

    def step(self, dt_us: int) -> None:
        """Advance the timeline by dt_us and start whatever is due."""
        if self.kind != NONE and not self.infinite:
            self.remaining -= dt_us
        if self._coast > 0:
            self._coast -= dt_us
            if self._coast <= 0:
                self.apply()
        guard = LOOP_GUARD
        while guard > 0:
            guard -= 1
            kind = self.kind
            if kind == NONE:
                if len(self.queue) == 0:
                    break
                self._start_next(0)
            elif kind == codes.VEL:
                if len(self.queue):
                    self.watchdog.disarm()
                    self._braking = False
                    self._start_next(0)
                elif self._braking:
                    if not self._slewing and self._at_rest(dt_us):
                        self._finish()
                elif self.watchdog.expired(dt_us):
                    if self._feedback:
                        self.brake_to_rest()
                    else:
                        self._finish()
                break
            elif self.infinite:
                if len(self.queue) == 0:
                    break
                self._start_next(0)
            elif self.remaining > 0:
                break
            elif kind == codes.DELTA and (len(self.queue) == 0 if self._reps_inf else self._reps > 0):
                self._repeat(self.remaining)
            elif len(self.queue):
                self._start_next(self.remaining)
            else:
                self._finish()
        if self._slewing and self.kind == codes.VEL:
            self._slew_due -= dt_us
            if self._slew_due <= 0:
                self._slew(self._drag_period - self._slew_due)
        if self._feedback and self.kind != NONE:
            self._feedback_step(dt_us)
        elif self._drag and self.kind != NONE:
            self._drag_due -= dt_us
            if self._drag_due <= 0:
                self._drag_step()
        if self.progress.state == COASTING:
            self._watch_due -= dt_us
            if self._watch_due <= 0:
                elapsed = self._drag_period - self._watch_due  # a slow loop's checks are further apart
                self._watch_due = self._drag_period
                self._read_counts()
                if self.progress.step(self._counts, elapsed):
                    self._warn(codes.W_SHORT)

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

    def _finish(self) -> None:
        watched = self.progress.moving
        self.stop()
        if watched:
            self._read_counts()
            self.progress.ended(self._counts)
            self._watch_due = self._drag_period
        self._on_idle()

    def _read_counts(self) -> None:
        """Every motor encoder's count into ``_counts``."""
        for i in range(self.n):
            self._counts[i] = self.hal.encoder_count(i)

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
            m[0] = _clamp(m[0] + d[0], lim)
        v = m[1] + d[1]
        if v != 0 and abs(v) < self.v_min:
            v = math.ceil(self.v_min) * (1 if v > 0 else -1)
        elif abs(v) > self.v_max:
            v = int(self.v_max) * (1 if v > 0 else -1)
            self._warn_once(SATURATED)
        m[1] = v
        c = m[2] + d[2]
        m[2] = c % 360 if c >= 0 else -((-c) % 360)
        m[3] = _clamp(m[3] + d[3], self.c_max)
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
            rate = self.landing.rate / self.landing.nominal  # 1/s
            acc = self._acc
            acc[0] = rate * vx
            acc[1] = rate * vy
            acc[2] = rate * w
            self._acc_on = rate != 0.0
            self._acc_turning = False
            vx *= ls
            vy *= ls
            w *= ls
        k = 1.0
        g = self.guard
        if g is not None and (vx != 0.0 or vy != 0.0):
            k = g.factor(vx * 100.0, vy * 100.0)
            if k <= 0.0:
                self.halt = g.code
                self.stop()
                return
            self._warn_once(g.flags)
            vx *= k
            vy *= k
            w *= k
            self._slow_down(math.sqrt(vx * vx + vy * vy) * 100.0, k < 1.0, g.decel)
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
            self._feedforward(vx, vy, w, rotate)
            model.wheel_speeds(vx, vy, w, self._target)
            if self.landing.active:  # the wheels turn faster by their creep, so the body goes as asked
                over = self._over
                if self.landing.overturn(vx, vy, w, over):
                    for i in range(self.n):
                        self._target[i] += over[i]
            if self._acc_on and (self.kind == codes.VEL or self.landing.active):
                self._accel(vx, vy, w, k)
        if self.mode & MODE_CLOSED_LOOP and not self._feedback:
            self._start_feedback()
        elif self._feedback:
            self.speedctl.hold(self._ff, self.powers)  # a new command keeps the speed loop's correction
        self._start_drag(flags)
        self.apply()

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

    def _closed_loop(self) -> bool:
        """The wheel-speed loop drives the motion (MODE bit 1 and encoders on every wheel)."""
        return bool(self.mode & MODE_CLOSED_LOOP) and self.speedctl.available

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

    # ------------------------------------------------------------------ roller drag (open loop)

    def _start_drag(self, flags: int) -> None:
        """Add the rollers' drag to an open-loop translation, and keep it up to date each step; an
        open-loop motion without it whose powers are not whole counts is refreshed each step too
        (dithered: :meth:`PowerModel.refinish`)."""
        model = self.model
        self._drag = not self._feedback and not flags & DEADBAND and (model.drags() or model.fractional())
        if self._drag and model.drags():
            self._drag_step()
        self._drag_due = self._drag_period

    def _drag_step(self) -> None:
        """Recompute the drag from the encoders now (or dither the powers again); the next time one
        control period on."""
        self._drag_due = self._drag_period
        model = self.model
        if model.drags():
            self._read_counts()
            self._warn_once(model.drag(self._counts, self.powers) & SATURATED)
        else:
            model.refinish(self.powers)
        self.apply()

    # ------------------------------------------------------------------ closed loop

    def _start_feedback(self) -> None:
        self._read_counts()
        self.speedctl.reset(self._counts)
        self._feedback = (
            bool(self.mode & MODE_CLOSED_LOOP)
            and self.speedctl.available
            and self.kind not in (NONE, codes.POWER)
        )

    def _feedback_step(self, dt_us: int) -> None:
        ctl = self.speedctl
        if ctl.due(dt_us):  # the encoders are read once a period, when the loop uses them
            self._read_counts()
        if self.landing.active:
            self._land_us += dt_us
            self._deadline -= dt_us
        if ctl.update(dt_us, self._counts, self._target, self._ff, self.powers):
            if self.landing.active:
                self._land_step()
            self.apply()

    # ------------------------------------------------------------------ landing (closed loop)

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
            L = _clamp(L + d[0], self.l_max)
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


def _clamp(v: int, lim: float) -> int:
    """v limited to |v| < lim (lim is an exclusive bound)."""
    m = math.ceil(lim) - 1
    if v > m:
        return m
    if v < -m:
        return -m
    return v


def _duration(amount: int, rate: int, scale: float) -> int:
    """Microseconds for amount / rate, stretched by 1/scale when the powers were saturated."""
    t = amount * 1000000 // rate
    if scale < 1.0:
        t = int(t / scale)
    return t
