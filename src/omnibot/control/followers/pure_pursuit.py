"""Holonomic pure pursuit: drive toward a point a lookahead distance ahead on the path.

The robot's progress is its projection on the path (searched near the last one, so a
self-crossing path is not short-cut); the goal is the path point ``lookahead`` further on,
lookahead = max(min_lookahead, lookahead_time x speed). An omnidirectional robot needs no
steering geometry: it translates straight at the goal at the profile's speed for its progress
(the path's v if the file has one), and turns its body toward the path's heading at the goal
(feedforward of the path's heading rate plus a proportional term). Near the end the speed follows
a braking curve to the last point.
"""

from __future__ import annotations

import math
from typing import Any

from omnibot.control.followers.base import (
    PLAN_MARGIN,
    STOP,
    Command,
    Follower,
    State,
    clamp_speed,
    register,
    to_body,
    wrap,
)
from omnibot.control.paths.limits import MotionLimits
from omnibot.control.paths.path import Path
from omnibot.control.paths.profile import SpeedProfile

CREEP = 0.1
"""m/s: the least speed commanded (from rest, and near the end until within ``end_tolerance``):
slower, a robot in its motors' dead band does not move."""


@register("pure_pursuit")
class PurePursuit(Follower):
    """Holonomic pure pursuit with a speed-scaled lookahead."""

    def __init__(
        self,
        limits: MotionLimits,
        *,
        rate: float = 100.0,
        lookahead_time: float = 0.3,
        min_lookahead: float = 0.08,
        heading_gain: float = 4.0,
        margin: float = PLAN_MARGIN,
        **options: Any,
    ) -> None:
        super().__init__(limits, rate=rate, **options)
        self.lookahead_time = lookahead_time
        self.min_lookahead = min_lookahead
        self.heading_gain = heading_gain
        self.margin = margin
        self.profile: SpeedProfile | None = None

    def start(self, path: Path, t: float) -> None:
        """Begin following ``path`` at time ``t``: plan its speed profile with the follower's margin."""
        super().start(path, t)
        self.profile = self.plan(path, self.margin)

    def command(self, state: State) -> Command:
        """Steer toward the look-ahead point on the path at the profile's speed; STOP once done."""
        path, prof = self.path, self.profile
        assert path is not None and prof is not None
        if self.done:
            return STOP
        proj = path.project_near(
            state.x, state.y, self.progress, ahead=0.2 + 2.0 * self.limits.v_max * self.dt
        )
        self.progress = max(self.progress, proj.s)
        speed = max(prof.speed_at(proj.s), CREEP)
        lookahead = max(self.min_lookahead, self.lookahead_time * speed)
        gx, gy, gth = path.at(proj.s + lookahead)
        ex, ey = path.end[0] - state.x, path.end[1] - state.y
        remaining = math.hypot(ex, ey)
        if proj.s + lookahead >= path.length:
            brake = math.sqrt(2.0 * self.limits.a_max * self.margin * remaining)
            speed = min(speed, max(brake, CREEP))
            if path.length - proj.s < 2 * self.end_tolerance and self.at_end(state):
                self.done = True
                return STOP
        dx, dy = gx - state.x, gy - state.y
        dist = math.hypot(dx, dy)
        if dist < 1e-6:
            vx = vy = 0.0
        else:
            vx, vy = speed * dx / dist, speed * dy / dist
        vx, vy = clamp_speed(vx, vy, self.limits.v_max)
        # heading: toward the path's heading at the goal, with the path's turn rate fed forward
        ahead = path.heading_at(min(proj.s + 0.02, path.length)) - path.heading_at(proj.s)
        w_ff = ahead / 0.02 * speed if proj.s + 0.02 <= path.length else 0.0
        w = w_ff + self.heading_gain * wrap(gth - state.theta)
        w = max(-self.limits.w_max, min(self.limits.w_max, w))
        return to_body(vx, vy, w, state.theta, self.dt)
