"""The localiser on a robot at rest: its pose beside the simulator's truth every cycle (issue 25).

Run: ``python -m benchmarks.localise_rest`` (``--robots``, ``--worlds``, ``--poses N``,
``--seconds S``, ``--resolution M``, ``--map MAP.yaml``; a minute or two per world on one core).

For each world, robot and pose (the world's start, then ``N - 1`` seeded poses where the robot
fits, :func:`benchmarks.goto.goals`): the robot stands there in a fresh lockstep simulator (seed
k, firmware and physics) on goto's runtime (:func:`omnibot.navigation.goto.navigation_runtime`,
nothing driving), the :class:`~omnibot.mapping.Localiser` in the world rasterised at
``--resolution`` (goto's benchmark's 2.5 cm by default), or in a saved map (``--map``: ``omnibot
map``'s of the world, whose map frame is the world's), started 5 cm of spread about the truth and
fed by the robot's scanner (:class:`~omnibot.mapping.LocalisingSink`, as ``omnibot goto``). Every
cycle: the truth, the localiser's pose now (its ``map -> odom`` on the latest odometry) and the
runtime's estimate (the fused odometry, which at rest must not move). Reported per world and
robot, over the cycles after the first second: the localiser's distance from the truth (mean,
95th percentile, max), its heading error (max), its spread (the standard deviation of its position
about its own mean, per pose: the wander) and how far the estimate moved.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from benchmarks.goto import goals
from benchmarks.planner import rasterise
from omnibot.lidar import open_scanner
from omnibot.mapping import Localiser, LocalisingSink, OccupancyGrid, load_map
from omnibot.motion import Pose2D
from omnibot.navigation import navigation_runtime, simulated_client
from omnibot.robot import load_robot
from omnibot.runtime import Cycle
from omnibot.sim import load_world
from omnibot.transport import find_simulator

FloatArray = NDArray[np.float64]

SETTLE = 1.0
"""s: the localiser's first second (its first scans) is not counted."""


@dataclass(frozen=True)
class Rest:
    """One robot at rest: per cycle after the first second, (t, truth x, y, theta, localiser x, y,
    theta, estimate x, y, theta)."""

    rows: FloatArray

    @property
    def off(self) -> FloatArray:
        """The localiser's distance from the truth, m."""
        r = self.rows
        return np.asarray(np.hypot(r[:, 4] - r[:, 1], r[:, 5] - r[:, 2]))

    @property
    def heading(self) -> FloatArray:
        """The localiser's heading error, rad (absolute)."""
        r = self.rows
        return np.asarray(np.abs((r[:, 6] - r[:, 3] + math.pi) % (2 * math.pi) - math.pi))

    @property
    def wander(self) -> float:
        """The localiser's position spread about its own mean, m (RMS)."""
        xy = self.rows[:, 4:6]
        return float(np.sqrt(((xy - xy.mean(axis=0)) ** 2).sum(axis=1).mean()))

    @property
    def drift(self) -> float:
        """How far the estimate moved from its first pose here, m (most)."""
        e = self.rows[:, 7:9]
        return float(np.hypot(*(e - e[0]).T).max())


def at_rest(
    robot_name: str, world: str, pose: Pose2D, seed: int, seconds: float, grid: OccupancyGrid
) -> Rest:
    """The robot standing at ``pose`` in ``world`` for ``seconds`` (simulated), localised in ``grid``."""
    robot = load_robot(robot_name)
    rows: list[tuple[float, ...]] = []
    with simulated_client(robot, world=world, start=pose, seed=seed) as client:
        sim = find_simulator(client.link)
        assert sim is not None
        localiser = Localiser(grid, seed=seed)
        localiser.reset(pose, spread=(0.05, 0.05))
        sink = LocalisingSink(open_scanner(None, client.link, robot), localiser)

        def trace(cycle: Cycle) -> None:
            now, est, true = sink.pose_now(), cycle.estimate, sim.pose
            if now is not None and est is not None and sink.updates:
                rows.append(
                    (cycle.t, true.x, true.y, true.theta, now.x, now.y, now.theta, est.x, est.y, est.theta)
                )

        try:
            with navigation_runtime(client, robot, pose) as runtime:
                runtime.add_sink(sink)
                runtime.add_sink(trace)
                start = client.clock.now()
                while client.clock.now() - start < seconds:
                    runtime.step()
                    client.sleep(runtime.period)
        finally:
            sink.close()
    table = np.array(rows)
    return Rest(table[table[:, 0] >= table[0, 0] + SETTLE])


def row(world: str, robot: str, rests: list[Rest]) -> str:
    off = 100 * np.concatenate([r.off for r in rests])
    heading = math.degrees(max(float(r.heading.max()) for r in rests))
    wander = 100 * max(r.wander for r in rests)
    drift = 100 * max(r.drift for r in rests)
    return (
        f"| {world} | {robot} | {len(rests)} | {off.mean():.2f}, {np.percentile(off, 95):.2f}, {off.max():.2f} cm | "
        f"{heading:.2f} | {wander:.2f} cm | {drift:.3f} cm |"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default="omni4,omni3,mecanum4")
    parser.add_argument("--worlds", default="room,house")
    parser.add_argument("--poses", type=int, default=3, help="the world's start and N - 1 seeded poses")
    parser.add_argument("--seconds", type=float, default=6.0)
    parser.add_argument("--resolution", type=float, default=0.025)
    parser.add_argument("--map", help="localise in this saved map (omnibot map's) instead; one world")
    args = parser.parse_args(argv)
    print(
        "| world | robot | poses | localiser from the truth (mean, 95 %, max) | heading (max, deg) | "
        "wander (RMS about its mean, worst pose) | estimate moved (max) |"
    )
    print("|---|---|---|---|---|---|---|")
    for world in args.worlds.split(","):
        start = load_world(world).start or Pose2D(0.0, 0.0, 0.0)
        grid = load_map(args.map) if args.map else rasterise(load_world(world), args.resolution)
        for robot in args.robots.split(","):
            poses = [start, *goals(robot, args.poses - 1, world)]
            rests = [at_rest(robot, world, pose, k + 1, args.seconds, grid) for k, pose in enumerate(poses)]
            print(row(world, robot, rests), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())


__all__ = ["Rest", "at_rest"]
