"""The 2D SLAM on synthetic scans: APE of SLAM vs odometry alone after ~100 m in the room world.

Run: ``python -m benchmarks.slam_synthetic`` (``--help`` for options). The true path loops around
the room world (an ellipse whose radii wander lap by lap, the body swinging +-0.5 rad about the
direction of travel), 0.5 m/s, scans at 10 Hz from the true poses (360 rays, 8 m, 1 cm range noise,
2 % dropouts; :func:`synthetic_scan`). The odometry drifts as a wheeled robot's does on a bad floor
(scale error 3 %, heading bias 2 deg per metre, per-step noise; :func:`drifting_odometry`). APE
RMSE is of positions against the truth (the map frame starts at the true start, no alignment);
CPU time is the SLAM's ``update`` per scan (mean, and the worst scan: a loop closure's). Scans are
"still" (all rays at once) or a spinning scanner's (one turn per 0.1 s, each ray cast from where
the base is by then), the SLAM deskewing them with the odometry's twist or not.

The helpers here also make the data of tests/mapping and benchmarks/scan_matching.py.
"""

from __future__ import annotations

import argparse
import itertools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from omnibot.mapping import compose
from omnibot.mapping.deskew import motion
from omnibot.mapping.se2 import between
from omnibot.motion import Pose2D, Twist
from omnibot.scan import Scan
from omnibot.sim import World, load_world, parse_world

RAYS = 360
RANGE_MAX = 8.0
RATE = 10.0
SPEED = 0.5


def synthetic_scan(
    world: World,
    pose: Pose2D,
    rng: np.random.Generator,
    stamp: float = 0.0,
    *,
    rays: int = RAYS,
    range_max: float = RANGE_MAX,
    noise: float = 0.01,
    noise_fraction: float = 0.0,
    dropout: float = 0.02,
    twist: Twist | None = None,
    time_increment: float = 0.0,
) -> Scan:
    """A 360-degree scan from ``pose`` (scanner at the base's origin): Gaussian range noise (1 sigma
    ``noise + noise_fraction * range``, m), dropouts.

    With a body ``twist`` and a ``time_increment``, ray ``i`` is cast ``i * time_increment`` s
    later, from where the base has moved by then (a spinning scanner's motion distortion).
    """
    increment = 2.0 * math.pi / rays
    angles = -math.pi + increment * np.arange(rays)
    origins = np.array([[pose.x, pose.y]])
    headings = angles + pose.theta
    if twist is not None and time_increment > 0:
        x, y, th = motion(twist, time_increment * np.arange(rays, dtype=np.float64))
        c, s = math.cos(pose.theta), math.sin(pose.theta)
        origins = np.column_stack((pose.x + c * x - s * y, pose.y + s * x + c * y))
        headings = headings + th
    ranges = world.raycast(origins, headings, range_max)
    ranges = ranges + rng.normal(0.0, 1.0, rays) * (
        noise + noise_fraction * np.where(ranges < math.inf, ranges, 0.0)
    )
    ranges[rng.random(rays) < dropout] = math.inf
    ranges[~(ranges <= range_max)] = math.inf
    return Scan(
        stamp,
        -math.pi,
        increment,
        ranges,
        0.05,
        range_max,
        time_increment=time_increment,
        scan_time=1.0 / RATE,
    )


def a1_scan(world: World, pose: Pose2D, rng: np.random.Generator, stamp: float = 0.0) -> Scan:
    """A :func:`synthetic_scan` with an RPLIDAR A1's reach and range noise (12 m, 1 % of the range, as
    the simulator's scanner has them)."""
    return synthetic_scan(world, pose, rng, stamp, range_max=12.0, noise=0.0, noise_fraction=0.01)


def corridor_world(length: float = 30.0, width: float = 2.0) -> World:
    """A long closed corridor without features along x from 0 to ``length``, centred on y = 0."""
    return parse_world(
        {
            "name": "long_corridor",
            "walls": [{"shape": "rectangle", "min": [0.0, -width / 2], "max": [length, width / 2]}],
        }
    )


def room_path(length: float, rate: float = RATE, speed: float = SPEED) -> list[Pose2D]:
    """Poses every ``1 / rate`` s on laps around the room world (see the module docstring)."""
    cx, cy = 2.4, 2.2
    step = speed / rate
    phi = 0.0
    poses: list[Pose2D] = []
    for k in range(round(length / step) + 1):
        rx = 1.0 + 0.2 * math.sin(phi / 5.0)
        ry = 0.7 + 0.1 * math.sin(phi / 3.0)
        x, y = cx + rx * math.cos(phi), cy + ry * math.sin(phi)
        tangent = math.atan2(ry * math.cos(phi), -rx * math.sin(phi))
        poses.append(Pose2D(x, y, tangent + 0.5 * math.sin(0.05 * k)))
        phi += step / math.hypot(rx * math.sin(phi), ry * math.cos(phi))
    return poses


def corridor_path(
    length: float, rate: float = RATE, speed: float = SPEED, start: float = 2.0
) -> list[Pose2D]:
    """Poses along a corridor's centre line from x = ``start``, weaving +-0.2 m, heading +-0.3 rad."""
    step = speed / rate
    return [
        Pose2D(start + k * step, 0.2 * math.sin(0.03 * k), 0.3 * math.sin(0.02 * k))
        for k in range(round(length / step) + 1)
    ]


