"""What one follow records: :class:`FollowRun` (times on the link clock, the estimate, the command and
the truth in the path's frame, how it ended), the sink that fills it in while the follower drives
(:class:`FollowTrace`), and the simulator's world mapped into the path's frame (:class:`FrameMap`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from omnibot.control import Command, Path, State
from omnibot.motion import Pose2D
from omnibot.runtime import Cycle, FollowerSource


@dataclass
class FollowRun:
    """What happened in one follow run (times on the link clock, poses in the path's frame)."""

    path: Path
    follower: str
    estimator: str
    t: list[float] = field(default_factory=list)
    estimate: list[tuple[float, float, float]] = field(default_factory=list)
    command: list[tuple[float, float, float]] = field(default_factory=list)
    truth: list[tuple[float, float, float]] = field(default_factory=list)
    start_time: float = 0.0
    end_time: float = 0.0
    completed: bool = False
    final_estimate: Pose2D | None = None
    final_truth: Pose2D | None = None
    distance: float = 0.0
    warnings: list[str] = field(default_factory=list)
    """What the runtime warned about up to the run's end (e.g. a silent gyro, a latched stop)."""
    failure: str = ""
    """Why the run ended early ("" when it did not): a stall, an emergency stop, a refused command."""

    @property
    def duration(self) -> float:
        """Time from the run's start to its end, s."""
        return self.end_time - self.start_time

    @property
    def has_truth(self) -> bool:
        """Whether ground truth was recorded (simulator runs only)."""
        return bool(self.truth)

    def arrays(self) -> dict[str, np.ndarray]:
        """The trace as arrays: t (n,), estimate (n, 3), command (n, 3), truth (n, 3) or empty."""
        return {
            "t": np.array(self.t),
            "estimate": np.array(self.estimate).reshape(-1, 3),
            "command": np.array(self.command).reshape(-1, 3),
            "truth": np.array(self.truth).reshape(-1, 3),
        }


class FollowTrace:
    """A sink: the run of ``source`` into ``run``: the estimate the follower steered by, its command
    and the truth (``truth()``: in the path's frame, None without one) at every cycle it drove."""

    def __init__(
        self,
        run: FollowRun,
        source: FollowerSource,
        truth: Callable[[], tuple[float, float, float] | None],
    ) -> None:
        self.run = run
        self.source = source
        self.truth = truth

    def __call__(self, cycle: Cycle) -> bool:
        """Record the cycle if the follower drove it; whether it did."""
        source = self.source
        if (
            cycle.sent is None
            or source.finished
            or cycle.decision.source != source.name
            or source.state is None
            or source.twist is None
        ):
            return False
        self.record(source.state, source.twist)
        return True

    def record(self, state: State, command: Command) -> None:
        """Record the state, the command and the truth now."""
        run = self.run
        run.t.append(state.t)
        run.estimate.append((state.x, state.y, state.theta))
        run.command.append((command.vx, command.vy, command.w))
        truth = self.truth()
        if truth is not None:
            run.truth.append(truth)


class FrameMap:
    """Maps simulator world poses into the path's frame: path_start o sim_start^-1."""

    def __init__(self, sim_start: Pose2D, path_start: Pose2D) -> None:
        self.dth = path_start.theta - sim_start.theta
        self.c, self.s = math.cos(self.dth), math.sin(self.dth)
        self.sim_start = sim_start
        self.path_start = path_start

    def __call__(self, x: float, y: float, theta: float) -> tuple[float, float, float]:
        """A simulator world pose ``(x, y, theta)`` in the path's frame (m, m, rad)."""
        dx, dy = x - self.sim_start.x, y - self.sim_start.y
        return (
            self.path_start.x + self.c * dx - self.s * dy,
            self.path_start.y + self.s * dx + self.c * dy,
            theta + self.dth,
        )
