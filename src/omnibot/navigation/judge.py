"""The judge of a follow on the runtime: ``run --follow``, the page's Repeat and ROS 2's ``path`` get
the verdict ``omnibot follow`` gives its own runs (the outcome against the tolerances, the accuracy
from the simulator's truth where there is one)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from omnibot.motion import Pose2D
from omnibot.navigation.metrics import follow_report
from omnibot.navigation.outcome import Tolerances
from omnibot.navigation.runner import SETTLE
from omnibot.navigation.trace import FollowRun, FollowTrace, FrameMap
from omnibot.robot import RobotDescription
from omnibot.runtime import Cycle, FollowerSource, Runtime
from omnibot.transport import find_simulator


class FollowJudge:
    """A sink: judges the run of ``source`` on ``runtime`` as ``omnibot follow`` judges its own.

    It records the run (:class:`~omnibot.navigation.trace.FollowTrace`: the estimate, the command
    and, where a simulator is behind the link, the truth mapped into the estimate's frame as it is
    when the judge is made) at every cycle the follower drives. ``SETTLE`` s
    (:data:`~omnibot.navigation.runner.SETTLE`) after the follower ended (reached the path's end, or
    ended early: a stall, an emergency stop, a refused command) the run is judged
    (:func:`~omnibot.navigation.metrics.follow_report`: the final distance to the path's end and the
    largest cross-track error against ``tolerances``, from the truth where there is one),
    :attr:`report` is set and ``on_verdict(report)`` called; the judge then leaves the runtime.
    :meth:`verdict` judges at once (a runtime that ends before the follower does).
    """

    def __init__(
        self,
        runtime: Runtime,
        robot: RobotDescription,
        source: FollowerSource,
        *,
        speed: float | None = None,
        tolerances: Tolerances | None = None,
        on_verdict: Callable[[dict[str, Any]], object] | None = None,
    ) -> None:
        self.runtime = runtime
        self.robot = robot
        self.source = source
        self.speed = speed
        self.tolerances = tolerances or Tolerances()
        self.on_verdict = on_verdict
        self.report: dict[str, Any] | None = None
        """The judged report (None until the verdict)."""
        self.sim = find_simulator(runtime.client.link)
        here = runtime.estimate_now()
        self.frame: FrameMap | None = None
        if self.sim is not None and here is not None:
            p = self.sim.pose
            self.frame = FrameMap(Pose2D(p.x, p.y, p.theta), here.pose)
        name = getattr(runtime.estimator, "name", "")
        self.run = FollowRun(source.path, source.follower.name, str(name))
        self.run.start_time = runtime.client.clock.now()  # until the follower first drives
        self.trace = FollowTrace(self.run, source, self.truth)
        self._ended: float | None = None
        runtime.add_sink(self)

    def truth(self) -> tuple[float, float, float] | None:
        """The body's true pose now in the estimate's frame (None without a simulator)."""
        if self.sim is None or self.frame is None:
            return None
        p = self.sim.pose
        return self.frame(p.x, p.y, p.theta)

    def __call__(self, cycle: Cycle) -> None:
        """Record the cycle if the follower drove it; judge ``SETTLE`` s after it ended."""
        if self.report is not None:
            return
        if self.trace(cycle) and len(self.run.t) == 1:
            self.run.start_time = cycle.t
        if not self.source.finished:
            return
        if self._ended is None:
            self._ended = self.run.end_time = cycle.t
        if cycle.t - self._ended >= SETTLE:
            self.verdict()

    def verdict(self) -> dict[str, Any]:
        """Judge the run now (once; the report)."""
        if self.report is not None:
            return self.report
        run, source = self.run, self.source
        if self._ended is None:
            run.end_time = self.runtime.client.clock.now()
        run.completed = source.completed
        run.failure = source.failure or (
            "" if source.finished else "not finished" if source.started else "never started"
        )
        here = self.runtime.estimate_now()
        run.final_estimate = here.pose if here is not None else None
        truth = self.truth()
        run.final_truth = Pose2D(*truth) if truth is not None else None
        self.report = follow_report(run, self.robot, self.tolerances, speed=self.speed)
        self.runtime.remove_sink(self)
        if self.on_verdict is not None:
            self.on_verdict(self.report)
        return self.report
