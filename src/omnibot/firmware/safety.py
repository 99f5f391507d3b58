"""The sonar stop's guard: the speed the robot may drive given what its sonars see (docs/safety.md).

A sonar is *armed* when it measures (SONAR period P > 0) with a stop threshold (STOP > 0). For an
armed sonar and travel at speed v (cm/s) in the body direction u, as a safety-rated scanner's
protective field (ISO 13855: S = K T + C) or Nav2's collision monitor "approach" model::

    closing speed   c = v cos(max(0, angle(u, axis) - half cone))   (0 when it moves away)
    stop distance   D(c) = STOP + c (P + latency) + c^2 / (2 a)
    room            the range r less what the footprint needs (:meth:`SonarGuard.travel_room`)
    latency         echo flight 2 r / 343 m/s + one main-loop pass + LATENCY_MS

``a`` is the robot's stop deceleration (config ``stop_decel_cms2``): the robot, cut off at a reading,
stops within c latency + c^2/(2a) of it; one period on, the next reading must find it still D away.
So with a range r the closing speed may be at most the root of D(c) = room:
``c_max = a (sqrt(T^2 + 2 (room - STOP) / a) - T)``, T = P + latency. The guard scales the commanded
twist down to that (flag LIMITED, WARN 14), never below the robot's slowest speed; when even that is
too fast the motion must stop at once (``W_SONAR_STOP``, the emergency stop). A reading with no echo
right after a range keeps that range less the travel since (one missed echo is bridged).

A direction of travel is *covered* when it lies inside the cone of an armed sonar. Travel no armed
sonar covers, while any is armed, is limited to ``uncovered_speed_cms`` (flag UNCOVERED, WARN 15),
or refused when ``refuse`` is set (MODE bit 3): ``E_UNCOVERED`` for a command, ``W_UNCOVERED_STOP``
for a motion that turns out uncovered when it runs (a DELTA's new course, a command queued earlier).
"""

import math

from omnibot.protocol import codes

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any

    from omnibot.firmware.sonar import Sonars

LIMITED = 4  # executor warning flags (power.py owns 1, 2 and 16)
UNCOVERED = 8
LATENCY_MS = 2  # driver and bookkeeping on top of the echo and one loop pass
SOUND_CMS = 34300.0
HALF_CONE_DEG = 7.5  # an HC-SR04's 15 degrees, for a config without sonar geometry
INCIDENCE_MAX = math.radians(60.0)  # walls met at 30 degrees or more to them are allowed for
INCIDENCE_STEPS = 12  # 5 degree steps


