"""Going to a place in the room: 20 seeded goals per robot, arrival error from the simulator's truth.

Run: ``python -m benchmarks.goto`` (``--goals N``, ``--robots``, ``--poses odometry,truth[,localiser]``,
``--world``, ``--obstacle``, ``--scanner``; a few minutes on one core).

For each robot and goal k (seed k): the room world rasterised at 2.5 cm
(:func:`benchmarks.planner.rasterise`) is the map; the robot stands at the world's start in a
fresh lockstep simulator (seed k, firmware and physics, wood floor with the room's carpet patch),
its estimator started there; the goal is a seeded random pose where the robot fits (clearance >=
radius + margin) inside the room. :func:`omnibot.navigation.goto.goto` plans, follows with the
tracker and judges arrival (5 cm, 5 degrees) by its pose provider:

* ``odometry``: the runtime's fused estimate (what ``omnibot goto`` has until a localiser gives
  the map pose);
* ``truth``: the simulator's true pose as the provider (standing in for a perfect localiser: the
  follower still steers by the estimate, the plan is moved into its frame and correction legs
  take out the drift);
* ``localiser``: ``omnibot goto``'s own, the :class:`~omnibot.mapping.Localiser` in the map fed
  by the robot's scanner (:class:`~omnibot.mapping.LocalisingSink`, started at the true start
  with 5 cm of spread), the obstacle watch on its points; its lead over the truth along the
  direction of travel while the robot moves at 0.5 m/s or more (issue 25's) and its distance
  from the truth every cycle after the first second, at rest and moving, are printed after the
  table.

Per robot and provider: goals arrived (by goto's verdict) and arrived by the truth (within 5 cm
and 5 degrees of the true pose), the truth's final position and heading errors (mean, max),
contacts (the simulator's collision events), re-plans, and the time (simulated s per goal).
``--obstacle`` adds a box to the simulated room that the map does not have, in the way of
every goal's straight line... (see OBSTACLE), so the sonar watch's stop and re-plan are measured;
``--scanner`` gives the watch the robot's scanner too (as ``omnibot goto`` does; without it a robot
with no sonar, omni3 and mecanum4, is blind to the box).
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml
from numpy.typing import NDArray

from benchmarks.planner import free_poses, inside_walls, rasterise
from omnibot.client import RobotClient
from omnibot.lidar import open_scanner
from omnibot.mapping import Localiser, LocalisingSink, OccupancyGrid, inflate
from omnibot.motion import Pose2D
from omnibot.navigation import GotoOptions, GotoResult, PoseProvider, ScanPoints, simulated_client
from omnibot.navigation.goto import goto
from omnibot.robot import RobotDescription, load_robot
from omnibot.runtime import Cycle, Runtime
from omnibot.sim import load_world
from omnibot.transport import find_simulator

FloatArray = NDArray[np.float64]

OBSTACLE: dict[str, object] = {"shape": "box", "center": [2.3, 2.0], "size": [0.3, 0.3]}
"""A box in the middle of the room that the map does not have (``--obstacle``)."""


@dataclass(frozen=True)
class Outcome:
    robot: str
    provider: str
    seed: int
    goal: Pose2D
    result: GotoResult
    truth: Pose2D
    contacts: int
    lead: float | None = None
    """``localiser``: its mean lead (m) over the truth along the travel at >= 0.5 m/s (None: not moving)."""
    off: tuple[FloatArray, FloatArray] | None = None
    """``localiser``: its distance (m) from the truth every cycle, at rest and moving (:meth:`LeadTrace.off`)."""

    @property
    def error(self) -> float:
        return math.hypot(self.truth.x - self.goal.x, self.truth.y - self.goal.y)

    @property
    def heading_error(self) -> float:
        return abs((self.truth.theta - self.goal.theta + math.pi) % (2 * math.pi) - math.pi)

    def within(self, tolerance: float = 0.05, heading: float = math.radians(5)) -> bool:
        return self.error <= tolerance and self.heading_error <= heading


def goals(robot_name: str, count: int, world: str = "room", seed: int = 100) -> list[Pose2D]:
    """``count`` seeded goals where the robot fits inside the world's walls."""
    grid = rasterise(load_world(world))
    cmap = inflate(grid, robot_radius=load_robot(robot_name).footprint.bounding_radius)
    start = load_world(world).start or Pose2D(0.0, 0.0, 0.0)
    return free_poses(cmap, count, seed, inside_walls(grid, start.x, start.y))


