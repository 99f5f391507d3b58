"""Path followers: the interface, shared helpers and the registry (strategies by name).

A follower is started on a path at a time, then asked once per control period for a body-frame
velocity command given the robot's estimated state (in the path's frame, already extrapolated to
the time the command is sent)::

    follower = make_follower("tracker", limits, rate=100.0)
    follower.start(path, t)
    while not (follower.done or follower.failure):
        command = follower.update(State(t, x, y, theta, vx, vy, w))   # -> VEL vx, vy, w

Followers see only the state they are given (the robot's own estimate), never ground truth.

Every follower's command is bounded the same way (:meth:`Follower.update` around each law's
:meth:`Follower.command`), as Nav2's controllers and ros2_controllers bound theirs:

* **the limits as given**: the body's twist each law asks is held within ``limits.v_max`` (the user's
  ``--speed``, else the description's ``speed_max``) and ``limits.w_max``; what is sent is that
  twist, or, for the tracker, the twist its learned response model says makes the body do it
  (:meth:`Follower.respond`: on a floor where the body answers slower than asked the VEL is up to
  1.3x that, the body's own speed staying within the limit);
* **no chase**: farther than ``off_path`` m (default :data:`OFF_PATH`) from the path near the
  progress made (a push, a localiser's correction, a wheel stalled then freed), the follower does
  not steer back: it asks STOP from then on and says why in :attr:`Follower.failure` (its
  :attr:`Follower.strayed` is how far off it was); the runtime's follower source ends the run
  there (``follow``: NOT COMPLETED, exit 1; goto: a re-plan from where the robot is);
* **a bounded correction**: the laws that add feedback to the path's own velocity keep that
  correction within :func:`correction_speed` (the speed the robot gains in
  :data:`CORRECTION_TIME` s at its acceleration limit), so near the path the command is at most the
  path's planned speed there plus that margin.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import replace
from typing import Any, ClassVar, TypeVar

from omnibot.control.paths.limits import MotionLimits
from omnibot.control.paths.path import Path
from omnibot.control.paths.profile import (
    SpeedProfile,
    min_traversal_time,
    profile_within,
    time_optimal_profile,
)
from omnibot.errors import ConfigError
from omnibot.motion import Estimate, Twist

State = Estimate
"""The robot's estimated state: world pose and world-frame velocity at time ``t`` (s); the
estimators' :class:`~omnibot.motion.Estimate` itself."""


Command = Twist
"""A body-frame velocity command: vx, vy m/s (x forward, y left), w rad/s (counter-clockwise);
the shared :class:`~omnibot.motion.Twist`."""

STOP = Command(0.0, 0.0, 0.0)
PLAN_MARGIN = 0.7
"""Fraction of the acceleration limits every follower plans its speeds with (the same speed schedule
for all of them; the rest of the grip is left for feedback)."""
PLAN_TIME_BUDGET = 1.2
"""The most a plan with a course-rate cap (:attr:`MotionLimits.course_rate`) may take, in minimum
times without the cap at the full limits (the floor's whole reach: the benchmarks' yardstick): the
cap gives way beyond it (the goal is 1.25x, less what tracking adds)."""
OFF_PATH = 0.5
"""m: how far from the path (the nearest point near the progress made) a follower still steers back;
farther, it stops and fails (:attr:`Follower.failure`). Nav2's ``IsWithinPathTrackingBounds``
defaults to the same 0.5 m either side; the trackers stay within 3 cm of their paths, and a path
handed over from elsewhere begins with a straight run from the robot (``APPROACH_GAP``)."""
CORRECTION_TIME = 0.4
"""s: a follower's feedback adds to the path's velocity at most the speed the robot gains in this
time at its acceleration limit (:func:`correction_speed`: omni4 and mecanum4 0.8 m/s, omni3 1.0
m/s), so a robot pushed off its path comes back at the path's speed plus that, not at its top speed.
The tracker's feedback reaches 0.5 m/s in normal tracking at omni4's top speed (it feeds back the
predicted error, the estimate's velocity in it): at 0.25 s omni4's random paths on carpet came out
0.38 -> 0.41 cm mean RMS, 1.33 -> 1.49 cm max; at 0.4 s as without the bound (BENCHMARKS.md)."""
PLAN_WHEEL_USE = 0.85
"""Fraction of the wheels' free-running speed every follower plans with (the rest is the floor's load
and the wheel-speed loop's headroom; see :mod:`omnibot.control.reach`)."""


