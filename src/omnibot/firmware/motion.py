"""The motion executor: runs queued MOVE/ROTATE/DELTA/POWER commands and VEL on a timeline.

Time is kept as the remaining microseconds of the current motion; a motion that ends mid-poll hands
its overshoot to the next one, so a run of queued motions keeps its timeline (37 moves of 50 ms take
1850 ms, whatever the poll rate). Infinite motions (L or A = +-INF) and VEL end as soon as a command
is queued behind them. Each step also runs the loop that refreshes the powers: the wheel-speed loop
(closed loop) or the rollers' drag (open loop), and the progress watch of a MOVE's coast.

:class:`Executor` is composed of one part per concern, each a mixin over the shared
:class:`~omnibot.firmware.motion_state.MotionState` (on MicroPython flattened into one class,
:func:`~omnibot.firmware.mixins.flat`):

================================  ============================================================
``motion_commands.py``            VEL; MOVE, ROTATE, DELTA, POWER started from the queue
``motion_drive.py``               a twist to powers, the sonar guard's limit, the warnings
``motion_landing.py``             closed-loop landing of finite motions on the encoders
``motion_brake.py``               the brake to rest of a VEL let go on the speed loop
================================  ============================================================
"""

from omnibot.firmware.mixins import flat
from omnibot.firmware.motion_brake import Brake
from omnibot.firmware.motion_commands import Commands
from omnibot.firmware.motion_drive import Drive
from omnibot.firmware.motion_landing import LandingMotion
from omnibot.firmware.motion_state import NONE
from omnibot.firmware.power import DEADBAND, SATURATED, PowerModel
from omnibot.firmware.progress import COASTING
from omnibot.protocol import codes

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any

    from omnibot.firmware.hal import HAL
    from omnibot.firmware.queue import CommandQueue

MODE_SIMULATION = codes.MODE_SIMULATION
MODE_CLOSED_LOOP = codes.MODE_CLOSED_LOOP
BRAKED = 1 << 20  # applied-power marker of a braked motor: any power written next releases it
LOOP_GUARD = 16  # motions started in one step at most (zero-length moves), keeps a poll short


class Executor(Drive, LandingMotion, Commands, Brake):
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
        self._init_drive(cfg)
        self._init_brake(cfg)
        self._init_loops(cfg)
        for i in range(self.n):
            hal.set_power(i, 0)

    # ------------------------------------------------------------------ state

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

    def _finish(self) -> None:
        watched = self.progress.moving
        self.stop()
        if watched:
            self._read_counts()
            self.progress.ended(self._counts)
            self._watch_due = self._drag_period
        self._on_idle()

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


if not TYPE_CHECKING:
    Executor = flat(Executor)  # one class on MicroPython (mixins.py)
