"""Teach and repeat from the dashboard: record the path the robot is driven along, then follow it.

:class:`PathTeacher` is the dashboard's teach hook (:class:`omnibot.web.teach.TeachRepeat`). It joins
the dashboard's runtime: the runtime's estimator (the ``fused`` one, started at the pose the page
shows, so the page and the path share a frame) gives the state, predicted to each cycle's time;
a sink of its own records and watches the repeat, and:

* **Teach** starts a :class:`~omnibot.control.paths.teach.PathRecorder` (a pose every 2 cm, heading
  kept): drive the robot with the page's stick, keys or a gamepad;
* **Stop** ends the recording (or stops a repeat);
* **Repeat** adds a :class:`~omnibot.runtime.sources.FollowerSource` (the same follower path as
  ``omnibot follow``) with the ``tracker`` at the dashboard's command rate, speed capped at
  ``speed``, with the controller's wheel-speed loop on (MODE bit 1, when every wheel has an
  encoder; the previous mode comes back when the repeat ends). If the robot is not where the path
  starts, it first drives straight there.

The page's driving has a higher priority than the repeat: it takes over, and when it lets go
the repeat resumes from where the robot is (:mod:`omnibot.runtime.sources`). The emergency stop, a
command the controller refuses, a latched sonar stop and a stall (the stall watch,
:mod:`omnibot.runtime.stall`, watches the robot while it repeats: wheels that turn while the body
does not) end the repeat, and the page is told why. Every repeat is judged as ``omnibot follow``
judges a run (:class:`~omnibot.navigation.judge.FollowJudge`): the page's log says ``repeat: RMS
..., final error ...`` and ``repeat completed (within ...)`` or ``repeat NOT COMPLETED: why``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from omnibot.control import MotionLimits, Path, PathRecorder, make_follower
from omnibot.control.followers.tracker import CROSS_GAIN, HEADING_GAIN, heading_gain
from omnibot.estimation import PoseEstimator, SlipParameters
from omnibot.motion import Pose2D
from omnibot.navigation.judge import FollowJudge
from omnibot.navigation.session import follower_limits, summary, verdict
from omnibot.robot import RobotDescription
from omnibot.runtime import Cycle, FollowerSource, Level, Runtime, StallWatch
from omnibot.transport import find_simulator

APPROACH_GAP = 0.02
"""m: farther than this from the path's start, a repeat first drives straight to it."""
WATCHDOG = 0.25
"""s: the VEL watchdog while following (longer than the dashboard's command period)."""


