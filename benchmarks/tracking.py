"""Path tracking: every follower x {omni4 <= 0.5 m/s, omni3 <= 2 m/s} x standard paths x {wood, carpet}.

Run: ``python -m benchmarks.tracking`` (``--help`` for subsets; ``--jobs`` processes). Each run is
the real stack in lockstep: follower -> VEL (binary protocol, 115200 baud) -> firmware -> simulated
physics with wheel slip, encoder/gyro noise and tracking-wheel slip; the follower sees only the
robot's own estimate (``fused``), corrected with the floor's slip calibration (driven once per robot
and floor on another seed; ``--no-slip-calibration`` leaves it out); errors are measured against the
simulator's ground truth. Seeds 1-3 by default: a cell is the mean RMS and time and the worst max.

Paths: the standard set with the heading held (seed 002's setting; ``--heading tangent`` turns the
body with the path, best with ``--calibrate-gyro``: a spin in place before each run teaches the
estimator the gyro's scale error), size 1 m for omni4 and 3 m for omni3 (so omni3 can reach 2 m/s). Time is
against the minimum traversal time of the robot's limits (time-optimal profile, 100 % of the
limits). Goals for ``tracker``: RMS <= 1 cm, max <= 3 cm, time <= 1.25x the minimum, and RMS at
least 3x lower than ``seed002`` at no more time.

``--seed002-plot FILE.png`` reproduces seed 002's experiment: the S path with and without reduced
overshoot (omni3, wood), plotted, with our tracker for comparison.
"""

from __future__ import annotations

import argparse
import functools
import math
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path as FsPath
from typing import Any

import numpy as np

ROBOTS = {"omni4": (0.5, 1.0), "omni3": (2.0, 3.0), "mecanum4": (0.5, 1.0)}
"""preset: (speed cap m/s, path size m)."""
FOLLOWERS = ("seed002", "pure_pursuit", "tracker")
SURFACES = ("wood", "carpet")


CALIBRATION_SEED = 1000
"""Simulator seed of the slip calibration drive (not the seed of the runs it is used in)."""


@functools.cache
def floor_slip(preset: str, surface: str) -> Any:
    """The floor's slip coefficients from ``omnibot calibrate``'s slip runs (simulator truth)."""
    from omnibot.navigation.slipcal import simulate_slip_calibration
    from omnibot.robot.description import load_robot

    speed = min(ROBOTS[preset][0], 0.8)
    return simulate_slip_calibration(load_robot(preset), surface, seed=CALIBRATION_SEED, speed=speed).params


def one_run(job: tuple[str, str, str, str, str, int, bool, bool]) -> dict[str, Any]:
    from omnibot.control.paths.standard import standard_path
    from omnibot.navigation.session import FollowOptions, simulate_follow
    from omnibot.robot.description import load_robot

    preset, surface, shape, follower, heading, seed, calibrate, slip = job
    speed, size = ROBOTS[preset]
    robot = load_robot(preset)
    path = standard_path(shape, size=size, heading=heading)
    params = floor_slip(preset, surface) if slip else None
    started = time.perf_counter()
    _, report = simulate_follow(
        robot,
        path,
        FollowOptions(follower=follower, speed=speed, calibrate_gyro=calibrate, slip=params),
        surface=surface,
        seed=seed,
    )
    report.update(path=shape, heading=heading, wall_s=time.perf_counter() - started)
    return report


def run_matrix(
    robots: list[str],
    surfaces: list[str],
    paths: list[str],
    followers: list[str],
    heading: str,
    seeds: list[int],
    jobs: int,
    calibrate: bool = False,
    slip: bool = True,
) -> list[dict[str, Any]]:
    work = [
        (r, s, p, f, heading, seed, calibrate, slip)
        for seed in seeds
        for r in robots
        for s in surfaces
        for p in paths
        for f in followers
    ]
    if jobs <= 1:
        return [one_run(j) for j in work]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(one_run, work))


