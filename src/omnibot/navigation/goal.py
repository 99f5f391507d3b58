"""What a goto is asked and what it gives: :class:`GotoOptions` (the tolerances of arrival, the
planner's, speed, heading, the obstacle watch), :class:`GotoResult` (arrived, or why not), whether a
pose is :func:`within` the goal's tolerances, and what a goto is handed: where the robot is on the
map (a :data:`PoseProvider`) and what its scanner sees (a :data:`ScanSource`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from omnibot.control import wrap
from omnibot.errors import ConfigError
from omnibot.mapping import MARGIN, OccupancyGrid, PlannedPath, Planner
from omnibot.motion import Pose2D
from omnibot.navigation.runner import SETTLE

FloatArray = NDArray[np.float64]
PoseProvider = Callable[[], Pose2D | None]
"""The robot's pose in the map frame now (None: not known yet)."""
ScanSource = Callable[[], FloatArray | None]
"""The latest scan's points (n, 2) in the map frame (None: no scan yet)."""
Outcome = Literal[
    "arrived", "no path", "blocked", "timed out", "stalled", "stopped", "missed", "cancelled", "off path"
]
Heading = Literal["auto", "travel", "goal"]


@dataclass(frozen=True)
class GotoOptions:
    """How to go: tolerances of arrival, the planner's, speed, heading, and the obstacle watch."""

    tolerance: float = 0.05
    """m from the goal's position to count as arrived."""
    heading_tolerance: float = math.radians(5.0)
    """rad from the goal's heading to count as arrived."""
    margin: float = MARGIN
    """m kept free beyond the robot's radius (the footprint's bounding circle)."""
    allow_unknown: bool = False
    """Plan through unknown cells (else they are walls)."""
    planner: Planner = "grid"
    speed: float | None = None
    """Speed cap, m/s (None: the robot's own limits)."""
    heading: Heading = "auto"
    """``travel``: the body faces where it goes (turning in place at corners and at the end),
    so a front sonar looks ahead; ``goal``: it turns towards the goal's heading along the way;
    ``auto``: travel when the robot has a sonar and no scan is given, else goal."""
    lookahead: float = 1.0
    """m of the path ahead watched for obstacles the map does not have, at least: farther where the
    leg's planned speed needs more room to stop (:func:`~omnibot.navigation.obstacles.stopping_reach`)."""
    max_replans: int = 5
    """Re-plans after obstacles before giving up (blocked), and after legs the robot was carried off
    (``off path``: farther than the follower chases, :data:`~omnibot.control.followers.base.OFF_PATH`)."""
    corrections: int = 2
    """Short legs from where the robot stopped when it ended farther than ``aim`` of the tolerances."""
    aim: float = 0.5
    """The fraction of the tolerances a leg's end must meet not to take a correction leg (arrival
    itself is judged at the whole tolerances, once the corrections are spent)."""
    timeout: float | None = None
    """s for the whole goto (None: three times each leg's minimum time plus 10 s per leg)."""
    settle: float = SETTLE
    """s to wait after each leg's stop before the pose is read."""

    def __post_init__(self) -> None:
        for name in ("tolerance", "heading_tolerance", "lookahead"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ConfigError(f"goto's {name} must be a positive number, not {value}")
        if not 0 < self.aim <= 1:
            raise ConfigError(f"goto's aim must be a fraction in (0, 1], not {self.aim}")
        if self.max_replans < 0 or self.corrections < 0:
            raise ConfigError("goto's max_replans and corrections must be >= 0")


@dataclass
class GotoResult:
    """What a goto did: ``arrived`` or why not (``outcome``, ``reason``), where it ended."""

    goal: Pose2D
    outcome: Outcome
    reason: str = ""
    """One line saying why it did not arrive ("" when it did)."""
    final: Pose2D | None = None
    """The provider's pose at the end (map frame)."""
    plans: list[PlannedPath] = field(default_factory=list)
    replans: int = 0
    """Plans made after an obstacle the map did not have."""
    strays: int = 0
    """Plans made from where the robot was after a leg it was carried off (a push, a localiser's
    correction: farther from the path than the follower chases)."""
    obstacles: list[tuple[float, float]] = field(default_factory=list)
    """Map-frame points marked as obstacles on the way."""
    grid: OccupancyGrid | None = None
    """The map with those obstacles marked."""
    duration: float = 0.0
    """s on the link's clock from the start to the end."""

    @property
    def arrived(self) -> bool:
        """Within the tolerances at the end."""
        return self.outcome == "arrived"

    @property
    def error(self) -> float:
        """m from the goal at the end (nan without a final pose)."""
        f = self.final
        return math.nan if f is None else math.hypot(f.x - self.goal.x, f.y - self.goal.y)

    @property
    def heading_error(self) -> float:
        """rad from the goal's heading at the end (nan without a final pose)."""
        f = self.final
        return math.nan if f is None else abs(wrap(f.theta - self.goal.theta))

    def summary(self) -> str:
        """One line for a terminal."""
        where = (
            ""
            if self.final is None
            else f" ({100 * self.error:.1f} cm, {math.degrees(self.heading_error):.1f} degrees from the goal)"
        )
        if self.arrived:
            return f"arrived at ({self.goal.x:.2f}, {self.goal.y:.2f}){where}"
        return f"did not arrive: {self.reason}{where}"


def within(pose: Pose2D, goal: Pose2D, opts: GotoOptions, share: float = 1.0) -> bool:
    """``pose`` is within ``share`` of the tolerances of ``goal``."""
    return (
        math.hypot(pose.x - goal.x, pose.y - goal.y) <= share * opts.tolerance
        and abs(wrap(pose.theta - goal.theta)) <= share * opts.heading_tolerance
    )
