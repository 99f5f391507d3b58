"""The occupancy mapper's ray traversal, three ways, and the cost of rebuilding a map.

Run: ``python -m benchmarks.mapping_mapper [--scans N] [--repeat R]``. Scans of 360 rays (1 cm
noise, 8 m range) are cast in the bundled ``room`` along its loop (benchmarks.mapping_scenes), and
integrated into a fixed 5 cm grid by:

* ``numba``: the compiled grid walk the mapper uses (:func:`omnibot.mapping.mapper._integrate`);
* ``numpy``: every ray sampled at a third of a cell in one vectorised pass, cells deduplicated
  (:func:`omnibot.mapping.mapper.ray_cells_numpy`), then the log-odds updated with fancy indexing;
* ``skimage``: scikit-image's ``draw.line`` per ray (Bresenham, a Python loop over rays), then the
  same update.

Each is timed per scan (best of ``--repeat`` passes over all scans, after a warm-up that compiles the
numba kernel). Then the rebuild a SLAM does after a loop closure: ``OccupancyMapper.rebuild`` of all
scans at new poses, and of 10x as many scans (a long run), with the map's score against the world.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from skimage.draw import line as draw_line

from benchmarks.mapping_scenes import cast_scan, path_poses
from omnibot.mapping.mapper import OccupancyMapper, ray_cells_numpy, ray_ends
from omnibot.mapping.score import score_map
from omnibot.motion import Pose2D
from omnibot.scan import Scan
from omnibot.sim import load_world

BOUNDS = (-1.0, -1.0, 6.0, 5.0)


def _update(mapper: OccupancyMapper, free: NDArray[np.int64], hit: NDArray[np.int64]) -> None:
    lo = mapper.logodds.reshape(-1)
    free = np.setdiff1d(free, hit)  # a hit wins over the free passes of its own scan
    lo[free] = np.maximum(lo[free] + mapper.l_free, mapper.l_min)
    hit = np.unique(hit)
    lo[hit] = np.minimum(lo[hit] + mapper.l_occ, mapper.l_max)


def integrate_numpy(mapper: OccupancyMapper, scan: Scan, pose: Pose2D) -> None:
    ox, oy, ends, hits = ray_ends(scan, pose, mapper.max_clear)
    o = mapper.origin
    free, hit = ray_cells_numpy(
        ox - o.x, oy - o.y, ends - (o.x, o.y), hits, mapper.resolution, mapper.logodds.shape
    )
    _update(mapper, free, hit)


def integrate_skimage(mapper: OccupancyMapper, scan: Scan, pose: Pose2D) -> None:
    ox, oy, ends, hits = ray_ends(scan, pose, mapper.max_clear)
    o, res = mapper.origin, mapper.resolution
    rows, cols = mapper.logodds.shape
    r0, c0 = int((oy - o.y) // res), int((ox - o.x) // res)
    cells_r, cells_c = [], []
    ends_rc = np.floor((ends - (o.x, o.y)) / res).astype(np.int64)
    for (c1, r1), is_hit in zip(ends_rc, hits, strict=True):
        rr, cc = draw_line(r0, c0, int(r1), int(c1))
        if is_hit:
            rr, cc = rr[:-1], cc[:-1]
        cells_r.append(rr)
        cells_c.append(cc)
    rr, cc = np.concatenate(cells_r), np.concatenate(cells_c)
    ok = (rr >= 0) & (rr < rows) & (cc >= 0) & (cc < cols)
    h = ends_rc[hits]
    hok = (h[:, 1] >= 0) & (h[:, 1] < rows) & (h[:, 0] >= 0) & (h[:, 0] < cols)
    _update(mapper, np.unique(rr[ok] * cols + cc[ok]), h[hok, 1] * cols + h[hok, 0])


Integrate = Callable[[OccupancyMapper, Scan, Pose2D], None]


def _time(run: Integrate, pairs: list[tuple[Scan, Pose2D]], repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        mapper = OccupancyMapper(bounds=BOUNDS)
        t0 = time.perf_counter()
        for scan, pose in pairs:
            run(mapper, scan, pose)
        best = min(best, time.perf_counter() - t0)
    return best / len(pairs)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.mapping_mapper", description=__doc__)
    ap.add_argument("--scans", type=int, default=220, help="scans along the loop (default 220, 5 cm apart)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    world = load_world("room")
    rng = np.random.default_rng(0)
    poses = path_poses(step=max(0.01, 11.0 / args.scans))[: args.scans]
    pairs = [(cast_scan(world, p, rng=rng), p) for p in poses]
    OccupancyMapper(bounds=BOUNDS).add(*pairs[0])  # compile
    ways: dict[str, Integrate] = {
        "numba": lambda m, s, p: m.add(s, p),
        "numpy": integrate_numpy,
        "skimage": integrate_skimage,
    }
    print(
        f"{len(pairs)} scans x {len(pairs[0][0])} rays, 5 cm grid {OccupancyMapper(bounds=BOUNDS).to_grid().shape}"
    )
    print("| traversal | per scan (ms) | vs numba |")
    print("|---|---|---|")
    base = 0.0
    for name, run in ways.items():
        t = _time(run, pairs, args.repeat)
        base = base or t
        print(f"| {name} | {t * 1e3:.2f} | {t / base:.1f}x |")
    print()
    print("| rebuild | scans | time (ms) | per scan (ms) | precision | recall |")
    print("|---|---|---|---|---|---|")
    mapper = OccupancyMapper()
    for label, batch in (("the loop", pairs), ("10 loops", pairs * 10)):
        shifted = [(s, Pose2D(p.x + 0.01, p.y, p.theta)) for s, p in batch]
        mapper.extend(shifted)
        t0 = time.perf_counter()
        mapper.rebuild(batch)
        grid = mapper.to_grid()
        dt = time.perf_counter() - t0
        sc = score_map(grid, world)
        print(
            f"| {label} | {len(batch)} | {dt * 1e3:.1f} | {dt / len(batch) * 1e3:.3f} | "
            f"{sc.precision:.3f} | {sc.recall:.3f} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
