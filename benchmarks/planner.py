"""Path planners side by side: grid A* with any-angle shortcuts against OMPL's RRT*, PRM*, BIT*.

Run: ``python -m benchmarks.planner`` (``--pairs N``, ``--worlds``, ``--planners``, ``--robots``,
``--time-limit``; about a minute).

Each bundled world with walls is rasterised at ``--resolution`` (:func:`rasterise`: a cell is a
wall where a wall or obstacle edge passes within half a cell diagonal of its centre, or inside an
obstacle); ``--pairs`` random start/goal pairs (seeded) at which the robot's disc fits (clearance
>= radius + margin) are planned by each planner on the same inflated grid. Per planner: success,
path length (and its ratio to the grid planner's on the pairs both solved; ``grid-nocost`` is the
grid planner with the walls' cost weighted 0, the shortest way within the inflation), the least clearance
(m beyond the robot's radius), the mean clearance along the path, and the planning time (wall
clock, this process, one core).
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import PlanningError
from omnibot.mapping import CostMap, OccupancyGrid, PlannedPath, inflate, plan_path
from omnibot.mapping.planner import COST_WEIGHT, PLANNERS
from omnibot.mapping.score import world_grid
from omnibot.motion import Pose2D
from omnibot.robot import load_robot
from omnibot.sim import World, load_world

RESOLUTION = 0.025
PAD = 0.1
NO_COST = "grid-nocost"
"""The grid planner without the walls' cost (weight 0): the shortest way within the inflated walls."""


def rasterise(world: World, resolution: float = RESOLUTION, pad: float = PAD) -> OccupancyGrid:
    """The world as the planner benchmark's map (:func:`omnibot.mapping.score.world_grid`)."""
    return world_grid(world, resolution, pad)


def free_poses(cmap: CostMap, count: int, seed: int, region: NDArray[np.bool_] | None = None) -> list[Pose2D]:
    """``count`` random poses (seeded) where the robot's disc fits, inside ``region`` if given."""
    rng = np.random.default_rng(seed)
    grid = cmap.grid
    ok = ~cmap.blocked
    if region is not None:
        ok &= region
    cells = np.argwhere(ok)
    picks = cells[rng.choice(len(cells), size=count, replace=True)]
    xy = grid.cell_to_world(picks)
    theta = rng.uniform(-math.pi, math.pi, size=count)
    return [Pose2D(float(x), float(y), float(t)) for (x, y), t in zip(xy, theta, strict=True)]


def inside_walls(grid: OccupancyGrid, x: float, y: float) -> NDArray[np.bool_]:
    """Cells reachable from (x, y) without crossing a wall cell (the room's inside)."""
    free = grid.data < 65
    rc = grid.world_to_cell([(x, y)])[0]
    seen = np.zeros(grid.shape, dtype=bool)
    queue = deque([(int(rc[0]), int(rc[1]))])
    seen[queue[0]] = True
    rows, cols = grid.shape
    while queue:
        r, c = queue.popleft()
        for nr, nc in ((r + 1, c), (r - 1, c), (r, c + 1), (r, c - 1)):
            if 0 <= nr < rows and 0 <= nc < cols and free[nr, nc] and not seen[nr, nc]:
                seen[nr, nc] = True
                queue.append((nr, nc))
    return seen


@dataclass
class Row:
    world: str
    robot: str
    planner: str
    solved: int = 0
    tried: int = 0
    lengths: list[float] | None = None
    clearances: list[float] | None = None
    means: list[float] | None = None
    seconds: list[float] | None = None


def mean_clearance(cmap: CostMap, path: PlannedPath, step: float = 0.02) -> float:
    """The clearance beyond the robot's radius averaged along the path, m."""
    pts: list[np.ndarray] = []
    for a, b in zip(path.waypoints[:-1], path.waypoints[1:], strict=True):
        n = max(1, math.ceil(float(np.hypot(*(b - a))) / step))
        pts.extend(a + (b - a) * k / n for k in range(n))
    return float(np.mean([cmap.clearance_at(float(p[0]), float(p[1])) for p in pts])) - cmap.robot_radius


