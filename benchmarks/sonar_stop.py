"""The sonar stop against a wall: collisions and clearance at every speed, angle and threshold.

Run: ``python -m benchmarks.sonar_stop [--closed-loop]`` (``--help`` for options; a few minutes on one
core). ``--closed-loop`` drives the MOVEs on the wheel-speed loop (MODE bit 1), as every front end does.

The simulated omni4 robot (firmware and physics in lockstep, fixed seeds) starts 1.4 m from a
point of the room world's west wall, its path meeting the wall at an angle (90 degrees: head-on,
30: glancing, 150: glancing from the other side), arms its front sonar (``SONAR,1,60,0,0,STOP``) and
drives ``MOVE,INF,V,D,0`` until the firmware stops it or 4 s pass (8 s sideways). Course D = 0 travels where the
sonar looks (covered); D = 90 travels sideways, where no sonar looks (uncovered: the firmware limits
the speed to the robot's uncovered speed, or refuses with MODE bit 3).

Per run: whether the robot touched the wall (the simulator's collision events), the least
clearance between its outline and the wall, the speed it was driving when the stop came (ground
truth) and the warnings. Goal: no collision where the sonar covers the direction of travel.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from omnibot.sim import Simulator

ROBOT = "omni4"
WALL_X = 0.0  # the room world's west wall
WALL_Y = 1.6  # the point of the wall the path aims at
RUN_UP = 1.4  # m from the start to that point, along the path
SPEEDS = (0.3, 0.5, 0.7, 0.85, 1.0)
ANGLES = (20, 30, 45, 60, 90, 120, 135, 150, 160)  # the stop allows for walls met at 30-150
STOPS = (5, 10, 25, 50)
SEEDS = (1, 2, 3)
DESIGN = (30, 150)  # angles to the wall the firmware allows for (safety.INCIDENCE_MAX = 60 degrees)
TIMEOUT = 4.0
TIMEOUT_UNCOVERED = 8.0  # s: the uncovered speed (0.3 m/s) needs 4.7 s to the wall


@dataclass(frozen=True)
class Run:
    speed: float  # commanded, m/s
    angle: int  # path to the wall, degrees
    stop_cm: int
    course: int  # degrees from the head (0: where the sonar looks)
    seed: int
    refuse: bool = False
    closed_loop: bool = False  # MODE bit 1: the wheel-speed loop (every front end's default)


@dataclass(frozen=True)
class Outcome:
    run: Run
    collided: bool
    impact: float  # m/s, fastest approach speed of a contact (0 without)
    clearance: float  # m, least gap between the outline and the wall (negative: pressed into it)
    speed_at_stop: float  # m/s (ground truth) when the firmware stopped the motion, nan if it did not
    warnings: tuple[int, ...]
    errors: tuple[int, ...]
    stopped: bool


def start_pose(angle_deg: float, course_deg: float) -> tuple[float, float, float]:
    """Pose whose travel along ``course_deg`` meets the wall at (WALL_X, WALL_Y) at ``angle_deg``."""
    travel = math.radians(90.0 + angle_deg)  # world direction of travel (90 degrees: -x, head-on)
    x = WALL_X - RUN_UP * math.cos(travel)
    y = WALL_Y - RUN_UP * math.sin(travel)
    return x, y, travel - math.radians(course_deg)


def wall_gap(sim: Simulator, outline: Sequence[tuple[float, float]]) -> float:
    """Distance (m) between the robot's outline and the west wall."""
    pose = sim.pose
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    return min(pose.x + c * px - s * py for px, py in outline) - WALL_X


def drive(run: Run) -> Outcome:
    from omnibot.protocol import codes
    from omnibot.sim import SimDevice

    device = SimDevice(ROBOT, world="room", seed=run.seed, start_pose=start_pose(run.angle, run.course))
    sim = device.sim
    outline = device.robot.footprint.outline()
    v = round(run.speed * 100)
    bits = (codes.MODE_REFUSE_UNCOVERED if run.refuse else 0) | (
        codes.MODE_CLOSED_LOOP if run.closed_loop else 0
    )
    mode = f"MODE,{bits};" if bits else ""
    device.receive(f"{mode}SONAR,1,60,0,0,{run.stop_cm};MOVE,30000,{v},{run.course},0;".encode())
    out = b""
    clearance = math.inf
    speed_at_stop = math.nan
    stopped = False
    steps = round((TIMEOUT if run.course == 0 else TIMEOUT_UNCOVERED) / device.tick)
    rest = 0
    for _ in range(steps):
        device.step()
        clearance = min(clearance, wall_gap(sim, outline))
        data = device.transmit()
        if data:
            out += data
            if not stopped and (b"WARN,13" in data or b"WARN,16" in data or b"IDLE" in data):
                stopped = True
                speed_at_stop = math.hypot(sim.twist.vx, sim.twist.vy)
            if b"ERROR" in data:
                stopped = True
        if stopped:
            rest += 1
            if rest > 1500 and math.hypot(sim.twist.vx, sim.twist.vy) < 1e-3:
                break
    lines = out.decode(errors="replace").split("\r\n")
    warnings = tuple(int(ln.split(",")[1]) for ln in lines if ln.startswith("WARN,"))
    errors = tuple(int(ln.split(",")[1]) for ln in lines if ln.startswith("ERROR,"))
    impact = max((c.speed for c in sim.collisions), default=0.0)
    return Outcome(run, bool(sim.collisions), impact, clearance, speed_at_stop, warnings, errors, stopped)


