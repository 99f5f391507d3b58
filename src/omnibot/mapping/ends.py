"""A path's ends: whether the robot may start or stop at a pose on a cost map, and why not.

Errors (:mod:`omnibot.errors`), each one line in the map frame's metres:
:class:`~omnibot.errors.OffMapError`, :class:`~omnibot.errors.BlockedError` (the goal, or the
start, in a wall, in unknown space or too near a wall), :class:`~omnibot.errors.NoPathError` (a
start hemmed in). A start inside the inflated margin (but clear of the walls themselves) is
allowed: the path first climbs the clearance out of it (:func:`escape`), or, where the clearance
does not climb (a slot narrower than the inflation, open at one end, whose middle is a ridge of
equal clearance), takes the fewest cells the robot fits in (clearance >= its radius) to the
nearest cell out of the margin.
"""

from __future__ import annotations

from collections import deque

from omnibot.errors import BlockedError, NoPathError, OffMapError
from omnibot.mapping.costmap import OCCUPIED, CostMap
from omnibot.motion import Pose2D


def check_goal(cmap: CostMap, goal: Pose2D) -> None:
    """OffMapError or BlockedError when the robot cannot stand at ``goal`` on ``cmap`` (what
    :func:`~omnibot.mapping.planner.plan_path` checks first), so a command can refuse a bad goal
    before it moves."""
    check_end(cmap, goal, "goal")


def check_start(cmap: CostMap, start: Pose2D) -> None:
    """OffMapError, BlockedError or NoPathError when no path can leave ``start`` on ``cmap`` whatever
    the goal (what :func:`~omnibot.mapping.planner.plan_path` checks of the start: on the map, not
    overlapping a wall, not hemmed in where the clearance cannot climb)."""
    escape(cmap, check_end(cmap, start, "start"))


def xy(p: Pose2D) -> str:
    """A pose's position as the errors say it: ``(x, y)`` in m, to the centimetre."""
    return f"({p.x:.2f}, {p.y:.2f})"


def check_end(cmap: CostMap, pose: Pose2D, name: str) -> tuple[int, int]:
    """The cell of a start or goal, or the error that says why the robot cannot be there."""
    grid = cmap.grid
    cell = cmap.cell_of(pose.x, pose.y)
    if cell is None:
        o = grid.origin
        raise OffMapError(
            f"{name} {xy(pose)} is off the map (it spans {grid.width:.2f} m x {grid.height:.2f} m "
            f"from ({o.x:.2f}, {o.y:.2f}))"
        )
    value = int(grid.data[cell])
    if value < 0 and not cmap.allow_unknown:
        raise BlockedError(f"{name} {xy(pose)} is in unmapped space (unknown on the map)")
    clearance = float(cmap.clearance[cell])
    if value >= OCCUPIED or clearance <= 0.0:
        raise BlockedError(f"{name} {xy(pose)} is inside a wall or obstacle")
    need = cmap.inflated
    if name == "goal" and clearance < need:
        raise BlockedError(
            f"goal {xy(pose)} is too close to a wall: {100 * clearance:.0f} cm from it, the robot needs "
            f"{100 * need:.0f} cm (radius {100 * cmap.robot_radius:.0f} + margin {100 * cmap.margin:.0f})"
        )
    if name == "start" and clearance < cmap.robot_radius:
        raise BlockedError(
            f"start {xy(pose)} overlaps a wall on the map: {100 * clearance:.0f} cm from it, the "
            f"robot's radius is {100 * cmap.robot_radius:.0f} cm"
        )
    return cell


Cell = tuple[int, int]


def escape(cmap: CostMap, cell: Cell) -> list[Cell]:
    """Cells from ``cell`` up the clearance until one is not blocked (just ``[cell]`` if it is not);
    where the clearance stops climbing, on through the cells the robot fits in (:func:`_fitting_way`);
    NoPathError when none leads out of the margin."""
    out = [cell]
    rows, cols = cmap.grid.shape

    def clearance(rc: Cell) -> float:
        return float(cmap.clearance[rc]) if 0 <= rc[0] < rows and 0 <= rc[1] < cols else -1.0

    while cmap.blocked[out[-1]]:
        r, c = out[-1]
        best = max(((r + dr, c + dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc), key=clearance)
        if clearance(best) <= clearance((r, c)):
            way = _fitting_way(cmap, out[-1])
            if way is None:
                raise NoPathError(
                    f"no path: the start is hemmed in {100 * cmap.clearance[cell]:.0f} cm from a wall"
                )
            return out + way
        out.append(best)
    return out


def _fitting_way(cmap: CostMap, cell: Cell) -> list[Cell] | None:
    """The fewest 8-connected steps from ``cell`` through cells the robot fits in (clearance at
    least its radius, known unless unknown is allowed) to the nearest one out of the margin (not
    blocked); None when there is none."""
    rows, cols = cmap.grid.shape
    fits = cmap.clearance >= cmap.robot_radius
    came: dict[Cell, Cell] = {cell: cell}
    todo = deque([cell])
    while todo:
        r, c = todo.popleft()
        if not cmap.blocked[r, c]:
            way = [(r, c)]
            while way[-1] != cell:
                way.append(came[way[-1]])
            return way[-2::-1]
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                n = (r + dr, c + dc)
                if 0 <= n[0] < rows and 0 <= n[1] < cols and n not in came and fits[n]:
                    came[n] = (r, c)
                    todo.append(n)
    return None


def why_no_path(cmap: CostMap) -> str:
    """Why no path joins two ends that are both clear: the way between is too narrow, or closed."""
    return (
        f"the free space between them is narrower than the robot needs "
        f"({100 * 2 * cmap.inflated:.0f} cm: radius {100 * cmap.robot_radius:.0f} cm + margin "
        f"{100 * cmap.margin:.0f} cm each side) or closed"
    )
