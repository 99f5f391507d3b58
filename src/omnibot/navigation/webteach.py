"""Teach and repeat from the dashboard: record the path the robot is driven along, then follow it.

:class:`PathTeacher` is the dashboard's teach hook (:class:`omnibot.web.teach.TeachRepeat`). It keeps
its own estimate of the pose from the controller's telemetry (the ``fused`` estimator, started at
the pose the page shows, so the page and the path share a frame), and:

* **Teach** starts a :class:`~omnibot.control.paths.teach.PathRecorder` (a pose every 2 cm, heading
  kept): drive the robot with the page's stick, keys or a gamepad;
* **Stop** ends the recording (or stops a repeat);
* **Repeat** follows the taught path with the ``tracker`` at the dashboard's command rate, speed
  capped at ``speed``, with the controller's wheel-speed loop on (MODE bit 1, when every wheel has an
  encoder; the previous mode comes back when the repeat ends). If the robot is not where the path
  starts, it first drives straight there.

Everything runs in the dashboard's link thread, which owns the client; the page's driving is
ignored while a path is followed, and the emergency stop ends a repeat.
"""

from __future__ import annotations

import math
from typing import Any

from omnibot.client.client import RobotClient
from omnibot.client.events import Telemetry
from omnibot.control.followers.base import Follower, State, make_follower
from omnibot.control.paths.path import Path
from omnibot.control.paths.teach import PathRecorder
from omnibot.estimation.estimator import PoseEstimator
from omnibot.estimation.slip import SlipParameters
from omnibot.motion import Pose2D
from omnibot.navigation.runner import submit_vel
from omnibot.navigation.session import follower_limits
from omnibot.robot.description import RobotDescription

APPROACH_GAP = 0.02
"""m: farther than this from the path's start, a repeat first drives straight to it."""
WATCHDOG = 0.25
"""s: the VEL watchdog while following (longer than the dashboard's command period)."""


def gains_for(period: float) -> dict[str, float]:
    """Tracker gains for a control period (the defaults are for 100 Hz): the loop gain per period
    stays below 0.5, the lead covers telemetry age plus one period."""
    scale = min(1.0, 0.01 / period)
    return {
        "cross": 45.0 * scale,
        "cross_i": 100.0 * scale * scale,
        "along": 10.0 * scale,
        "along_i": 20.0 * scale * scale,
        "heading": 8.0 * scale,
        "heading_i": 10.0 * scale * scale,
        "lead": 0.04 + period,
    }


