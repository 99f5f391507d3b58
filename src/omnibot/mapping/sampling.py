"""OMPL's sampling planners in R2 on a cost map: RRT*, PRM* and BIT* (:func:`ompl_plan`).

OMPL's Python bindings, imported on first use, with the blocked cells as the validity checker, for
``time_limit`` s (longer only while it has no path yet, up to :data:`FIRST_PATH_WAIT` s: A* has
told first that there is one), then OMPL's path simplification; seeded (``seed``) for repeatable
runs. A straight run of OMPL's path that clips a blocked cell (OMPL checks its motions at a
resolution, the cells exactly) is replaced by the grid planner's way between its ends.
"""

from __future__ import annotations

import importlib
import itertools
import time

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import NoPathError
from omnibot.mapping.astar import astar, shortcut
from omnibot.mapping.costmap import CostMap
from omnibot.mapping.ends import xy
from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]

FIRST_PATH_WAIT = 10.0
"""s an OMPL planner may run in all (at least its ``time_limit``) while it has no path yet: there is
one, the grid planner found it first. The time limit is for improving a path; on a loaded machine
the sampling slows, and a plan that exists is not refused for it."""
FIRST_PATH_SLICE = 0.02
"""s of each further solve while an OMPL planner has no path yet (OMPL's planners report a path at the
end of a solve; each further solve carries on from the tree or roadmap it has)."""


def ompl_plan(
    cmap: CostMap,
    first: tuple[float, float],
    start: Pose2D,
    goal: Pose2D,
    planner: str,
    time_limit: float,
    seed: int,
) -> FloatArray:
    """Waypoints from ``first`` to the goal by one of OMPL's planners in R2 (see the module);
    NoPathError without a solution."""
    # optional bindings without types, loaded on first use
    ob = importlib.import_module("ompl.base")
    og = importlib.import_module("ompl.geometric")
    ou = importlib.import_module("ompl.util")

    ou.setLogLevel(ou.LOG_NONE)
    ou.RNG.setSeed(seed)
    grid = cmap.grid
    space = ob.RealVectorStateSpace(2)
    bounds = ob.RealVectorBounds(2)
    corners = grid.cell_to_world([(0, 0), (grid.shape[0] - 1, grid.shape[1] - 1)])
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    bounds.setLow(0, float(lo[0]))
    bounds.setLow(1, float(lo[1]))
    bounds.setHigh(0, float(hi[0]))
    bounds.setHigh(1, float(hi[1]))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    blocked = cmap.blocked

    def valid(state: object) -> bool:
        cell = cmap.cell_of(state[0], state[1])  # type: ignore[index]
        return cell is not None and not bool(blocked[cell])

    setup.setStateValidityChecker(valid)
    a, b = space.allocState(), space.allocState()
    a[0], a[1] = float(first[0]), float(first[1])
    b[0], b[1] = goal.x, goal.y
    setup.setStartAndGoalStates(a, b)
    info = setup.getSpaceInformation()
    info.setStateValidityCheckingResolution(0.25 * grid.resolution / space.getMaximumExtent())
    made = {"rrtstar": og.RRTstar, "prmstar": og.PRMstar, "bitstar": og.BITstar}[planner](info)
    setup.setPlanner(made)
    end = time.monotonic() + max(time_limit, FIRST_PATH_WAIT)
    setup.solve(time_limit)
    while not setup.haveExactSolutionPath() and (left := end - time.monotonic()) > 0:
        setup.solve(min(left, max(time_limit, FIRST_PATH_SLICE)))  # the planner goes on where it was
    if not setup.haveExactSolutionPath():
        raise NoPathError(
            f"no path from {xy(start)} to {xy(goal)} found by OMPL's {planner} in "
            f"{max(time_limit, FIRST_PATH_WAIT):.2f} s"
        )
    setup.simplifySolution(min(1.0, time_limit))
    path = setup.getSolutionPath()
    points = [(path.getState(i)[0], path.getState(i)[1]) for i in range(path.getStateCount())]
    out = np.array([first, *points[1:-1], (goal.x, goal.y)], dtype=np.float64)
    keep = np.concatenate(([True], np.hypot(*np.diff(out, axis=0).T) > 1e-9))
    return _repaired(cmap, np.asarray(out[keep], dtype=np.float64))


def _repaired(cmap: CostMap, points: FloatArray) -> FloatArray:
    """``points`` with every straight run that clips a blocked cell (OMPL checks its motions at a
    resolution, the cells exactly) replaced by the grid planner's way between its ends."""
    out = [points[0]]
    for a, b in itertools.pairwise(points):
        pa, pb = (float(a[0]), float(a[1])), (float(b[0]), float(b[1]))
        ca, cb = cmap.cell_of(*pa), cmap.cell_of(*pb)
        if cmap.segment_free(pa, pb) or ca is None or cb is None:
            out.append(b)
            continue
        cells = astar(~cmap.blocked, cmap.cost, ca, cb, 0.0)
        if cells is None:
            raise NoPathError(f"no path: OMPL's run from {pa} to {pb} clips a wall and none goes round")
        out.extend(shortcut(cmap, cells, pa, pb, 0.0)[1:])
    return np.asarray(out, dtype=np.float64)