def gains_for(period: float, limits: MotionLimits | None = None) -> dict[str, float]:
    """Tracker gains for a control period (the defaults are for 100 Hz): the loop gain per period
    stays below 0.5. The runtime predicts the state to the cycle's time (telemetry age covered), so the
    lead is the 100 Hz one (0.04 s of actuation) plus half a period (a command holds for a period).
    The heading gain is the robot's (:func:`~omnibot.control.followers.tracker.heading_gain`, given
    its ``limits``), scaled the same way."""
    scale = min(1.0, 0.01 / period)
    heading = HEADING_GAIN if limits is None else heading_gain(limits, 0.04)
    return {
        "cross": CROSS_GAIN * scale,
        "cross_i": 100.0 * scale * scale,
        "along": 10.0 * scale,
        "along_i": 20.0 * scale * scale,
        "heading": heading * scale,
        "heading_i": 10.0 * scale * scale,
        "lead": 0.04 + 0.5 * period,
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
        priority: int = 10,
    ) -> None:
        if not (period > 0 and speed > 0):
            raise ValueError(f"period and speed must be positive, got {period} and {speed}")
        self.robot = robot
        self.period = period
        self.speed = speed
        self.slip = slip
        self.priority = priority
        self.runtime: Runtime | None = None
        self.recorder: PathRecorder | None = None
        self.path: Path | None = None
        """The last taught path (estimator frame = the page's frame)."""
        self.source: FollowerSource | None = None
        """The repeat under way (None when not repeating)."""
        self.judge: FollowJudge | None = None
        """The judge of the last repeat (its report once it has given its verdict)."""
        self.watch: StallWatch | None = None
        """The stall watch it added for its repeats (None while none runs, or another watches)."""
        self._mode: int | None = None  # the MODE to restore after a repeat
        cpr = {e.wheel for e in robot.encoders.motors}
        self.wheel_loop = all(w.name in cpr for w in robot.wheels)

    @property
    def following(self) -> bool:
        """True while a recorded path is being followed."""
        return self.source is not None

    @property
    def estimator(self) -> PoseEstimator | None:
        """The runtime's pose estimator, None when detached or it has another kind."""
        est = None if self.runtime is None else self.runtime.estimator
        return est if isinstance(est, PoseEstimator) else None

    # ------------------------------------------------------------------ the hook

    def attach(self, runtime: Runtime, pose: tuple[float, float, float] | None) -> None:
        """Join ``runtime``: its estimator (made here unless it has one) and a sink."""
        self.runtime = runtime
        if runtime.estimator is None:
            tracking = len(self.robot.encoders.tracking) >= 2
            runtime.estimator = PoseEstimator(
                self.robot,
                translation="tracking" if tracking else "encoders",
                start=Pose2D(*pose) if pose is not None else Pose2D(0.0, 0.0, 0.0),
                name="teach",
                slip=self.slip,
            )
        runtime.add_sink(self._on_cycle)

    def command(self, action: str, pose: tuple[float, float, float] | None) -> str:
        """Teach (``record``), Stop (``stop``) or Repeat (``follow``); the line the page shows."""
        if action == "record":
            if self.source is not None:
                self._end_repeat()
            self.recorder = PathRecorder("distance", 0.02)
            self._record()
            return "teaching: drive the path, then press Stop"
        if action == "stop":
            if self.source is not None:
                self._end_repeat()
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
            if self.source is not None:
                return "already repeating"
            return self._repeat()
        raise ValueError(f"unknown teach action {action!r}")

    # ------------------------------------------------------------------ helpers

    def _on_cycle(self, cycle: Cycle) -> None:
        if self.recorder is not None:
            self._record()
        source = self.source
        if source is not None and source.finished:
            failure = source.failure
            self._end_repeat()
            assert self.runtime is not None
            if failure:
                self.runtime.notify("warn", f"repeat ended: {failure}", "repeat")

    def _verdict(self, report: dict[str, Any]) -> None:
        """The repeat's outcome and accuracy to every front end; the stall watch stops watching."""
        assert self.runtime is not None
        level: Level = "info" if report["completed"] else "warn"
        self.runtime.notify(level, f"repeat: {summary(report)}", "repeat")
        self.runtime.notify(level, f"repeat {verdict(report)}", "repeat")
        if self.watch is not None:
            self.watch.close()
            self.watch = None

    def _record(self) -> None:
        est = self.estimator
        if self.recorder is None or est is None or self.runtime is None or not self.runtime.samples:
            return
        e = est.estimate
        self.recorder.add(e.t, e.x, e.y, e.theta)

    def _finish(self) -> Path | None:
        assert self.recorder is not None
        self._record()
        try:
            path = self.recorder.path()
        except ValueError:  # fewer than two distinct poses
            return None
        return path if path.length >= 0.05 else None

    def _repeat(self) -> str:
        assert self.path is not None and self.runtime is not None
        runtime = self.runtime
        state = runtime.estimate_now()
        if state is None or not runtime.samples:
            return "no telemetry yet: cannot locate the robot"
        path = self.path
        gap = math.hypot(path.x[0] - state.x, path.y[0] - state.y)
        note = ""
        if gap > APPROACH_GAP:
            path = _with_approach(path, state.x, state.y, state.theta)
            note = f", driving {gap:.2f} m to its start first"
        limits = follower_limits(self.robot, self.speed)
        follower = make_follower("tracker", limits, rate=1.0 / self.period, **gains_for(self.period, limits))
        client = runtime.client
        if self.wheel_loop:
            self._mode = client.mode_bits if client.mode_bits is not None else client.status().mode
            client.mode(closed_loop=True)
        self.source = FollowerSource(follower, path, name="repeat", priority=self.priority, watchdog=WATCHDOG)
        self.source.start(state.t)
        if self.judge is not None:
            self.judge.verdict()  # the last repeat's, if it had not given it yet
        self.judge = FollowJudge(runtime, self.robot, self.source, speed=self.speed, on_verdict=self._verdict)
        if self.watch is None and StallWatch.of(runtime) is None:  # ROS 2's bridge may watch already
            self.watch = StallWatch(runtime, self.robot, truth=find_simulator(runtime.client.link))
        runtime.add_source(self.source)
        return f"repeating the taught {self.path.length:.2f} m{note}"

    def _end_repeat(self) -> None:
        assert self.runtime is not None
        if self.source is not None:
            if not self.source.finished:
                self.source.end("stopped from the page")  # its judge judges what was repeated
            self.runtime.remove_source(self.source.name)
            self.source = None
        client = self.runtime.client
        if not self.runtime.latched:  # STOP would release a latched sonar stop behind the user's back
            client.stop()
        if self._mode is not None:
            client.mode(self._mode)
            self._mode = None


def _with_approach(path: Path, x: float, y: float, theta: float) -> Path:
    """``path`` with a straight run from (x, y) to its start in front (heading turning to the path's)."""
    kwargs: dict[str, Any] = {}
    if path.v is not None:
        kwargs["v"] = np.concatenate(([path.v[0]], path.v))
    return Path(
        np.concatenate(([x], path.x)),
        np.concatenate(([y], path.y)),
        np.concatenate(([theta], path.theta)),
        **kwargs,
    )