class PathTeacher:
    """Teach and repeat for the dashboard (see the module docstring)."""

    def __init__(
        self,
        robot: RobotDescription,
        *,
        period: float = 0.05,
        speed: float = 0.3,
        slip: SlipParameters | None = None,
    ) -> None:
        if not (period > 0 and speed > 0):
            raise ValueError(f"period and speed must be positive, got {period} and {speed}")
        self.robot = robot
        self.period = period
        self.speed = speed
        self.slip = slip
        self.estimator: PoseEstimator | None = None
        self.recorder: PathRecorder | None = None
        self.path: Path | None = None
        """The last taught path (estimator frame = the page's frame)."""
        self.follower: Follower | None = None
        self._client: RobotClient | None = None
        self._start: Pose2D = Pose2D(0.0, 0.0, 0.0)
        self._mode: int | None = None  # the MODE to restore after a repeat
        cpr = {e.wheel for e in robot.encoders.motors}
        self.wheel_loop = all(w.name in cpr for w in robot.wheels)

    # ------------------------------------------------------------------ the hook

    def command(self, action: str, client: RobotClient, pose: tuple[float, float, float] | None) -> str:
        """Teach (``record``), Stop (``stop``) or Repeat (``follow``); the line the page shows."""
        self._attach(client, pose)
        if action == "record":
            self.follower = None
            self.recorder = PathRecorder("distance", 0.02)
            self._record()
            return "teaching: drive the path, then press Stop"
        if action == "stop":
            if self.follower is not None:
                self._end_repeat(client)
                return "repeat stopped"
            if self.recorder is None:
                return "nothing to stop"
            path, self.recorder = self._finish(), None
            if path is None:
                return "taught path too short (drive at least 5 cm): nothing kept"
            self.path = path
            return f"taught {path.length:.2f} m ({len(path)} points): press Repeat to follow it"
        if action == "follow":
            if self.recorder is not None:
                return "stop teaching first"
            if self.path is None:
                return "nothing taught yet: press Teach and drive a path"
            return self._repeat(client)
        raise ValueError(f"unknown teach action {action!r}")

    def tick(self, client: RobotClient, pose: tuple[float, float, float] | None) -> bool:
        """Every link period: record a pose, or send the follower's command; True while following."""
        self._attach(client, pose)
        if self.recorder is not None:
            self._record()
        follower = self.follower
        if follower is None:
            return False
        command = follower.update(self.state(client))
        if follower.done:
            self._end_repeat(client)
            return False
        submit_vel(client, command, WATCHDOG)
        return True

    # ------------------------------------------------------------------ helpers

    def state(self, client: RobotClient) -> State:
        """The latest estimate, stamped with the link clock's now (the tracker's ``lead`` covers the
        telemetry's age, at most a period)."""
        assert self.estimator is not None
        est = self.estimator.estimate
        now = client.clock.now()
        return State(now, est.x, est.y, est.theta, est.vx, est.vy, est.w, est.slipping)

    def _attach(self, client: RobotClient, pose: tuple[float, float, float] | None) -> None:
        if self._client is client:
            return
        if self._client is not None:
            self._client.remove_listener(self._on_telemetry)
        self._client = client
        self._start = Pose2D(*pose) if pose is not None else Pose2D(0.0, 0.0, 0.0)
        self.estimator = None
        client.on_telemetry(self._on_telemetry)

    def _on_telemetry(self, event: Telemetry) -> None:
        if self.estimator is None:
            tracking = event.tracking is not None and len(self.robot.encoders.tracking) >= 2
            self.estimator = PoseEstimator(
                self.robot,
                translation="tracking" if tracking else "encoders",
                start=self._start,
                name="teach",
                slip=self.slip,
            )
        self.estimator.update(event)

    def _record(self) -> None:
        if self.recorder is None or self.estimator is None:
            return
        e = self.estimator.estimate
        self.recorder.add(e.t, e.x, e.y, e.theta)

    def _finish(self) -> Path | None:
        assert self.recorder is not None
        self._record()
        try:
            path = self.recorder.path()
        except ValueError:  # fewer than two distinct poses
            return None
        return path if path.length >= 0.05 else None

    def _repeat(self, client: RobotClient) -> str:
        assert self.path is not None
        if self.estimator is None:
            return "no telemetry yet: cannot locate the robot"
        path = self.path
        e = self.estimator.estimate
        gap = math.hypot(path.x[0] - e.x, path.y[0] - e.y)
        note = ""
        if gap > APPROACH_GAP:
            path = _with_approach(path, e.x, e.y, e.theta)
            note = f", driving {gap:.2f} m to its start first"
        limits = follower_limits(self.robot, self.speed)
        follower = make_follower("tracker", limits, rate=1.0 / self.period, **gains_for(self.period))
        if self.wheel_loop:
            self._mode = client.mode_bits if client.mode_bits is not None else client.status().mode
            client.mode(closed_loop=True)
        follower.start(path, client.clock.now())
        self.follower = follower
        return f"repeating the taught {self.path.length:.2f} m{note}"

    def _end_repeat(self, client: RobotClient) -> None:
        self.follower = None
        client.stop()
        if self._mode is not None:
            client.mode(self._mode)
            self._mode = None


def _with_approach(path: Path, x: float, y: float, theta: float) -> Path:
    """``path`` with a straight run from (x, y) to its start in front (heading turning to the path's)."""
    import numpy as np

    kwargs: dict[str, Any] = {}
    if path.v is not None:
        kwargs["v"] = np.concatenate(([path.v[0]], path.v))
    return Path(
        np.concatenate(([x], path.x)),
        np.concatenate(([y], path.y)),
        np.concatenate(([theta], path.theta)),
        **kwargs,
    )