def wrap(angle: float) -> float:
    """Angle in [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def to_body(vx: float, vy: float, w: float, theta: float, dt: float = 0.0) -> Command:
    """World-frame velocity to a body-frame command, turned by the heading at the middle of the next
    ``dt`` s (the body keeps turning while the command acts)."""
    th = theta + 0.5 * w * dt
    c, s = math.cos(th), math.sin(th)
    return Command(c * vx + s * vy, -s * vx + c * vy, w)


def clamp_speed(vx: float, vy: float, v_max: float) -> tuple[float, float]:
    """``(vx, vy)`` scaled down to the speed ``v_max`` m/s when faster (kept as is when ``v_max`` <= 0)."""
    speed = math.hypot(vx, vy)
    if speed > v_max > 0:
        return vx * v_max / speed, vy * v_max / speed
    return vx, vy


def correction_speed(limits: MotionLimits) -> float:
    """m/s: the most feedback may add to the path's velocity (:data:`CORRECTION_TIME` at ``a_max``)."""
    return CORRECTION_TIME * limits.a_max


def bound_correction(vx: float, vy: float, ref_vx: float, ref_vy: float, cap: float) -> tuple[float, float]:
    """``(vx, vy)`` with its difference from the reference's ``(ref_vx, ref_vy)`` at most ``cap`` m/s."""
    dx, dy = clamp_speed(vx - ref_vx, vy - ref_vy, cap)
    return ref_vx + dx, ref_vy + dy


def within_limits(limits: MotionLimits, command: Command) -> Command:
    """``command`` with its translation within ``limits.v_max`` and its turn rate within ``w_max``."""
    vx, vy = clamp_speed(command.vx, command.vy, limits.v_max)
    w = max(-limits.w_max, min(limits.w_max, command.w))
    if (vx, vy, w) == (command.vx, command.vy, command.w):
        return command
    return Command(vx, vy, w)