def aggregate(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One record per robot, surface, path and follower over the seeds: mean RMS, time and duration,
    worst max, completed only if every seed completed."""
    groups: dict[tuple[str, str, str, str], list[dict[str, Any]]] = {}
    for r in results:
        groups.setdefault((r["robot"], r["surface"], r["path"], r["follower"]), []).append(r)
    out = []
    for runs in groups.values():
        merged = dict(runs[0])
        for key in ("rms_cross_track_m", "time_ratio", "duration_s"):
            merged[key] = float(np.mean([r[key] for r in runs]))
        merged["max_cross_track_m"] = max(r["max_cross_track_m"] for r in runs)
        merged["completed"] = all(r["completed"] for r in runs)
        merged["seeds"] = len(runs)
        out.append(merged)
    return out


def _cell(r: dict[str, Any]) -> str:
    mark = "" if r["completed"] else " (!)"
    return f"{100 * r['rms_cross_track_m']:.2f} / {100 * r['max_cross_track_m']:.2f} / {r['time_ratio']:.2f}{mark}"


def format_tables(results: list[dict[str, Any]], followers: list[str]) -> str:
    out = []
    combos = sorted(
        {(r["robot"], r["surface"]) for r in results}, key=lambda k: (list(ROBOTS).index(k[0]), k[1])
    )
    for robot, surface in combos:
        speed = ROBOTS[robot][0]
        out.append(
            f"\n### {robot} on {surface}, up to {speed} m/s: RMS / max cross-track (cm) / time vs minimum\n"
        )
        out.append("| path | min time (s) | " + " | ".join(followers) + " |")
        out.append("|---|---|" + "---|" * len(followers))
        rows = [r for r in results if r["robot"] == robot and r["surface"] == surface]
        for shape in dict.fromkeys(r["path"] for r in rows):
            cells = {r["follower"]: r for r in rows if r["path"] == shape}
            min_time = next(iter(cells.values()))["min_time_s"]
            out.append(
                f"| {shape} | {min_time:.2f} | "
                + " | ".join(_cell(cells[f]) if f in cells else "-" for f in followers)
                + " |"
            )
    out.append("\n### Summary over all runs\n")
    out.append(
        "| follower | mean RMS (cm) | worst RMS (cm) | worst max (cm) | mean time ratio | worst time ratio | completed |"
    )
    out.append("|---|---|---|---|---|---|---|")
    for f in followers:
        rs = [r for r in results if r["follower"] == f]
        if not rs:
            continue
        rms = [100 * r["rms_cross_track_m"] for r in rs]
        mx = [100 * r["max_cross_track_m"] for r in rs]
        ratio = [r["time_ratio"] for r in rs]
        out.append(
            f"| {f} | {np.mean(rms):.2f} | {max(rms):.2f} | {max(mx):.2f} | {np.mean(ratio):.2f} | {max(ratio):.2f} | "
            f"{sum(r['completed'] for r in rs)}/{len(rs)} |"
        )
    out.append(goals(results))
    return "\n".join(out)


def goals(results: list[dict[str, Any]]) -> str:
    ours = {(r["robot"], r["surface"], r["path"]): r for r in results if r["follower"] == "tracker"}
    seed = {(r["robot"], r["surface"], r["path"]): r for r in results if r["follower"] == "seed002"}
    if not ours:
        return ""
    lines = ["\n### Goals for `tracker`\n", "| goal | met in | worst |", "|---|---|---|"]
    checks = [
        (
            "RMS <= 1 cm",
            lambda r: r["rms_cross_track_m"] <= 0.01,
            lambda r: 100 * r["rms_cross_track_m"],
            "cm",
        ),
        (
            "max <= 3 cm",
            lambda r: r["max_cross_track_m"] <= 0.03,
            lambda r: 100 * r["max_cross_track_m"],
            "cm",
        ),
        ("time <= 1.25x minimum", lambda r: r["time_ratio"] <= 1.25, lambda r: r["time_ratio"], "x"),
    ]
    for name, ok, value, unit in checks:
        met = sum(ok(r) for r in ours.values())
        worst = max(ours.values(), key=value)
        lines.append(
            f"| {name} | {met}/{len(ours)} | {value(worst):.2f} {unit} ({worst['robot']} {worst['surface']} {worst['path']}) |"
        )
    pairs = [(ours[k], seed[k]) for k in ours if k in seed]
    if pairs:
        ratios = [s["rms_cross_track_m"] / max(o["rms_cross_track_m"], 1e-9) for o, s in pairs]
        faster = [o["duration_s"] <= s["duration_s"] * 1.001 for o, s in pairs]
        lowest = int(np.argmin(ratios))
        o = pairs[lowest][0]
        lines.append(
            f"| RMS >= 3x lower than seed002 | {sum(x >= 3 for x in ratios)}/{len(pairs)} | "
            f"{ratios[lowest]:.1f}x ({o['robot']} {o['surface']} {o['path']}); geometric mean {math.exp(np.mean(np.log(ratios))):.1f}x |"
        )
        lines.append(f"| no more time than seed002 | {sum(faster)}/{len(pairs)} | |")
    return "\n".join(lines)


def seed002_experiment(target: FsPath, seed: int = 1, slip: bool = True) -> str:
    """Seed 002's S path on omni3 (wood) with and without reduced overshoot; the plot and a summary."""
    from omnibot.control.paths.standard import standard_path
    from omnibot.navigation.plot import plot_runs
    from omnibot.navigation.session import FollowOptions, simulate_follow, summary
    from omnibot.robot.description import load_robot

    robot = load_robot("omni3")
    speed, size = ROBOTS["omni3"]
    path = standard_path("s_curve", size=size)
    runs, lines = [], []
    labels = (
        "seed 002 without reduced overshoot",
        "seed 002 with reduced overshoot (14)-(17)",
        "tracker (ours)",
    )
    for name, label in zip(("seed002-plain", "seed002", "tracker"), labels, strict=True):
        run, report = simulate_follow(
            robot,
            path,
            FollowOptions(follower=name, speed=speed, slip=floor_slip("omni3", "wood") if slip else None),
            surface="wood",
            seed=seed,
        )
        runs.append(run)
        lines.append(f"  {label:42s} {summary(report)}")
    plot_runs(runs, target, title=f"seed 002's S path, omni3 on wood, up to {speed} m/s", labels=list(labels))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--robots", default=",".join(ROBOTS))
    p.add_argument("--surfaces", default=",".join(SURFACES))
    p.add_argument("--paths", default="line,circle,figure_eight,s_curve,square,lemniscate")
    p.add_argument("--followers", default=",".join(FOLLOWERS))
    p.add_argument("--heading", default="fixed", choices=("fixed", "tangent"))
    p.add_argument("--seeds", default="1,2,3", help="simulator seeds, comma-separated (default 1,2,3)")
    p.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    p.add_argument("--calibrate-gyro", action="store_true", help="gyro calibration spin before each run")
    p.add_argument(
        "--no-slip-calibration",
        dest="slip",
        action="store_false",
        help="uncorrected driven-wheel encoders (default: the floor's slip calibration first)",
    )
    p.add_argument(
        "--seed002-plot", default="out/seed002_s_path.png", help="'' to skip the S-path experiment"
    )
    args = p.parse_args(argv)
    followers = args.followers.split(",")
    seeds = [int(v) for v in args.seeds.split(",")]
    started = time.perf_counter()
    results = run_matrix(
        args.robots.split(","),
        args.surfaces.split(","),
        args.paths.split(","),
        followers,
        args.heading,
        seeds,
        args.jobs,
        args.calibrate_gyro,
        args.slip,
    )
    spin = ", gyro calibration spin first" if args.calibrate_gyro else ""
    spin += ", floor slip calibrated" if args.slip else ", no slip calibration"
    per = f"mean over seeds {args.seeds}, max the worst" if len(seeds) > 1 else f"seed {args.seeds}"
    print(f"## Path tracking (heading {args.heading}{spin}; {per}; {len(results)} runs)")
    print(format_tables(aggregate(results), followers))
    if args.seed002_plot:
        target = FsPath(args.seed002_plot)
        target.parent.mkdir(parents=True, exist_ok=True)
        print("\n### Seed 002's experiment: the S path (omni3, wood)\n")
        print(seed002_experiment(target, seeds[0], args.slip))
        print(f"  plot: {target}")
    print(f"\n({time.perf_counter() - started:.0f} s wall)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