def world_with_obstacle(world: str, obstacle: Mapping[str, object], folder: Path) -> str:
    """A copy of a bundled world's file with one more obstacle; its path."""
    spec = load_world(world).spec.model_dump(exclude_none=True)
    spec["obstacles"] = [*spec.get("obstacles", ()), dict(obstacle)]
    spec["name"] = f"{world}-plus"
    path = folder / f"{world}-plus.yaml"
    path.write_text(yaml.safe_dump(spec))
    return str(path)


def run_goal(
    robot_name: str,
    goal: Pose2D,
    seed: int,
    provider: str = "odometry",
    world: str = "room",
    sim_world: str | None = None,
    options: GotoOptions | None = None,
    scanner: bool = False,
) -> Outcome:
    """One goto in a fresh simulator; its outcome against the truth. ``scanner``: the robot's
    scanner watches for what the map lacks (:class:`~omnibot.navigation.scanwatch.ScanPoints`, placed
    by the provider), as in ``omnibot goto``; else only its sonars do (none on omni3 and mecanum4)."""
    robot = load_robot(robot_name)
    w = load_world(world)
    grid = rasterise(w)
    start = w.start or Pose2D(0.0, 0.0, 0.0)
    with simulated_client(robot, world=sim_world or world, start=start, seed=seed) as client:
        sim = find_simulator(client.link)
        assert sim is not None

        def truth() -> Pose2D:
            p = sim.pose
            return Pose2D(p.x, p.y, p.theta)

        if provider == "localiser":
            result, trace = localised(client, robot, grid, (start, goal), options, seed, truth)
            return Outcome(
                robot_name,
                provider,
                seed,
                goal,
                result,
                truth(),
                len(sim.collisions),
                trace.lead(),
                trace.off(),
            )
        pose = truth if provider == "truth" else None
        if not scanner:
            result = goto(client, robot, grid, goal, start, options, pose=pose)
            return Outcome(robot_name, provider, seed, goal, result, truth(), len(sim.collisions))
        scans = open_scanner(None, client.link, robot)
        sink = ScanPoints(scans, pose)

        def watching(runtime: Runtime) -> PoseProvider:
            runtime.add_sink(sink)
            return pose or (lambda: None if (est := runtime.estimate_now()) is None else est.pose)

        try:
            result = goto(client, robot, grid, goal, start, options, pose_from=watching, scan=sink.points)
        finally:
            scans.close()
        return Outcome(robot_name, provider, seed, goal, result, truth(), len(sim.collisions))


class LeadTrace:
    """A runtime sink after the localising one: the localiser's pose now beside the truth now."""

    def __init__(self, sink: LocalisingSink, truth: Callable[[], Pose2D]) -> None:
        self.sink, self.truth = sink, truth
        self.rows: list[tuple[float, float, float, float, float]] = []

    def __call__(self, cycle: Cycle) -> None:
        now = self.sink.pose_now()
        if now is not None:
            true = self.truth()
            self.rows.append((cycle.t, now.x, now.y, true.x, true.y))

    def off(self, rest: float = 0.005, settle: float = 1.0) -> tuple[FloatArray, FloatArray]:
        """The localiser's distance from the truth each cycle after its first ``settle`` s: those
        with the truth at rest (slower than ``rest`` m/s), and those moving."""
        if len(self.rows) < 3:
            return np.zeros(0), np.zeros(0)
        t, x, y, tx, ty = np.array(self.rows).T
        still = np.hypot(np.gradient(tx, t), np.gradient(ty, t)) < rest
        off = np.hypot(x - tx, y - ty)
        late = t >= t[0] + settle
        return off[late & still], off[late & ~still]

    def lead(self, speed: float = 0.5) -> float | None:
        """Mean of (pose - truth) along the truth's velocity over the cycles at ``speed`` m/s or more."""
        if len(self.rows) < 3:
            return None
        t, x, y, tx, ty = np.array(self.rows).T
        vx, vy = np.gradient(tx, t), np.gradient(ty, t)
        fast = np.hypot(vx, vy) >= speed
        if not fast.any():
            return None
        along = ((x - tx) * vx + (y - ty) * vy)[fast] / np.hypot(vx, vy)[fast]
        return float(along.mean())