def measure(
    worlds: list[str], robots: list[str], planners: list[str], pairs: int, time_limit: float, seed: int
) -> list[Row]:
    rows: list[Row] = []
    for world_name in worlds:
        world = load_world(world_name)
        grid = rasterise(world)
        for robot_name in robots:
            robot = load_robot(robot_name)
            cmap = inflate(grid, robot_radius=robot.footprint.bounding_radius)
            centre = grid.cell_to_world([(grid.shape[0] // 2, grid.shape[1] // 2)])[0]
            start = world.start or Pose2D(float(centre[0]), float(centre[1]), 0.0)
            room = inside_walls(grid, start.x, start.y)
            poses = free_poses(cmap, 2 * pairs, seed, room)
            for name in planners:
                row = Row(world_name, robot_name, name, lengths=[], clearances=[], means=[], seconds=[])
                for k in range(pairs):
                    a, b = poses[2 * k], poses[2 * k + 1]
                    row.tried += 1
                    t0 = time.perf_counter()
                    try:
                        path = plan_path(
                            cmap,
                            a,
                            b,
                            planner="grid" if name == NO_COST else name,  # type: ignore[arg-type]
                            weight=0.0 if name == NO_COST else COST_WEIGHT,
                            time_limit=time_limit,
                            seed=seed + k,
                        )
                    except PlanningError:
                        assert row.lengths is not None
                        row.lengths.append(math.nan)
                        continue
                    assert row.lengths is not None and row.clearances is not None
                    assert row.means is not None and row.seconds is not None
                    row.seconds.append(time.perf_counter() - t0)
                    row.solved += 1
                    row.lengths.append(path.length)
                    row.clearances.append(path.clearance - cmap.robot_radius)
                    row.means.append(mean_clearance(cmap, path))
                rows.append(row)
    return rows


def table(rows: list[Row]) -> str:
    out = [
        "| world | robot | planner | solved | length vs grid (mean, max) | least clearance (min, mean) | "
        "mean clearance | time (median, max) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    base = {(r.world, r.robot): r for r in rows if r.planner == "grid"}
    for r in rows:
        assert r.lengths is not None and r.clearances is not None and r.means is not None
        assert r.seconds is not None
        ref = base.get((r.world, r.robot))
        ratios = (
            [
                a / b
                for a, b in zip(r.lengths, ref.lengths or [], strict=True)
                if math.isfinite(a) and math.isfinite(b) and b > 0
            ]
            if ref is not None
            else []
        )
        ratio = f"{statistics.mean(ratios):.3f}, {max(ratios):.3f}" if ratios else "-"
        clear = (
            f"{100 * min(r.clearances):.1f}, {100 * statistics.mean(r.clearances):.1f} cm"
            if r.clearances
            else "-"
        )
        mean = f"{100 * statistics.mean(r.means):.1f} cm" if r.means else "-"
        secs = (
            f"{1000 * statistics.median(r.seconds):.0f}, {1000 * max(r.seconds):.0f} ms" if r.seconds else "-"
        )
        out.append(
            f"| {r.world} | {r.robot} | {r.planner} | {r.solved}/{r.tried} | {ratio} | {clear} | {mean} | {secs} |"
        )
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", default="room,corridor")
    parser.add_argument("--robots", default="omni4,omni3")
    parser.add_argument("--planners", default=",".join((*PLANNERS[:1], NO_COST, *PLANNERS[1:])))
    parser.add_argument("--pairs", type=int, default=30)
    parser.add_argument("--time-limit", type=float, default=0.5, help="s per OMPL plan")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    # compile the kernels first, so the first plan's time is planning
    warm = rasterise(load_world("room"))
    plan_path(warm, Pose2D(1.0, 1.0, 0.0), Pose2D(4.0, 3.0, 0.0), robot_radius=0.15)
    rows = measure(
        args.worlds.split(","),
        args.robots.split(","),
        args.planners.split(","),
        args.pairs,
        args.time_limit,
        args.seed,
    )
    print(table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