class SonarGuard:
    """Speed factors for body velocities from the armed sonars' latest ranges."""

    def __init__(self, cfg: "dict[str, Any]", sonars: "Sonars") -> None:
        self.sonars = sonars
        n = sonars.count
        axes = cfg.get("sonar_axes") or [[0.0, HALF_CONE_DEG, 0.0, 0.0]] * n
        self.ax = [math.cos(math.radians(float(a[0]))) for a in axes]
        self.ay = [math.sin(math.radians(float(a[0]))) for a in axes]
        self.half = [math.radians(float(a[1])) for a in axes]
        self.lead = [float(a[2]) for a in axes]
        self.width = [float(a[3]) for a in axes]
        self.decel = float(cfg.get("stop_decel_cms2", 100.0))
        self.v_min = float(cfg["speed_min_cms"])
        self.uncovered_speed = float(cfg.get("uncovered_speed_cms", 25.0))
        self.loop_ms = 1000.0 / float(cfg.get("loop_hz", 500)) + LATENCY_MS
        self.range = [-1.0] * n
        self.room = [-1.0] * n  # travel left before the footprint could touch, cm (-1: no range)
        self.refuse = False
        self.code = 0
        self.flags = 0
        self._closing = [0.0] * n
        self._missed = [False] * n

    def armed(self, s: int) -> bool:
        """Whether sonar ``s`` guards the motion: it measures (period > 0) and has a stop distance."""
        return self.sonars.period[s] > 0 and self.sonars.stop[s] > 0

    def reading(self, s: int, cm: int) -> None:
        """A new reading of sonar s (cm, -1 for no echo)."""
        if cm >= 0:
            self.range[s] = float(cm)
            self._missed[s] = False
        elif self.range[s] >= 0 and not self._missed[s]:  # first miss: the last range, less the travel
            self.range[s] = max(0.0, self.range[s] - self._closing[s] * self.sonars.period[s] * 0.001)
            self._missed[s] = True
        else:  # a second miss in a row: nothing in range
            self.range[s] = -1.0
        self.room[s] = self.travel_room(s, self.range[s])

    def travel_room(self, s: int, r: float) -> float:
        """How far (cm) the robot may travel along sonar s's axis before its footprint could touch
        a straight wall whose nearest point in the cone is r away, for walls met at up to
        INCIDENCE_MAX from square (the footprint's corners lead at a slant; the cone's edge sees a
        slanted wall before the axis does), less the footprint's lead ahead of the sonar."""
        if r < 0:
            return -1.0
        half = self.half[s]
        w = self.width[s]
        room = r
        for k in range(1, INCIDENCE_STEPS + 1):
            a = INCIDENCE_MAX * k / INCIDENCE_STEPS
            seen = r * math.cos(a - half) if a > half else r
            room = min(room, (seen - w * math.sin(a)) / math.cos(a))
        return max(0.0, room - self.lead[s])

    def clear(self, s: int) -> None:
        """Forget sonar s's range (it was reconfigured)."""
        self.range[s] = -1.0
        self.room[s] = -1.0
        self._missed[s] = False

    def below_stop(self) -> bool:
        """An armed sonar's range is below its STOP threshold (for motions without travel)."""
        for s in range(self.sonars.count):
            if self.armed(s) and 0 <= self.range[s] < self.sonars.stop[s]:
                return True
        return False

    def covers(self, vx: float, vy: float) -> bool:
        """Travel along (vx, vy) lies in an armed sonar's cone, or nothing is armed."""
        v = math.sqrt(vx * vx + vy * vy)
        armed = False
        for s in range(self.sonars.count):
            if self.armed(s):
                armed = True
                if v > 0 and _angle(vx / v, vy / v, self.ax[s], self.ay[s]) <= self.half[s]:
                    return True
        return not armed

    def closing_max(self, s: int) -> float:
        """Fastest closing speed (cm/s) at which sonar s's last range leaves room to stop."""
        d = self.room[s] - self.sonars.stop[s]
        if d <= 0:
            return 0.0
        t = (self.sonars.period[s] + self.loop_ms) * 0.001 + 2.0 * self.range[s] / SOUND_CMS
        a = self.decel
        return a * (math.sqrt(t * t + 2.0 * d / a) - t)

    def factor(self, vx: float, vy: float) -> float:
        """Scale (0..1] for travel at (vx, vy) cm/s in the body frame; 0: it must not go on.

        Sets :attr:`flags` (LIMITED, UNCOVERED) and, when 0, :attr:`code` (why).
        """
        self.flags = 0
        self.code = 0
        v = math.sqrt(vx * vx + vy * vy)
        if v <= 0:
            return 1.0
        ux = vx / v
        uy = vy / v
        allowed = v
        armed = False
        covered = False
        for s in range(self.sonars.count):
            self._closing[s] = 0.0
            if not self.armed(s):
                continue
            armed = True
            off = _angle(ux, uy, self.ax[s], self.ay[s]) - self.half[s]
            if off <= 0:
                covered = True
                c = 1.0
            elif off < math.pi / 2:
                c = math.cos(off)
            else:
                continue  # moving away from all the cone sees
            self._closing[s] = v * c
            if self.room[s] >= 0:
                m = self.closing_max(s) / c
                allowed = min(allowed, m)
        if armed and not covered:
            if self.refuse:
                self.code = codes.E_UNCOVERED
                return 0.0
            if self.uncovered_speed < v:
                self.flags |= UNCOVERED
                allowed = min(allowed, self.uncovered_speed)
        if allowed >= v:
            return 1.0
        floor = v if v < self.v_min else self.v_min
        if allowed < floor:
            self.code = codes.W_SONAR_STOP
            return 0.0
        if not self.flags & UNCOVERED or allowed < self.uncovered_speed:
            self.flags |= LIMITED
        return allowed / v


def _angle(ux: float, uy: float, ax: float, ay: float) -> float:
    """Angle (rad, 0..pi) between unit vectors."""
    d = ux * ax + uy * ay
    if d >= 1.0:
        return 0.0
    if d <= -1.0:
        return math.pi
    return math.acos(d)
