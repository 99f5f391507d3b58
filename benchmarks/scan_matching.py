"""2D scan registration candidates side by side: accuracy, robustness to bad guesses, time per match.

Run: ``python -m benchmarks.scan_matching`` (``--help`` for options). Pairs of synthetic scans
(benchmarks/slam_synthetic.py: 360 rays, 1 cm range noise, 2 % dropouts) taken 0.3 m apart along
the room world's laps, and mid-way along a 40 m featureless corridor (its ends out of range). Each
pair is registered from the true relative pose plus an error drawn uniformly within +-E m in x and
y and +-A degrees in heading. Candidates:

* ``csm+icp``: :class:`omnibot.mapping.matcher.ScanMatcher` (correlative search over a window as
  wide as the guess's error bounds, then point-to-line ICP);
* ``icp``: the same without the search (``search_xy = search_theta = 0``);
* ``small_gicp GICP``: ``small_gicp.align`` on the points at z = 0 (2.5 cm downsampling, 0.5 m
  correspondences), the result projected on the plane (x, y, yaw); ``, walls``: the points
  extruded into 0.2 m high walls first (three copies at z = -0.1, 0, 0.1), so that the local
  surfaces have horizontal normals (flat points give point-to-plane the floor's normal, z; it
  failed every match that way), with ``GICP`` or ``PLANE_ICP``;
* ``kiss-icp``: kiss-icp's point-to-point registration (its voxel map of the target, 0.05 m voxels,
  0.5 m correspondences, kernel 0.05) at z = 0.

A match succeeds when it lands within 2 cm and 0.5 degree of the truth (in the corridor: across
the axis and in heading only, the axis being unobservable). Time is the process CPU per match
(one thread), preparation of the target included.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable

import numpy as np

from benchmarks.slam_synthetic import corridor_path, corridor_world, room_path, synthetic_scan
from omnibot.mapping import compose
from omnibot.mapping.matcher import ScanMatcher
from omnibot.mapping.se2 import between
from omnibot.motion import Pose2D
from omnibot.sim import load_world

Points = np.ndarray
Matcher = Callable[[Points, Points, Pose2D], Pose2D]


def _matrix(p: Pose2D) -> np.ndarray:
    c, s = math.cos(p.theta), math.sin(p.theta)
    t = np.eye(4)
    t[:2, :2] = [[c, -s], [s, c]]
    t[:2, 3] = (p.x, p.y)
    return t


def _planar(t: np.ndarray) -> Pose2D:
    return Pose2D(float(t[0, 3]), float(t[1, 3]), math.atan2(t[1, 0], t[0, 0]))


def _xyz(p: Points) -> np.ndarray:
    return np.column_stack((p, np.zeros(len(p))))


def _walls(p: Points) -> np.ndarray:
    """The points extruded into walls (copies at z = -0.1, 0, 0.1 m): surfaces with horizontal normals."""
    return np.vstack([np.column_stack((p, np.full(len(p), z))) for z in (-0.1, 0.0, 0.1)])


def ours(search_xy: float, search_theta: float) -> Matcher:
    matcher = ScanMatcher(search_xy=search_xy, search_theta=search_theta)
    return lambda src, tgt, guess: matcher.match(src, tgt, guess).pose


def small_gicp_matcher(kind: str, extrude: bool) -> Matcher:
    import small_gicp

    lift = _walls if extrude else _xyz

    def run(src: Points, tgt: Points, guess: Pose2D) -> Pose2D:
        result = small_gicp.align(
            lift(tgt),
            lift(src),
            _matrix(guess),
            registration_type=kind,
            downsampling_resolution=0.025,
            max_correspondence_distance=0.5,
            num_threads=1,
            max_iterations=50,
        )
        return _planar(np.asarray(result.T_target_source))

    return run


def kiss_icp_matcher() -> Matcher:
    from kiss_icp.mapping import VoxelHashMap
    from kiss_icp.registration import Registration

    registration = Registration(max_num_iterations=500, convergence_criterion=1e-4, max_num_threads=1)

    def run(src: Points, tgt: Points, guess: Pose2D) -> Pose2D:
        voxels = VoxelHashMap(voxel_size=0.05, max_distance=20.0, max_points_per_voxel=20)
        voxels.add_points(_xyz(tgt))
        t = registration.align_points_to_map(_xyz(src), voxels, _matrix(guess), 0.5, 0.05)
        return _planar(np.asarray(t))

    return run


CANDIDATES: dict[str, Callable[[float, float], Matcher]] = {
    "csm+icp": ours,
    "icp": lambda xy, th: ours(0.0, 0.0),
    "small_gicp GICP": lambda xy, th: small_gicp_matcher("GICP", False),
    "small_gicp GICP, walls": lambda xy, th: small_gicp_matcher("GICP", True),
    "small_gicp plane, walls": lambda xy, th: small_gicp_matcher("PLANE_ICP", True),
    "kiss-icp": lambda xy, th: kiss_icp_matcher(),
}
"""name: factory taking the guess's error bounds (m, rad), which only the correlative search uses."""