class Follower(ABC):
    """Base class: keeps the path, the limits and the control rate; subclasses implement the law."""

    name: ClassVar[str] = ""
    end_tolerance: ClassVar[float] = 0.02
    """Position error (m) at the end within which the path counts as done."""

    def __init__(
        self, limits: MotionLimits, *, rate: float = 100.0, off_path: float = OFF_PATH, **options: Any
    ) -> None:
        if options:
            raise ConfigError(f"follower {self.name!r} has no option(s) {', '.join(sorted(options))}")
        if not rate > 0:
            raise ConfigError(f"control rate must be positive, got {rate}")
        if not off_path > 0:
            raise ConfigError(f"off_path must be a positive distance (m), got {off_path}")
        self.limits = limits
        self.off_path = off_path
        """m: farther than this from the path the follower stops and fails (see the module docstring)."""
        self.failure = ""
        """Why the follower gave up ("" while it steers): it was farther than :attr:`off_path` from the path."""
        self.strayed: float | None = None
        """m: how far from the path the robot was when the follower gave up (None: it did not)."""
        self._near = 0.0  # arc length of the path's point nearest the robot, m
        self.rate = rate
        self.dt = 1.0 / rate
        self.path: Path | None = None
        self.done = False
        self.progress = 0.0
        """Arc length (m) of the path reached so far."""
        self.t0 = 0.0
        self.options: dict[str, Any] = {}
        """The options it was made with (:func:`make_follower` sets them; ``log replay`` remakes it)."""
        self.planned_accel = 0.0
        """m/s^2: the planned rate of change of the last command's speed (0: no plan); the runtime
        sends it with the VEL to a controller whose wheel-speed loop feeds it forward. The tracker
        plans it only where the reference goes straight with the body's heading held: it is the
        speed-up along the travel, and a turning body or a curving path also needs torque for the
        turn or across the travel, which version 3's VEL does not carry (version 4's does:
        :attr:`planned_body_accel`); fed alone it cost the heading (omni4 on a swinging random path
        0.048 -> 0.059 rad RMS) and the track on a circle (BENCHMARKS.md)."""
        self.planned_body_accel: tuple[float, float, float] | None = None
        """The planned acceleration of the body for the last command (m/s^2 along the body's x and y
        axes: its centre's acceleration in the world, centripetal included; rad/s^2), or None (no
        plan); the runtime sends it with the VEL to a controller of protocol version 4, whose
        wheel-speed loop feeds each wheel its share forward (it carries the turn's and the
        sideways acceleration that :attr:`planned_accel` cannot)."""

    def start(self, path: Path, t: float) -> None:
        """Begin following ``path`` at time ``t`` (the robot stands at its start)."""
        if len(path) < 2 or path.length <= 0:
            raise ConfigError("a path to follow needs at least two distinct points")
        self.path = path
        self.t0 = t
        self.done = False
        self.progress = 0.0
        self.failure = ""
        self.strayed = None
        self._near = 0.0

    def update(self, state: State) -> Command:
        """The command for the next control period: the law's (:meth:`command`) within the limits,
        or STOP once the robot is farther than :attr:`off_path` from the path (then for good:
        :attr:`failure` says why)."""
        if not self.failure:
            self._watch_path(state)
        if self.failure:
            self.planned_accel = 0.0
            self.planned_body_accel = None
            return STOP
        return self.respond(state, within_limits(self.limits, self.command(state)))

    def _watch_path(self, state: State) -> None:
        """Set :attr:`failure` when ``state`` is farther than :attr:`off_path` from the path near the
        point it was nearest last time."""
        path = self.path
        assert path is not None
        near = path.project_near(state.x, state.y, self._near)
        self._near = near.s
        off = math.hypot(state.x - near.x, state.y - near.y)
        if off > self.off_path:
            self.strayed = off
            self.failure = (
                f"off the path: {100 * off:.1f} cm from it {near.s:.2f} m along (more than "
                f"{100 * self.off_path:.0f} cm), not chased"
            )

    @abstractmethod
    def command(self, state: State) -> Command:
        """The law's command for the next control period: the body's twist (:meth:`update` bounds it)."""

    def respond(self, state: State, command: Command) -> Command:
        """What to send for the body to do ``command`` (within the limits): ``command`` itself; a
        follower with a model of how the robot answers (the tracker's) inverts it here."""
        return command

    def plan(self, path: Path, margin: float = PLAN_MARGIN) -> SpeedProfile:
        """The time-optimal profile within ``margin`` of the acceleration limits and
        :data:`PLAN_WHEEL_USE` of the wheels' free speed (honouring the path's v); with a
        course-rate cap, the cap within :data:`PLAN_TIME_BUDGET` of the minimum time without it."""
        limits = self.limits.scaled(margin)
        limits = limits.with_wheel_use(min(limits.wheel_use, PLAN_WHEEL_USE))
        if limits.course_rate is None:
            return time_optimal_profile(path, limits)
        minimum = min_traversal_time(path, replace(self.limits, course_rate=None, floor_use=1.0))
        return profile_within(path, limits, minimum, PLAN_TIME_BUDGET)

    def at_end(self, state: State, tolerance: float | None = None) -> bool:
        """Within ``tolerance`` of the path's end, nearly stopped."""
        assert self.path is not None
        x, y, _ = self.path.end
        tol = self.end_tolerance if tolerance is None else tolerance
        return math.hypot(state.x - x, state.y - y) <= tol and math.hypot(state.vx, state.vy) < 0.05


F = TypeVar("F", bound=type[Follower])

FOLLOWERS: dict[str, Callable[..., Follower]] = {}
"""Followers by name: ``FOLLOWERS[name](limits, rate=..., **options)``."""


def register(name: str, **defaults: Any) -> Callable[[F], F]:
    """Class decorator: register a follower class under ``name`` (with default options)."""

    def deco(cls: F) -> F:
        def factory(limits: MotionLimits, **options: Any) -> Follower:
            follower = cls(limits, **{**defaults, **options})
            follower.name = name  # type: ignore[misc]
            follower.options = {**defaults, **options}
            return follower

        if name in FOLLOWERS:
            raise ValueError(f"follower {name!r} registered twice")
        FOLLOWERS[name] = factory
        return cls

    return deco


def follower_names() -> list[str]:
    """The names of the registered followers (the built-in ones are registered on first call)."""
    from omnibot.control import followers  # noqa: F401  (registers the built-in followers)

    return list(FOLLOWERS)


def make_follower(name: str, limits: MotionLimits, **options: Any) -> Follower:
    """The follower registered as ``name``; ConfigError naming the choices if there is none."""
    names = follower_names()
    if name not in FOLLOWERS:
        import difflib

        close = difflib.get_close_matches(name, names, n=1, cutoff=0.5)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise ConfigError(f"unknown follower '{name}'{hint}; expected one of: {', '.join(names)}")
    return FOLLOWERS[name](limits, **options)
