"""The executor's state, shared by its parts (:mod:`~omnibot.firmware.motion` and the ``motion_*`` mixins).

:class:`MotionState` holds what more than one part reads or writes: the current motion, its powers
and twist, the remembered MOVE, the mode bits, a VEL's planned acceleration, the closed loops'
objects (progress watch, landing, speed loop) and their timing. Each mixin keeps its own state
besides (``_init_drive``, ``_init_brake``); under ``TYPE_CHECKING`` this class names, for mypy only,
the state and methods a part uses from another one.
"""

import math

from omnibot.firmware.landing import Landing
from omnibot.firmware.progress import ProgressWatch
from omnibot.firmware.speedctl import SpeedControl
from omnibot.firmware.watchdog import Watchdog
from omnibot.protocol import codes

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any

    from omnibot.firmware.hal import HAL
    from omnibot.firmware.power import PowerModel
    from omnibot.firmware.queue import CommandQueue
    from omnibot.firmware.safety import SonarGuard

MODE_CLOSED_LOOP = codes.MODE_CLOSED_LOOP
NONE = 0  # no motion (kinds are the command ids of protocol/codes.py otherwise)


class MotionState:
    """The state of the executor's current motion and loops (see the module docstring)."""

    if TYPE_CHECKING:
        hal: HAL
        queue: CommandQueue
        model: PowerModel
        n: int
        _warn: Callable[[int], None]
        _on_idle: Callable[[], None]
        l_max: float
        v_min: float
        v_max: float
        c_max: float
        vel_dead_band: bool
        _braking: bool  # the brake to rest's (motion_brake.py)
        _slewing: bool
        _slew_due: int

        def apply(self) -> None:
            """Executor.apply (motion.py)."""

        def stop(self) -> bool:
            """Executor.stop (motion.py)."""

        def _start_feedback(self) -> None:
            """Executor._start_feedback (motion.py)."""

        def _start_drag(self, flags: int) -> None:
            """Executor._start_drag (motion.py)."""

        def _drive(self, vx: float, vy: float, w: float, rotate: bool, gain: float = 1.0) -> None:
            """Drive._drive (motion_drive.py)."""

        def _warn_once(self, flags: int) -> None:
            """Drive._warn_once (motion_drive.py)."""

        def _land_reset(self) -> None:
            """LandingMotion._land_reset (motion_landing.py)."""

        def _land_start(
            self, ux: float, uy: float, uw: float, rotate: bool, goal: float, nominal: float
        ) -> None:
            """LandingMotion._land_start (motion_landing.py)."""

        def _timed(self, duration: int, carry: int) -> None:
            """LandingMotion._timed (motion_landing.py)."""

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
        self._acc = [0.0, 0.0, 0.0]  # a VEL's planned body acceleration, m/s^2, m/s^2, rad/s^2
        self._acc_on = False  # the VEL carries one
        self._acc_turning = False  # version 4's: the wheels' part takes the turning axes' term (_accel)
        self._counts = [0] * self.n

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

    @property
    def moving(self) -> bool:
        """True while a motion runs (idle otherwise)."""
        return self.kind != NONE

    @property
    def travelling(self) -> bool:
        """A MOVE, DELTA or VEL that translates the body (what the sonar guard limits)."""
        n = self._nominal
        return self.kind in (codes.MOVE, codes.DELTA, codes.VEL) and (n[0] != 0.0 or n[1] != 0.0)

    def _closed_loop(self) -> bool:
        """The wheel-speed loop drives the motion (MODE bit 1 and encoders on every wheel)."""
        return bool(self.mode & MODE_CLOSED_LOOP) and self.speedctl.available

    def _read_counts(self) -> None:
        """Every motor encoder's count into ``_counts``."""
        for i in range(self.n):
            self._counts[i] = self.hal.encoder_count(i)


def clamp(v: int, lim: float) -> int:
    """v limited to |v| < lim (lim is an exclusive bound)."""
    m = math.ceil(lim) - 1
    if v > m:
        return m
    if v < -m:
        return -m
    return v
