"""Path followers: the interface, shared helpers and the registry (strategies by name).

A follower is started on a path at a time, then asked once per control period for a body-frame
velocity command given the robot's estimated state (in the path's frame, already extrapolated to
the time the command is sent)::

    follower = make_follower("tracker", limits, rate=100.0)
    follower.start(path, t)
    while not follower.done:
        command = follower.update(State(t, x, y, theta, vx, vy, w))   # -> VEL vx, vy, w

Followers see only the state they are given (the robot's own estimate), never ground truth.
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


class Follower(ABC):
    """Base class: keeps the path, the limits and the control rate; subclasses implement the law."""

    name: ClassVar[str] = ""
    end_tolerance: ClassVar[float] = 0.02
    """Position error (m) at the end within which the path counts as done."""

    def __init__(self, limits: MotionLimits, *, rate: float = 100.0, **options: Any) -> None:
        if options:
            raise ConfigError(f"follower {self.name!r} has no option(s) {', '.join(sorted(options))}")
        if not rate > 0:
            raise ConfigError(f"control rate must be positive, got {rate}")
        self.limits = limits
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

    @abstractmethod
    def update(self, state: State) -> Command:
        """The command for the next control period."""

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
