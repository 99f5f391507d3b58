"""Localisation in a saved map: the particle filter alone against the filter plus scan-to-map refinement.

Run: ``python -m benchmarks.mapping_localise [--seeds 1,2,3,4,5] [--particles N]``. The bundled
``room`` is mapped from scans at the true poses along its loop (benchmarks.mapping_scenes) and the
map saved and loaded again (a trinary map_server file, as a user localises in), then the
robot drives the loop again (220 poses 5 cm apart, 11 m) with odometry 10 % long and turning 3 degrees
per metre too much. Each seed draws another wrong start (0.3 m away in another direction, 15 degrees
off), other scan noise (1 cm) and other filter draws. The localiser first updates 15 times at
standstill (convergence), then once per pose. Reported: the error after convergence, the worst and
RMS position error and the worst heading error along the path, and the time per update.
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.mapping_scenes import cast_scan, drifting_odometry, path_poses
from omnibot.mapping import Localiser, OccupancyGrid, load_map, save_map
from omnibot.mapping.mapper import build_map
from omnibot.mapping.se2 import wrap
from omnibot.motion import Pose2D
from omnibot.sim import World, load_world


def drive(poses: int) -> tuple[list[Pose2D], list[Pose2D]]:
    """The true poses along the loop (the first ``poses`` of them) and the drifting odometry's."""
    truth = path_poses(step=0.05)[:poses]
    return truth, drifting_odometry(truth, scale=1.1, heading_drift=0.05)


def run(
    world: World, grid: OccupancyGrid, seed: int, refine: bool, particles: int, poses: int
) -> dict[str, float]:
    truth, odom = drive(poses)
    rng = np.random.default_rng(seed + 10)
    loc = Localiser(grid, seed=seed, refine=refine, particles=particles)
    t0 = truth[0]
    loc.reset(Pose2D(t0.x + 0.3 * math.cos(seed), t0.y + 0.3 * math.sin(seed), t0.theta + math.radians(15)))
    start = time.perf_counter()
    for _ in range(15):
        r = loc.update(odom[0], cast_scan(world, t0, rng=rng))
    conv = math.hypot(r.pose.x - t0.x, r.pose.y - t0.y)
    xy, th = [], []
    for tp, op in zip(truth, odom, strict=True):
        r = loc.update(op, cast_scan(world, tp, rng=rng))
        xy.append(math.hypot(r.pose.x - tp.x, r.pose.y - tp.y))
        th.append(abs(wrap(r.pose.theta - tp.theta)))
    per = (time.perf_counter() - start) / (len(truth) + 15)
    e = np.array(xy)
    return {
        "conv": conv,
        "max": float(e.max()),
        "rms": float(np.sqrt(np.mean(e**2))),
        "deg": math.degrees(max(th)),
        "ms": per * 1e3,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.mapping_localise", description=__doc__)
    ap.add_argument("--seeds", default="1,2,3,4,5")
    ap.add_argument("--particles", type=int, default=500)
    ap.add_argument("--poses", type=int, default=220, help="poses of the loop driven (default all 220)")
    args = ap.parse_args(argv)
    seeds = [int(s) for s in args.seeds.split(",")]
    world = load_world("room")
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as tmp:  # localise in a saved map, as a user does
        save_map(
            build_map([(cast_scan(world, p, rng=rng), p) for p in path_poses()[::2]]), Path(tmp, "room.yaml")
        )
        grid = load_map(Path(tmp, "room.yaml"))
    truth, odom = drive(args.poses)
    drift = math.hypot(odom[-1].x - truth[-1].x, odom[-1].y - truth[-1].y)
    print(f"{args.particles} particles, 60 beams, {len(truth)} poses; odometry's final error {drift:.2f} m")
    print(
        "| localiser | seed | after convergence (cm) | max (cm) | RMS (cm) | max heading (deg) | per update (ms) |"
    )
    print("|---|---|---|---|---|---|---|")
    for refine in (False, True):
        name = "filter + refinement" if refine else "particle filter"
        for seed in seeds:
            m = run(world, grid, seed, refine, args.particles, args.poses)
            print(
                f"| {name} | {seed} | {m['conv'] * 100:.1f} | {m['max'] * 100:.1f} | {m['rms'] * 100:.2f} | "
                f"{m['deg']:.2f} | {m['ms']:.1f} |"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
