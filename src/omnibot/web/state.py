"""The live state the page shows, folded from telemetry: pose, wheels, heading, battery, sonars, link.

:class:`StateTracker` is a client listener (it runs in the link thread) plus :meth:`frame`, which
builds one ``state`` frame (JSON-ready, SI units). Wheel speeds come from encoder count differences
over the controller's own time stamps; the pose is the simulator's ground truth on ``sim://`` and
the robot's estimate on a real robot: the ``fused`` estimator the followers use
(:mod:`omnibot.estimation.estimator`), whose heading filter learns the gyro's bias whenever the wheels
stand still and takes it out. The ``heading`` chart shows that heading too: the controller's raw gyro
sum (TEL's heading) drifts by the bias, about 0.6-0.8 degree/s, on a robot standing still.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any

from omnibot.client import Telemetry
from omnibot.errors import ConfigError
from omnibot.estimation import Estimator, make_estimator
from omnibot.motion import Pose2D
from omnibot.protocol import codes
from omnibot.robot import RobotDescription, battery_level

STATES = {
    codes.STATE_MOVING: "moving",
    codes.STATE_IDLE: "idle",
    codes.STATE_ESTOP: "estop",
    codes.STATE_BATTERY: "battery stop",
}


@dataclass
class LinkHealth:
    """How the robot link is doing, as the link thread sees it."""

    url: str
    ok: bool = True
    error: str = ""
    errors: int = 0
    rtt: float | None = None
    """s from sending the last VEL to its OK (link clock)."""
    tel_times: deque[float] = field(default_factory=lambda: deque(maxlen=400))

    def tel_rate(self, now: float, window: float = 1.0) -> float:
        """TEL samples per second over the last ``window`` s of link time."""
        return sum(1 for t in self.tel_times if now - t <= window) / window


def _r(value: float | None, digits: int = 4) -> float | None:
    return None if value is None or not math.isfinite(value) else round(value, digits)


class StateTracker:
    """Keeps the newest telemetry and derived values for the state frames."""

    def __init__(self, robot: RobotDescription, url: str, start: Pose2D | None = None) -> None:
        self.robot = robot
        self.health = LinkHealth(url)
        self.last: Telemetry | None = None
        self.wheel_speeds: list[float] | None = None
        cpr = {e.wheel: e.counts_per_rev for e in robot.encoders.motors}
        self._rad_per_count = [2 * math.pi / cpr[w.name] if w.name in cpr else 0.0 for w in robot.wheels]
        try:
            self.estimator: Estimator | None = make_estimator("fused", robot, start)
        except ConfigError:  # no sensors to estimate from
            self.estimator = None
        self._prev: tuple[float, tuple[int, ...]] | None = None

    def __call__(self, tel: Telemetry) -> None:
        """Listener for Telemetry events."""
        self.health.tel_times.append(tel.time)
        self.last = tel
        if tel.encoders is None:
            return
        if self._prev is not None and len(tel.encoders) == len(self._prev[1]):
            dt = tel.controller_time - self._prev[0]
            if dt > 0:
                self.wheel_speeds = [
                    (c - p) * k / dt
                    for c, p, k in zip(tel.encoders, self._prev[1], self._rad_per_count, strict=False)
                ]
        self._prev = (tel.controller_time, tel.encoders)
        if self.estimator is not None and len(tel.encoders) == self.robot.n_wheels:
            self.estimator.update(tel)

    def _battery_level(self, tel: Telemetry | None) -> str:
        """ok, low, limited, flat (the thresholds of the description; flat also while the controller
        holds its battery stop) or unknown."""
        b = self.robot.battery
        stopped = tel is not None and tel.state == codes.STATE_BATTERY
        return battery_level(None if tel is None else tel.battery, b.warn_v, b.limit_v, b.stop_v, stopped)

    def frame(
        self, now: float, truth: tuple[float, float, float] | None, drive: dict[str, Any]
    ) -> dict[str, Any]:
        """One ``state`` frame: ``now`` on the link clock, ``truth`` the simulator's pose if any."""
        tel = self.last
        odo = self.estimator.estimate if self.estimator is not None else None
        if truth is not None:
            pose, source = truth, "truth"
        elif odo is not None:
            pose, source = (odo.x, odo.y, odo.theta), "odometry"
        else:
            pose, source = None, "none"
        h = self.health
        return {
            "type": "state",
            "t": round(now, 3),
            "pose": None if pose is None else [_r(v) for v in pose],
            "pose_source": source,
            "odometry": None if odo is None else [_r(odo.x), _r(odo.y), _r(odo.theta)],
            "powers": None if tel is None or tel.powers is None else list(tel.powers),
            "wheel_speeds": None if self.wheel_speeds is None else [_r(v, 2) for v in self.wheel_speeds],
            "heading": None if tel is None else _r(odo.theta if odo is not None else tel.heading),
            "battery": None if tel is None else _r(tel.battery, 3),
            "battery_level": self._battery_level(tel),
            "ranges": None if tel is None or tel.ranges is None else [_r(r, 3) for r in tel.ranges],
            "robot_state": None
            if tel is None or tel.state is None
            else STATES.get(tel.state, str(tel.state)),
            "drive": drive,
            "link": {
                "url": h.url,
                "ok": h.ok,
                "error": h.error,
                "errors": h.errors,
                "rtt_ms": None if h.rtt is None else round(h.rtt * 1000, 1),
                "tel_hz": round(h.tel_rate(now), 1),
            },
        }