def runs(
    speeds: Iterable[float],
    angles: Iterable[int],
    stops: Iterable[int],
    seeds: Iterable[int],
    closed_loop: bool = False,
) -> list[Run]:
    speeds, stops, seeds = list(speeds), list(stops), list(seeds)
    cl = closed_loop
    out = [
        Run(v, a, st, 0, seed, closed_loop=cl)
        for v in speeds
        for a in angles
        for st in stops
        for seed in seeds
    ]
    # sideways, where no sonar looks: limited (default) and refused (MODE bit 3), head-on only
    out += [Run(v, 90, st, 90, seed, closed_loop=cl) for v in speeds for st in stops for seed in seeds]
    out += [Run(max(speeds), 90, max(stops), 90, min(seeds), refuse=True, closed_loop=cl)]
    return out


def table(outcomes: list[Outcome]) -> str:
    rows = [
        "| travel | speed m/s | STOP cm | runs | collisions (fastest, m/s) | least clearance cm | "
        "speed at the stop m/s | warnings |",
        "|---|---|---|---|---|---|---|---|",
    ]

    def key(o: Outcome) -> tuple[int, bool, float, int]:  # sideways, no sonar sees: STOP is moot
        return (o.run.course, o.run.refuse, o.run.speed, o.run.stop_cm if o.run.course == 0 else 0)

    for course, refuse, speed, stop in sorted({key(o) for o in outcomes}):
        group = [o for o in outcomes if key(o) == (course, refuse, speed, stop)]
        hits = sum(o.collided for o in group)
        fastest = max(o.impact for o in group)
        least = min(o.clearance for o in group)
        at_stop = [o.speed_at_stop for o in group if not math.isnan(o.speed_at_stop)]
        codes_seen = sorted({w for o in group for w in o.warnings} | {e for o in group for e in o.errors})
        travel = "covered (course 0)" if course == 0 else "uncovered (course 90)"
        if refuse:
            travel += ", refused"
        rows.append(
            f"| {travel} | {speed:.2f} | {stop or 'any'} | {len(group)} | {hits}"
            + (f" ({fastest:.2f})" if hits else "")
            + f" | {100 * least:.1f} | "
            + (f"{min(at_stop):.2f}-{max(at_stop):.2f}" if at_stop else "-")
            + f" | {', '.join(map(str, codes_seen)) or '-'} |"
        )
    return "\n".join(rows)


def angle_table(outcomes: list[Outcome]) -> str:
    covered = [o for o in outcomes if o.run.course == 0]
    angles = sorted({o.run.angle for o in covered})
    rows = [
        "| angle to the wall | " + " | ".join(f"{a}" for a in angles) + " |",
        "|---" * (len(angles) + 1) + "|",
    ]
    for stop in sorted({o.run.stop_cm for o in covered}):
        hits = [
            sum(o.collided for o in covered if o.run.angle == a and o.run.stop_cm == stop) for a in angles
        ]
        least = [
            min(o.clearance for o in covered if o.run.angle == a and o.run.stop_cm == stop) for a in angles
        ]
        rows.append(f"| STOP {stop} cm: collisions | " + " | ".join(map(str, hits)) + " |")
        rows.append(
            f"| STOP {stop} cm: least clearance cm | " + " | ".join(f"{100 * c:.1f}" for c in least) + " |"
        )
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.sonar_stop", description=__doc__.split("\n")[0])
    ap.add_argument("--speeds", type=float, nargs="+", default=list(SPEEDS), help="m/s")
    ap.add_argument("--angles", type=int, nargs="+", default=list(ANGLES), help="degrees to the wall")
    ap.add_argument("--stops", type=int, nargs="+", default=list(STOPS), help="STOP thresholds, cm")
    ap.add_argument("--seeds", type=int, nargs="+", default=list(SEEDS))
    ap.add_argument("--jobs", type=int, default=1, help="worker processes")
    ap.add_argument(
        "--closed-loop",
        action="store_true",
        help="MOVEs on the wheel-speed loop (MODE bit 1), as every front end drives",
    )
    args = ap.parse_args(argv)
    todo = runs(args.speeds, args.angles, args.stops, args.seeds, args.closed_loop)
    started = time.perf_counter()
    if args.jobs > 1:
        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            outcomes = list(pool.map(drive, todo))
    else:
        outcomes = [drive(r) for r in todo]
    print(table(outcomes))
    print()
    print(angle_table(outcomes))
    covered_hits = sum(
        o.collided for o in outcomes if o.run.course == 0 and DESIGN[0] <= o.run.angle <= DESIGN[1]
    )
    glancing = sum(
        o.collided for o in outcomes if o.run.course == 0 and not DESIGN[0] <= o.run.angle <= DESIGN[1]
    )
    print(
        f"\n{len(outcomes)} runs in {time.perf_counter() - started:.0f} s; collisions where the sonar covers "
        f"the travel: {covered_hits} with the wall at {DESIGN[0]}-{DESIGN[1]} degrees (goal 0), {glancing} "
        f"at more glancing angles"
    )
    return 1 if covered_hits else 0


if __name__ == "__main__":
    raise SystemExit(main())
