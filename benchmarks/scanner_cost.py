"""Laser scanner cost: what a 10 Hz x 360-ray scanner adds to a simulated second, alone and in a fleet.

Run: ``python -m benchmarks.scanner_cost`` (``make bench`` runs every benchmark). Each case is run
with and without scan listeners, interleaved, in the same process; the best of ``--repeats`` runs
is kept for each (the least disturbed by the other processes of a shared machine). The scanner's
cost is the difference, per simulated second, reported as a share of the simulator's own time for
that simulated second (the goal: <= 10 %) and of one second of real time.

* single: one omni4 :class:`~omnibot.sim.simulator.Simulator` (no firmware) driving a curve at
  1 kHz, in the ``room`` (72 edges) and ``house`` (400 edges) worlds;
* fleet: a :class:`~omnibot.sim.fleet.Fleet` of four omni4 robots (firmware included, standing
  still), every one with a scanner that sees the three others, in the same worlds;
* ray casting alone: 360 rays of a turning robot, the compiled kernels (the edge index by direction,
  built every few revolutions, and a revolution's cast, :func:`~omnibot.sim.kernels.scan_revolution`
  without the noise) against the vectorised numpy
  :meth:`World.raycast <omnibot.sim.world.World.raycast>` (every ray against every edge), the same rays.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable

import numpy as np

from omnibot.motion import Pose2D
from omnibot.robot import load_robot
from omnibot.scan import Scan
from omnibot.sim import Fleet, Simulator, kernels, load_world
from omnibot.sim.kernels.scan import P_AX, P_AY, P_DT, P_INNER, P_REACH, SCAN_PARAMS

FLEET_POSES = {
    "room": [(1.0, 1.0), (2.5, 2.0), (4.2, 3.2), (1.0, 2.0)],
    "house": [(1.0, 3.0), (5.0, 3.0), (7.5, 1.0), (2.0, 5.3)],
}


def _single(world: str, scan: bool, seconds: float) -> tuple[float, int]:
    """Wall seconds for ``seconds`` of one simulated robot, and the scans it delivered."""
    sim = Simulator(load_robot("omni4"), world=world, seed=1)
    sim.set_pwm([60, 150, -20, -150])
    got: list[Scan] = []
    if scan:
        sim.add_scan_listener(got.append)
    sim.step(200)
    got.clear()
    t0 = time.process_time()
    sim.advance(seconds)
    return time.process_time() - t0, len(got)


def _fleet(world: str, scan: bool, seconds: float) -> tuple[float, int]:
    """Wall seconds for ``seconds`` of a fleet of four, and the scans they delivered."""
    fleet = Fleet(load_world(world))
    got: list[Scan] = []
    for k, (x, y) in enumerate(FLEET_POSES[world]):
        device = fleet.add(f"r{k}", "omni4", seed=k, pose=Pose2D(x, y, 0.3 * k))
        if scan:
            device.sim.add_scan_listener(got.append)
    for _ in range(200):
        fleet.step()
    steps = round(seconds / fleet.dt)
    got.clear()
    t0 = time.process_time()
    for _ in range(steps):
        fleet.step()
    return time.process_time() - t0, len(got)


def _best(
    run: Callable[[str, bool, float], tuple[float, int]], world: str, seconds: float, repeats: int
) -> dict[str, float]:
    bare = scanned = math.inf
    scans = 0
    for _ in range(repeats):  # interleaved: both see the same machine load
        bare = min(bare, run(world, False, seconds)[0])
        wall, scans = run(world, True, seconds)
        scanned = min(scanned, wall)
    return {
        "bare_ms": 1e3 * bare / seconds,
        "scan_ms": 1e3 * scanned / seconds,
        "scans_per_s": scans / seconds,
    }


def ray_casting(world: str, repeats: int = 200) -> tuple[float, float, float, float]:
    """(index us, kernel us, numpy us, largest difference m) for 360 rays of a robot turning 0.5 rad
    meanwhile: building the edge index (once every few revolutions), a revolution's cast with it
    (the rays' table made once, as a scanner makes it), and the vectorised numpy raycast of every
    ray against every edge."""
    w = load_world(world)
    seg = np.ascontiguousarray(w.segments)
    n = 360
    start = w.start or Pose2D(1.0, 1.0, 0.0)
    ray_t = np.arange(n, dtype=np.float64) * (0.1 / n)
    ray_a = np.arange(n, dtype=np.float64) * (-2 * math.pi / n)
    hist_p = np.zeros((101, 3))
    hist_p[:, 0], hist_p[:, 1] = start.x, start.y
    hist_p[:, 2] = np.linspace(0.0, 0.5, 101)
    out, none = np.empty(n), np.zeros(0)
    no_v, no_off = np.zeros((0, 2)), np.zeros(1, dtype=np.int64)
    rays = kernels.ray_table(ray_t, ray_a)  # once per scanner
    params = np.zeros(SCAN_PARAMS)
    params[[P_DT, P_REACH, P_AX, P_AY, P_INNER]] = 0.001, 14.0, start.x, start.y, 0.25
    index = kernels.scan_index(seg, start.x, start.y, 0.25, 14.0)
    args = (0.0, 0, n, rays, hist_p, 0, params, seg, *index, no_v, no_off, out, none, none, none)
    assert kernels.scan_revolution(*args)  # cast only: no draws
    t0 = time.process_time()
    for _ in range(repeats):
        index = kernels.scan_index(seg, start.x, start.y, 0.25, 14.0)
    built = (time.process_time() - t0) / repeats
    t0 = time.process_time()
    for _ in range(repeats):
        kernels.scan_revolution(*args)
    compiled = (time.process_time() - t0) / repeats
    origins = np.column_stack((np.full(n, start.x), np.full(n, start.y)))
    angles = ray_a + np.interp(ray_t, np.arange(101) * 0.001, hist_p[:, 2])
    t0 = time.process_time()
    for _ in range(max(1, repeats // 10)):
        ref = w.raycast(origins, angles, 14.0)
    vectorised = (time.process_time() - t0) / max(1, repeats // 10)
    both = np.isfinite(ref) & np.isfinite(out)
    assert np.array_equal(np.isfinite(ref), np.isfinite(out))
    return 1e6 * built, 1e6 * compiled, 1e6 * vectorised, float(np.max(np.abs(ref[both] - out[both])))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="simulated seconds per run (default 3)")
    parser.add_argument("--repeats", type=int, default=5, help="runs of each case, best kept (default 5)")
    parser.add_argument("--quick", action="store_true", help="0.5 s runs, 2 repeats (a check that it works)")
    args = parser.parse_args(argv)
    seconds, repeats = (0.5, 2) if args.quick else (args.seconds, args.repeats)
    kernels.warm_up(every=False)  # from a cold cache too, the compiled kernels are measured, not their twins
    print("ray casting, 360 rays of a turning robot (us per revolution):")
    print(
        "| world | edges | edge index (now and then) | compiled cast | numpy World.raycast | largest difference |"
    )
    print("|---|---|---|---|---|---|")
    for world in ("room", "house"):
        built, compiled, vectorised, diff = ray_casting(world)
        edges = len(load_world(world).segments)
        print(f"| {world} | {edges} | {built:.1f} | {compiled:.1f} | {vectorised:.1f} | {diff:.1e} m |")
    print()
    print(f"scanner cost, 10 Hz x 360 rays, best of {repeats} runs of {seconds:g} simulated s:")
    print("| case | world | simulator ms per sim s | with scanners | scanner ms per sim s "
          "| of the simulator | of real time | scans/s |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    worst = 0.0
    for case, run in (("1 robot", _single), ("fleet of 4", _fleet)):
        for world in ("room", "house"):
            r = _best(run, world, seconds, repeats)
            extra = r["scan_ms"] - r["bare_ms"]
            share = extra / r["bare_ms"]
            worst = max(worst, share)
            print(
                f"| {case} | {world} | {r['bare_ms']:.2f} | {r['scan_ms']:.2f} | {extra:.2f} | "
                f"{100 * share:.1f} % | {extra / 10:.2f} % | {r['scans_per_s']:.0f} |"
            )
    print(f"\nlargest share of the simulator's time: {100 * worst:.1f} % (goal <= 10 %)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