def pairs(
    world_name: str, count: int, rng: np.random.Generator
) -> list[tuple[Points, Points, Pose2D, float]]:
    """(source points, target points, true pose of the source in the target's frame, target's heading)."""
    if world_name == "room":
        world = load_world("room")
        path = room_path(30.0)
        gap = 6
    else:
        world = corridor_world(40.0)
        path = corridor_path(10.0, start=14.0)
        gap = 6
    starts = np.linspace(0, len(path) - gap - 1, count).astype(int)
    out = []
    for k in starts:
        a, b = path[k], path[k + gap]
        out.append(
            (
                synthetic_scan(world, b, rng).points(),
                synthetic_scan(world, a, rng).points(),
                between(a, b),
                a.theta,
            )
        )
    return out


def score(name: str, world: str, count: int, err_xy: float, err_deg: float, seed: int) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    data = pairs(world, count, rng)
    matcher = CANDIDATES[name](err_xy, math.radians(err_deg))
    matcher(data[0][0], data[0][1], data[0][2])  # warm up (compilation, imports)
    errs_xy, errs_th, cpu = [], [], []
    ok = 0
    for src, tgt, truth, heading in data:
        off = Pose2D(*rng.uniform(-1, 1, 3) * np.array([err_xy, err_xy, math.radians(err_deg)]))
        guess = compose(truth, off)
        t0 = time.process_time()
        got = matcher(src, tgt, guess)
        cpu.append(time.process_time() - t0)
        e = between(truth, got)
        dx, dy = got.x - truth.x, got.y - truth.y  # in the target's frame
        across = abs(-math.sin(-heading) * dx + math.cos(-heading) * dy)  # off the corridor's axis
        exy = across if world == "corridor" else math.hypot(e.x, e.y)
        errs_xy.append(exy)
        errs_th.append(abs(e.theta))
        ok += exy < 0.02 and abs(e.theta) < math.radians(0.5)
    return {
        "success": ok / len(data),
        "median_xy": float(np.median(errs_xy)),
        "median_th": float(np.degrees(np.median(errs_th))),
        "cpu_ms": 1e3 * float(np.mean(cpu)),
    }


def covariance_nees(count: int, seed: int) -> float:
    """Mean normalised estimation error squared of ``csm+icp`` on the room pairs (3 if calibrated)."""
    rng = np.random.default_rng(seed)
    matcher = ScanMatcher()
    nees = []
    for src, tgt, truth, _ in pairs("room", count, rng):
        guess = compose(truth, Pose2D(*rng.uniform(-1, 1, 3) * np.array([0.2, 0.2, math.radians(10.0)])))
        r = matcher.match(src, tgt, guess)
        d = np.array(
            [r.pose.x - truth.x, r.pose.y - truth.y, math.remainder(r.pose.theta - truth.theta, 2 * math.pi)]
        )
        nees.append(float(d @ np.linalg.solve(r.covariance, d)))
    return float(np.mean(nees))


def main(argv: list[str] | None = None) -> int:
    """Print the BENCHMARKS.md table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=40, help="pairs per world and guess error (default 40)")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    cases = [("room", 0.05, 2.0), ("room", 0.2, 10.0), ("room", 0.5, 30.0), ("corridor", 0.2, 10.0)]
    print("| candidate | world | guess error | success | median error (xy / heading) | CPU per match |")
    print("|---|---|---|---|---|---|")
    for name in CANDIDATES:
        for world, exy, eth in cases:
            r = score(name, world, args.pairs, exy, eth, args.seed)
            print(
                f"| {name} | {world} | {exy:.2f} m, {eth:.0f} deg | {r['success'] * 100:.0f} % "
                f"| {r['median_xy'] * 1000:.1f} mm / {r['median_th']:.2f} deg | {r['cpu_ms']:.1f} ms |",
                flush=True,
            )
    print(
        f"\ncsm+icp covariance: mean NEES {covariance_nees(args.pairs, args.seed):.2f} on the room pairs (3 if calibrated)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