def drifting_odometry(
    truth: Sequence[Pose2D],
    rng: np.random.Generator,
    *,
    scale: float = 0.03,
    heading_bias: float = math.radians(2.0),
    noise_xy: float = 0.01,
    noise_theta: float = 0.002,
) -> list[Pose2D]:
    """Odometry of the true path: steps scaled by ``1 + scale``, ``heading_bias`` rad per metre, noise."""
    odom = [truth[0]]
    for a, b in itertools.pairwise(truth):
        d = between(a, b)
        dist = math.hypot(d.x, d.y)
        step = Pose2D(
            d.x * (1.0 + scale) + rng.normal(0.0, noise_xy * dist + 1e-4),
            d.y * (1.0 + scale) + rng.normal(0.0, noise_xy * dist + 1e-4),
            d.theta + heading_bias * dist + rng.normal(0.0, noise_theta),
        )
        odom.append(compose(odom[-1], step))
    return odom


def position_errors(estimate: Sequence[Pose2D], truth: Sequence[Pose2D]) -> np.ndarray:
    """Position error of every pose, m."""
    e = np.array([(p.x, p.y) for p in estimate]) - np.array([(p.x, p.y) for p in truth])
    return np.asarray(np.hypot(e[:, 0], e[:, 1]))


def rmse(errors: np.ndarray) -> float:
    """Root mean square of the errors."""
    return float(math.sqrt(np.mean(np.square(errors))))


@dataclass
class Run:
    """One SLAM run's scores."""

    distance: float
    scans: int
    odometry_ape: float
    slam_ape: float
    slam_end: float
    odometry_end: float
    cpu_mean_ms: float
    cpu_max_ms: float
    keyframes: int
    closures: int


def run(
    length: float,
    seed: int,
    world: World | None = None,
    optimizer: str = "isam2",
    distorted: bool = False,
    deskew: bool = True,
) -> Run:
    """Drive ``length`` m around the room, run the SLAM on every scan, score it.

    ``distorted``: the scans are a spinning scanner's (one turn per scan period, rays cast along
    the true motion), which the SLAM corrects unless ``deskew`` is False.
    """
    from omnibot.mapping.slam import Slam

    rng = np.random.default_rng(seed)
    world = world or load_world("room")
    truth = room_path(length)
    odom = drifting_odometry(truth, rng)
    slam = Slam(optimizer=optimizer, deskew=deskew)
    cpu: list[float] = []
    for k, (true_pose, odom_pose) in enumerate(zip(truth, odom, strict=True)):
        twist = None
        if distorted and k + 1 < len(truth):
            step = between(true_pose, truth[k + 1])
            twist = Twist(step.x * RATE, step.y * RATE, step.theta * RATE)
        spin = 1.0 / (RATE * RAYS) if distorted else 0.0
        scan = synthetic_scan(world, true_pose, rng, k / RATE, twist=twist, time_increment=spin)
        t0 = time.process_time()
        slam.update(odom_pose, scan, k / RATE)
        cpu.append(time.process_time() - t0)
    estimate = [p for _, p in slam.trajectory()]
    slam_err = position_errors(estimate, truth)
    odom_err = position_errors(odom, truth)
    return Run(
        length,
        len(truth),
        rmse(odom_err),
        rmse(slam_err),
        float(slam_err[-1]),
        float(odom_err[-1]),
        1e3 * float(np.mean(cpu)),
        1e3 * float(np.max(cpu)),
        len(slam.keyframes()),
        slam.closures,
    )


def main(argv: list[str] | None = None) -> int:
    """Print the BENCHMARKS.md table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--length", type=float, default=100.0, help="metres driven (default 100)")
    parser.add_argument("--seeds", default="1,2,3", help="comma-separated seeds (default 1,2,3)")
    parser.add_argument("--optimizer", default="isam2,lm", help="back ends to compare (isam2, lm)")
    args = parser.parse_args(argv)
    print(
        "| back end | scans | seed | keyframes | closures | odometry APE RMSE | SLAM APE RMSE | ratio "
        "| end error odometry / SLAM | CPU per scan mean / max |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    setups = [(o, "still", False, True) for o in args.optimizer.split(",")]
    setups += [("isam2", "spinning, deskewed", True, True), ("isam2", "spinning, not deskewed", True, False)]
    for optimizer, scans, distorted, deskew in setups:
        for seed in (int(s) for s in args.seeds.split(",")):
            r = run(args.length, seed, optimizer=optimizer, distorted=distorted, deskew=deskew)
            print(
                f"| {optimizer} | {scans} | {seed} | {r.keyframes} | {r.closures} | {r.odometry_ape * 100:.1f} cm "
                f"| {r.slam_ape * 100:.2f} cm | {r.odometry_ape / r.slam_ape:.0f}x "
                f"| {r.odometry_end * 100:.1f} / {r.slam_end * 100:.2f} cm "
                f"| {r.cpu_mean_ms:.1f} / {r.cpu_max_ms:.0f} ms |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