def localised(
    client: RobotClient,
    robot: RobotDescription,
    grid: OccupancyGrid,
    ends: tuple[Pose2D, Pose2D],
    options: GotoOptions | None,
    seed: int,
    truth: Callable[[], Pose2D],
) -> tuple[GotoResult, LeadTrace]:
    """One goto from ``ends[0]`` to ``ends[1]`` on ``omnibot goto``'s localiser; its result and the
    localiser's pose beside the truth every cycle."""
    start, goal = ends
    scans = open_scanner(None, client.link, robot)
    localiser = Localiser(grid, seed=seed)
    localiser.reset(start, spread=(0.05, 0.05))
    sink = LocalisingSink(scans, localiser)
    trace = LeadTrace(sink, truth)

    def placing(runtime: Runtime) -> PoseProvider:
        runtime.add_sink(sink)
        runtime.add_sink(trace)
        return sink.pose_now

    try:
        result = goto(client, robot, grid, goal, start, options, pose_from=placing, scan=sink.points)
    finally:
        sink.close()
    return result, trace


def table(outcomes: list[Outcome]) -> str:
    out = [
        "| robot | pose provider | arrived (goto's verdict) | within 5 cm, 5 deg by the truth | "
        "truth error (mean, max) | heading error (mean, max) | contacts | re-plans | time per goal "
        "(mean, max) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    keys = sorted({(o.robot, o.provider) for o in outcomes}, key=lambda k: (k[0], k[1] != "odometry"))
    for robot, provider in keys:
        rows = [o for o in outcomes if (o.robot, o.provider) == (robot, provider)]
        n = len(rows)
        err = [100 * o.error for o in rows]
        head = [math.degrees(o.heading_error) for o in rows]
        dur = [o.result.duration for o in rows]
        out.append(
            f"| {robot} | {provider} | {sum(o.result.arrived for o in rows)}/{n} | "
            f"{sum(o.within() for o in rows)}/{n} | {statistics.mean(err):.1f}, {max(err):.1f} cm | "
            f"{statistics.mean(head):.1f}, {max(head):.1f} | {sum(o.contacts for o in rows)} | "
            f"{sum(o.result.replans for o in rows)} | {statistics.mean(dur):.1f}, {max(dur):.1f} s |"
        )
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default="omni4,omni3,mecanum4")
    parser.add_argument("--poses", default="odometry,truth")
    parser.add_argument("--goals", type=int, default=20)
    parser.add_argument("--world", default="room")
    parser.add_argument("--obstacle", action="store_true", help=f"add {OBSTACLE} to the simulated room")
    parser.add_argument(
        "--scanner", action="store_true", help="the robot's scanner watches too, as in omnibot goto"
    )
    parser.add_argument("--detail", action="store_true", help="one line per goal")
    args = parser.parse_args(argv)
    outcomes: list[Outcome] = []
    with tempfile.TemporaryDirectory() as tmp:
        sim_world = world_with_obstacle(args.world, OBSTACLE, Path(tmp)) if args.obstacle else None
        for robot in args.robots.split(","):
            targets = goals(robot, args.goals, args.world)
            for provider in args.poses.split(","):
                for k, goal in enumerate(targets):
                    o = run_goal(robot, goal, k + 1, provider, args.world, sim_world, scanner=args.scanner)
                    outcomes.append(o)
                    if args.detail:
                        print(
                            f"{robot} {provider} seed {k + 1} goal ({goal.x:.2f}, {goal.y:.2f}, "
                            f"{math.degrees(goal.theta):.0f}): {o.result.summary()}; truth "
                            f"{100 * o.error:.1f} cm {math.degrees(o.heading_error):.1f} deg, "
                            f"{o.contacts} contacts, {o.result.replans} re-plans",
                            flush=True,
                        )
    print(table(outcomes))
    for robot in args.robots.split(","):
        leads = [100 * o.lead for o in outcomes if o.robot == robot and o.lead is not None]
        if leads:
            print(
                f"{robot}: the localiser's lead over the truth along the travel at >= 0.5 m/s, "
                f"per goal mean {statistics.mean(leads):+.2f} cm (from {min(leads):+.2f} to {max(leads):+.2f})"
            )
        offs = [o.off for o in outcomes if o.robot == robot and o.off is not None]
        for k, state in enumerate(("at rest", "moving")):
            off = 100 * np.concatenate([o[k] for o in offs]) if offs else np.zeros(0)
            if len(off):
                print(
                    f"{robot}: the localiser's distance from the truth {state} (after its first second), "
                    f"mean {off.mean():.2f} cm, 95th percentile {np.percentile(off, 95):.2f}, max {off.max():.2f}"
                )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())


__all__ = ["OBSTACLE", "Outcome", "goals", "run_goal", "world_with_obstacle"]
