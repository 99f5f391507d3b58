"""Seed 002's path following as written: straight segments, offset-heading correction, speed PID.

Seed 002 (Tak et al.) breaks the taught path into "miniscule straight lines" between sampled points
and drives each one in turn (section IV):

* direction of travel (13): theta = atan(dY / dX) of the segment (X1, Y1) -> (X2, Y2), turned into
  wheel speeds by (5)-(7) - here a world-frame velocity turned into the body frame by the heading;
* heading hold: a PID on the gyro heading error, "perpetually running" in parallel;
* reduced overshoot, part 1 (14)-(15): the offset heading d_theta, found by the same triangulation
  from where the robot is to the segment's end, is subtracted (offset path 1, left of the line) or
  added (offset path 2, right of it), every loop ("placed in the main loop ... this will prevent path
  error to accumulate"); so the robot heads for the end of the segment from wherever it is;
* reduced overshoot, part 2 (16)-(17): speed control, a PID on the distance travelled per loop
  (diff_x, diff_y) against the preset speed; its flow chart (Fig. 5) passes only Kp, so the default
  gains are proportional only.

Without reduced overshoot the direction stays the segment's own (13) and the speed is commanded open
loop: errors are never corrected, only segment switching looks at the position. A segment is done
when the robot has passed its end (its projection on the segment goes beyond it); after the last one
the robot is told to stand still (zero velocity) until it has stopped.

Interpretation choices (the paper leaves them open): the path is resampled into segments of
``segment`` m (the taught sampling); the preset speed at each point is the path's v when the file
has one, else the time-optimal profile within the follower's margin (the same speed the other
followers are offered); the heading target is the path's theta at the segment's end.
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
    correction_speed,
    register,
    to_body,
    wrap,
)
from omnibot.control.paths.geometry import resample
from omnibot.control.paths.limits import MotionLimits
from omnibot.control.paths.path import Path
from omnibot.control.paths.profile import SpeedProfile
from omnibot.control.pid import PID

CREEP = 0.1
"""m/s: the least speed commanded before the last point is passed (a stop short of it never ends)."""


@register("seed002", reduced_overshoot=True)
@register("seed002-plain", reduced_overshoot=False)
class Seed002Follower(Follower):
    """Seed 002's straight-segment follower (``reduced_overshoot`` selects (14)-(17))."""

    def __init__(
        self,
        limits: MotionLimits,
        *,
        rate: float = 100.0,
        reduced_overshoot: bool = True,
        segment: float = 0.10,
        margin: float = PLAN_MARGIN,
        heading_gains: tuple[float, float, float] = (4.0, 0.5, 0.1),
        speed_gains: tuple[float, float, float] = (0.5, 0.0, 0.0),
        **options: Any,
    ) -> None:
        super().__init__(limits, rate=rate, **options)
        if not segment > 0:
            raise ValueError(f"segment length must be positive, got {segment}")
        self.reduced_overshoot = reduced_overshoot
        self.segment = segment
        self.margin = margin
        kp, ki, kd = heading_gains
        w = limits.w_max
        self.heading_pid = PID(kp, ki, kd, lo=-w, hi=w, i_limit=0.2, d_tau=0.02)
        kp, ki, kd = speed_gains
        v = limits.v_max
        i_limit = 0.2 * v / ki if ki > 0 else 0.0
        # the speed loop slows down as it likes, and speeds up by at most the bounded correction
        hi = min(0.5 * v, correction_speed(limits))
        self.speed_pid = PID(kp, ki, kd, lo=-0.5 * v, hi=hi, i_limit=i_limit, d_tau=0.03)
        self.points: Path | None = None
        self.profile: SpeedProfile | None = None
        self.index = 0
        self._direction = 0.0
        self._last: State | None = None
        self._arrived = False

    def start(self, path: Path, t: float) -> None:
        """Begin following ``path`` at time ``t``: resample it into segments, plan the speed, reset the
        heading PID."""
        super().start(path, t)
        self.points = resample(path, self.segment)
        self.profile = self.plan(path, self.margin)
        self.index = 0
        self._last = None
        self._arrived = False
        self.heading_pid.reset()
        self.speed_pid.reset()
        self._begin_segment(None)

    def _segment(self) -> tuple[float, float, float, float]:
        p = self.points
        assert p is not None
        i = self.index
        return float(p.x[i]), float(p.y[i]), float(p.x[i + 1]), float(p.y[i + 1])

    def _begin_segment(self, state: State | None) -> None:
        x1, y1, x2, y2 = self._segment()
        self._direction = math.atan2(y2 - y1, x2 - x1)  # (13)

    def _passed(self, state: State) -> bool:
        x1, y1, x2, y2 = self._segment()
        dx, dy = x2 - x1, y2 - y1
        length = math.hypot(dx, dy)
        if length <= 0:
            return True
        along = ((state.x - x1) * dx + (state.y - y1) * dy) / length
        return along >= length

    def command(self, state: State) -> Command:
        """Seed 002's segment-by-segment command for this state; STOP once done."""
        p, prof = self.points, self.profile
        assert p is not None and prof is not None and self.path is not None
        dt = self.dt if self._last is None else max(state.t - self._last.t, 1e-6)
        last = self._last
        self._last = state
        if self.done:
            return STOP
        while self.index < len(p) - 2 and self._passed(state):
            self.index += 1
            self._begin_segment(state)
        x1, y1, x2, y2 = self._segment()
        final = self.index == len(p) - 2
        if final and (self._passed(state) or self.at_end(state)):
            self._arrived = True
        if self._arrived:  # the last point is reached: hold still (zero velocity) until stopped
            if math.hypot(state.vx, state.vy) < 0.05:
                self.done = True
            return STOP

        direction = self._direction
        if self.reduced_overshoot:
            # offset heading by triangulation from the robot to the segment end, (14) or (15)
            offset = wrap(math.atan2(y2 - state.y, x2 - state.x) - direction)
            if offset < 0:
                direction -= abs(offset)  # (14): the robot is on offset path 1 (left of the line)
            else:
                direction += abs(offset)  # (15): offset path 2

        length = math.hypot(x2 - x1, y2 - y1)
        along = ((state.x - x1) * (x2 - x1) + (state.y - y1) * (y2 - y1)) / length if length > 0 else 0.0
        self.progress = float(p.s[self.index]) + min(max(along, 0.0), length)
        target = max(prof.speed_at(self.progress), CREEP)  # the speed stored where the robot is
        if final:
            remaining = math.hypot(x2 - state.x, y2 - state.y)
            brake = math.sqrt(2.0 * self.limits.a_max * self.margin * remaining)
            target = min(target, max(brake, CREEP))
        speed = target
        if self.reduced_overshoot and last is not None:
            # (16)-(17): distance travelled in the loop against the preset speed, PID on the error
            diff_x, diff_y = state.x - last.x, state.y - last.y
            measured = math.hypot(diff_x, diff_y) / dt
            speed = target + self.speed_pid.update(target - measured, dt, measurement=measured)
        speed = min(max(speed, 0.0), self.limits.v_max)

        heading_target = float(p.theta[self.index + 1])
        w = self.heading_pid.update(wrap(heading_target - state.theta), dt, measurement=state.theta)
        vx, vy = clamp_speed(speed * math.cos(direction), speed * math.sin(direction), self.limits.v_max)
        return to_body(vx, vy, w, state.theta, self.dt)
