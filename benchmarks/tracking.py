"""Path tracking: followers x robots x floors x paths, in four suites (``--suites``).

Run: ``python -m benchmarks.tracking`` (``--help`` for subsets; ``--jobs`` processes). Each run is
the real stack in lockstep: follower -> VEL (binary protocol, 115200 baud) -> firmware -> simulated
physics with wheel slip, encoder/gyro noise and tracking-wheel slip; the follower sees only the
robot's own estimate (``fused``), corrected with the floor's slip calibration (driven once per robot
and floor on another seed; ``--no-slip-calibration`` leaves it out); errors are measured against the
simulator's ground truth. Time is against the minimum traversal time of the robot's limits
(time-optimal profile at 100 % of the limits and of the wheels' free-running speed). Goals for
``tracker``: RMS <= 1 cm, max <= 3 cm, time <= 1.25x the minimum (and, on the standard suite, RMS
at least 3x lower than ``seed002`` at no more time).

Suites:

* ``standard``: the six standard shapes with the heading held (seed 002's setting; ``--heading``
  changes it), every follower, seeds 1-3 (a cell: mean RMS and time, worst max); size 1 m for
  omni4 and mecanum4 at up to 0.5 m/s, 3 m for omni3 at up to 2 m/s.
* ``heading``: the curved shapes with the body turning: ``tangent`` (facing the direction of travel)
  and ``swing`` (90 degrees either side, independently of the course), at each robot's top speed.
* ``random``: ``--random-count`` paths per robot, floor and family (``--families``) at the top
  speed: ``random`` smooth random paths (:func:`~omnibot.control.paths.generator.smooth_random_path`,
  swing heading), ``eight`` figure eights (:func:`~omnibot.control.paths.generator.figure_eight_path`)
  and ``closed`` closed free-form curves (:func:`~omnibot.control.paths.generator.closed_curve_path`),
  their heading mode picked by the seed; path K of a family is seeded K and simulated with seed K;
  the worst path of each family is reported, not only the mean.
* ``top``: straight runs long enough to cruise at the top speed on the courses 0, 45 and 90
  degrees (heading held), and one with the body swinging; with the speed each robot's motors
  allow (:mod:`omnibot.control.reach`) and the peak each run reached.

``heading``, ``random`` and ``top`` (each at the top speed) plan within the floor
(``FollowOptions.floor``: the motors' reach for each body twist against the floor's load,
:func:`~omnibot.control.reach.floor_reach`, and the accelerations the wheels' grip leaves beside the
floor's drag, :func:`~omnibot.control.reach.floor_grip`) and their time is against the minimum on
that floor, so what the floor forbids shows as the bound that forbids it instead of a time the robot
cannot make. ``standard`` plans with the robot's own limits (its speed caps are within every
floor's reach; its tables were measured so).

The suites with a turning body spin in place first (``calibrate_gyro``: the gyro's scale error is
learned; a 1 % scale error is 3.6 degrees a turn). The top speeds: omni4 1 m/s (seed 000's
requirement), omni3 5 m/s (seed 002's), mecanum4 0.8 m/s (its preset's limit).

``--seed002-plot FILE.png`` reproduces seed 002's experiment: the S path with and without reduced
overshoot (omni3, wood), plotted, with our tracker for comparison.
"""

from __future__ import annotations

import argparse
import functools
import math
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path as FsPath
from typing import Any

import numpy as np

from omnibot.control import Path


@dataclass(frozen=True)
class Bench:
    """What one preset is asked: the standard suite's speed cap and size, its top speed, the random
    paths' length and least radius of curvature (the closed curves' too), and the figure eights'
    length (an eight needs 16 radii or more)."""

    speed: float
    size: float
    top: float
    random_length: float
    random_radius: float
    eight_length: float


ROBOTS = {
    "omni4": Bench(speed=0.5, size=1.0, top=1.0, random_length=6.0, random_radius=0.4, eight_length=10.0),
    "omni3": Bench(speed=2.0, size=3.0, top=5.0, random_length=15.0, random_radius=1.2, eight_length=25.0),
    "mecanum4": Bench(speed=0.5, size=1.0, top=0.8, random_length=6.0, random_radius=0.4, eight_length=10.0),
}
FOLLOWERS = ("seed002", "pure_pursuit", "tracker")
SUITE_FOLLOWERS = ("seed002", "tracker")
"""The followers of the suites other than ``standard``: seed 002's method and ours side by side."""
SURFACES = ("wood", "carpet")
SUITES = ("standard", "heading", "random", "top")
STANDARD_PATHS = "line,circle,figure_eight,s_curve,square,lemniscate"
HEADING_PATHS = ("circle", "lemniscate")
TOP_COURSES = (0, 45, 90)
FAMILIES = ("random", "eight", "closed")
"""The random suite's path families (the spec's prefix)."""


CALIBRATION_SEED = 1000
"""Simulator seed of the slip calibration drive (not the seed of the runs it is used in)."""


@functools.cache
def floor_slip(preset: str, surface: str) -> Any:
    """The floor's slip coefficients from ``omnibot calibrate``'s slip runs (simulator truth)."""
    from omnibot.navigation.slipcal import simulate_slip_calibration
    from omnibot.robot import load_robot

    speed = min(ROBOTS[preset].speed, 0.8)
    return simulate_slip_calibration(load_robot(preset), surface, seed=CALIBRATION_SEED, speed=speed).params


def top_length(preset: str) -> float:
    """m: a straight run that cruises at the top speed for about half its length (planned with the
    followers' acceleration margin)."""
    from omnibot.control.followers.base import PLAN_MARGIN
    from omnibot.robot import load_robot

    top = ROBOTS[preset].top
    accel = PLAN_MARGIN * load_robot(preset).limits.acceleration_max
    return round(max(2.0, 2.0 * top * top / accel), 1)


def build_path(preset: str, spec: str) -> Path:
    """The path named ``spec`` for ``preset``: ``shape`` or ``shape/heading`` (a standard path),
    ``random-SEED`` (a smooth random path, swing heading), ``eight-SEED`` (a figure eight),
    ``closed-SEED`` (a closed free-form curve), ``line-COURSE`` (a straight run at the
    top speed's length, COURSE degrees from the body's x axis) or ``line-swing``."""
    from omnibot.control import standard_path
    from omnibot.control.paths.generator import closed_curve_path, figure_eight_path, smooth_random_path
    from omnibot.control.paths.standard import SWING

    bench = ROBOTS[preset]
    if spec.startswith("random-"):
        return smooth_random_path(
            int(spec.split("-", 1)[1]),
            length=bench.random_length,
            radius_min=bench.random_radius,
            heading="swing",
        )
    if spec.startswith("eight-"):
        return figure_eight_path(
            int(spec.split("-", 1)[1]), length=bench.eight_length, radius_min=bench.random_radius
        )
    if spec.startswith("closed-"):
        return closed_curve_path(
            int(spec.split("-", 1)[1]), length=bench.random_length, radius_min=bench.random_radius
        )
    if spec.startswith("line-"):
        length = top_length(preset)
        n = int(length / 0.01) + 1
        along = np.linspace(0.0, length, n)
        what = spec.split("-", 1)[1]
        if what == "swing":
            theta = SWING * np.sin(math.pi * along / max(1.0, length / 4))
            return Path(along, np.zeros(n), theta)
        course = math.radians(float(what))
        return Path(along * math.cos(course), along * math.sin(course), np.zeros(n))
    shape, _, heading = spec.partition("/")
    return standard_path(shape, size=bench.size, heading=heading or "fixed")


def odometry_error(run: Any) -> float:
    """m: the largest distance between the robot's own estimate and the ground truth during the run
    (what no follower can correct: it steers the estimate), NaN without truth."""
    a = run.arrays()
    est, truth = a["estimate"], a["truth"]
    if not len(truth):
        return math.nan
    return float(np.max(np.hypot(est[:, 0] - truth[:, 0], est[:, 1] - truth[:, 1])))


def own_cross_track(run: Any) -> float:
    """m: RMS distance of the robot's own estimate from the path (what the follower steers)."""
    est = run.arrays()["estimate"]
    if not len(est):
        return math.nan
    dist, _ = run.path.nearest(est[:, :2])
    return float(np.sqrt(np.mean(dist**2)))


def peak_speed(run: Any) -> float:
    """m/s: the fastest the robot really went (ground truth over 0.1 s), NaN without truth."""
    a = run.arrays()
    truth, t = a["truth"], a["t"]
    if len(truth) < 6:
        return math.nan
    step = 10
    d = np.hypot(truth[step:, 0] - truth[:-step, 0], truth[step:, 1] - truth[:-step, 1])
    dt = np.maximum(t[step:] - t[:-step], 1e-9)
    return float(np.max(d / dt))


Job = tuple[str, str, str, str, str, int, float, bool, bool, tuple[tuple[str, float], ...]]
"""(suite, preset, surface, path spec, follower, seed, speed cap, gyro calibration spin, slip,
the tracker's options)."""


def one_run(job: Job) -> dict[str, Any]:
    from omnibot.navigation import FollowOptions
    from omnibot.navigation.session import simulate_follow
    from omnibot.robot import load_robot

    suite, preset, surface, spec, follower, seed, speed, calibrate, slip, tuning = job
    robot = load_robot(preset)
    path = build_path(preset, spec)
    params = floor_slip(preset, surface) if slip else None
    started = time.perf_counter()
    run, report = simulate_follow(
        robot,
        path,
        FollowOptions(
            follower=follower,
            speed=speed,
            calibrate_gyro=calibrate,
            slip=params,
            follower_options=dict(tuning) if follower == "tracker" else {},
            floor=None if suite == "standard" else surface,
        ),
        surface=surface,
        seed=seed,
    )
    report.update(
        suite=suite,
        path=spec,
        peak_speed_m_s=peak_speed(run),
        odometry_error_m=odometry_error(run),
        own_rms_cross_track_m=own_cross_track(run),
        wall_s=time.perf_counter() - started,
    )
    return report


def suite_jobs(
    suite: str,
    robots: list[str],
    surfaces: list[str],
    followers: list[str],
    seeds: list[int],
    *,
    paths: list[str],
    heading: str,
    random_count: int,
    calibrate: bool,
    slip: bool,
    tuning: tuple[tuple[str, float], ...] = (),
    families: tuple[str, ...] = ("random",),
) -> list[Job]:
    """The runs of one suite."""
    work: list[Job] = []
    for r in robots:
        bench = ROBOTS[r]
        for s in surfaces:
            if suite == "standard":
                specs = [
                    (f"{p}/{heading}" if heading != "fixed" else p, seed) for p in paths for seed in seeds
                ]
                work += [
                    ("standard", r, s, p, f, seed, bench.speed, calibrate, slip, tuning)
                    for p, seed in specs
                    for f in followers
                ]
                continue
            if suite == "heading":
                specs = [(f"{p}/{h}", seeds[0]) for p in HEADING_PATHS for h in ("tangent", "swing")]
            elif suite == "random":
                specs = [(f"{fam}-{k}", k) for fam in families for k in range(1, random_count + 1)]
            else:
                specs = [(f"line-{c}", seeds[0]) for c in TOP_COURSES] + [("line-swing", seeds[0])]
            fs = [f for f in followers if f in SUITE_FOLLOWERS] or followers
            work += [
                (suite, r, s, p, f, seed, bench.top, True, slip, tuning) for p, seed in specs for f in fs
            ]
    return work


def run_jobs(work: list[Job], jobs: int) -> list[dict[str, Any]]:
    """Every run, in ``jobs`` processes."""
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
    """The standard suite's tables: per robot and floor, a cell per path and follower; the summary
    and the goals."""
    out = []
    combos = sorted(
        {(r["robot"], r["surface"]) for r in results}, key=lambda k: (list(ROBOTS).index(k[0]), k[1])
    )
    for robot, surface in combos:
        speed = ROBOTS[robot].speed
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


def _combos(results: list[dict[str, Any]]) -> list[tuple[str, str]]:
    return sorted(
        {(r["robot"], r["surface"]) for r in results}, key=lambda k: (list(ROBOTS).index(k[0]), k[1])
    )


@functools.cache
def profile_peak(preset: str, spec: str, surface: str | None = None) -> float:
    """m/s: the top speed of the path's minimum-time profile at the robot's top speed (100 % of its
    limits, of the wheels' free speed and, given a ``surface``, of that floor's reach): what the
    limits let this path reach at all."""
    from omnibot.control import MotionLimits, time_optimal_profile
    from omnibot.robot import load_robot

    limits = MotionLimits.from_robot(load_robot(preset), ROBOTS[preset].top, surface=surface)
    return float(np.max(time_optimal_profile(build_path(preset, spec), limits, use_path_speed=False).speed))


def format_pairs(results: list[dict[str, Any]], title: str, followers: list[str], speeds: bool) -> str:
    """Per robot and floor, a row per path: seed 002's method and ours side by side (``speeds``: the
    peak speed the limits allow on the path, within the floor's reach, and the peak the tracker
    reached)."""
    out = []
    for robot, surface in _combos(results):
        top = ROBOTS[robot].top
        out.append(
            f"\n### {title}: {robot} on {surface}, up to {top} m/s: RMS / max cross-track (cm) / time vs minimum\n"
        )
        extra = " profile peak (m/s) | reached (m/s) |" if speeds else ""
        out.append(
            "| path | min time (s) |" + extra + " " + " | ".join(followers) + " | odometry error, max (cm) |"
        )
        out.append("|---|---|" + ("---|---|" if speeds else "") + "---|" * (len(followers) + 1))
        rows = [r for r in results if r["robot"] == robot and r["surface"] == surface]
        for spec in dict.fromkeys(r["path"] for r in rows):
            cells = {r["follower"]: r for r in rows if r["path"] == spec}
            first = next(iter(cells.values()))
            speed_cells = ""
            if speeds:
                ours = cells.get("tracker", first)
                peak = profile_peak(robot, spec, surface)
                speed_cells = f" {peak:.2f} | {ours['peak_speed_m_s']:.2f} |"
            out.append(
                f"| {spec} | {first['min_time_s']:.2f} |{speed_cells} "
                + " | ".join(_cell(cells[f]) if f in cells else "-" for f in followers)
                + f" | {100 * cells.get('tracker', first)['odometry_error_m']:.2f} |"
            )
    return "\n".join(out)


FAMILY_TITLES = {
    "random": "Random smooth paths",
    "eight": "Figure eights",
    "closed": "Closed free-form curves",
}


def family(spec: str) -> str:
    """The random suite's family of a path spec (``eight-3`` -> ``eight``)."""
    return spec.split("-", 1)[0]


def format_random(
    results: list[dict[str, Any]], followers: list[str], title: str = "Random smooth paths"
) -> str:
    """Per robot and floor and follower: the mean and the worst path of the random suite."""
    out = [
        f"\n### {title}: the mean and the WORST path (RMS / max cross-track in cm, time vs minimum)\n",
        "| robot | floor | follower | paths | mean RMS | worst RMS | worst max | mean time | worst time | completed "
        "| odometry error, worst max |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for robot, surface in _combos(results):
        for f in followers:
            rs = [
                r for r in results if r["robot"] == robot and r["surface"] == surface and r["follower"] == f
            ]
            if not rs:
                continue
            rms = max(rs, key=lambda r: r["rms_cross_track_m"])
            mx = max(rs, key=lambda r: r["max_cross_track_m"])
            slow = max(rs, key=lambda r: r["time_ratio"])
            out.append(
                f"| {robot} | {surface} | {f} | {len(rs)} | {100 * np.mean([r['rms_cross_track_m'] for r in rs]):.2f} | "
                f"{100 * rms['rms_cross_track_m']:.2f} ({rms['path']}) | {100 * mx['max_cross_track_m']:.2f} ({mx['path']}) | "
                f"{np.mean([r['time_ratio'] for r in rs]):.2f} | {slow['time_ratio']:.2f} ({slow['path']}) | "
                f"{sum(r['completed'] for r in rs)}/{len(rs)} | {100 * max(r['odometry_error_m'] for r in rs):.2f} |"
            )
    return "\n".join(out)


def format_bounds(robots: list[str]) -> str:
    """Each robot's top speed against what its motors allow (:mod:`omnibot.control.reach`)."""
    from omnibot.control import free_wheel_speeds
    from omnibot.control.followers.base import PLAN_WHEEL_USE
    from omnibot.control.reach import speed_bound
    from omnibot.robot import load_robot

    out = [
        "\n### Top speed against the motors (free-running wheel speed at full PWM, nominal battery)\n",
        "| robot | asked (m/s) | wheel free speed (rad/s) | bound, worst - best course (m/s) | "
        f"while turning 2 rad/s | planned on every course ({PLAN_WHEEL_USE:.0%} of the wheels) | on every course? |",
        "|---|---|---|---|---|---|---|",
    ]
    for name in robots:
        robot = load_robot(name)
        top = ROBOTS[name].top
        lo, hi = speed_bound(robot)
        tlo, thi = speed_bound(robot, w=2.0)
        verdict = (
            "yes" if PLAN_WHEEL_USE * lo >= top else f"no: {PLAN_WHEEL_USE * lo:.2f} m/s on the worst course"
        )
        out.append(
            f"| {name} | {top:.2f} | {float(np.min(free_wheel_speeds(robot))):.1f} | {lo:.2f} - {hi:.2f} | "
            f"{tlo:.2f} - {thi:.2f} | {PLAN_WHEEL_USE * lo:.2f} | {verdict} |"
        )
    return "\n".join(out)


TOP_TURN = 2.0
"""rad/s: the turn rate of the floor bound's turning column (:func:`format_floor_bounds`)."""


def format_floor_bounds(robots: list[str], surfaces: list[str]) -> str:
    """Each robot's top speed on each floor: where its motors' torque-speed line meets the floor's
    load at full power (:func:`omnibot.control.reach.floor_reach`), on the top suite's courses and
    the worst one, with no turn and turning at :data:`TOP_TURN` (each wheel's translation and
    rotation parts together)."""
    from omnibot.control import MotionLimits
    from omnibot.navigation.session import PLAN_FLOOR_USE
    from omnibot.robot import load_robot

    cols = " | ".join(f"{c} deg" for c in TOP_COURSES)
    out = [
        "\n### Top speed on each floor (full power against the floor's load; what the suites plan with)\n",
        f"| robot | floor | asked (m/s) | {cols} | worst course | planned on every course ({PLAN_FLOOR_USE:.0%}) "
        f"| turning {TOP_TURN:g} rad/s: {cols} | worst course, turning |",
        "|---|---|---|" + "---|" * len(TOP_COURSES) + "---|---|" + "---|" * len(TOP_COURSES) + "---|",
    ]
    for name in robots:
        robot = load_robot(name)
        for surface in surfaces:
            reach = MotionLimits.from_robot(robot, surface=surface).floor
            assert reach is not None
            table = reach.courses
            step = 360.0 / len(table)
            worst = int(np.flatnonzero(np.isclose(table, min(table), rtol=1e-4))[0])
            at = " | ".join(f"{table[round(float(c) / step) % len(table)]:.2f}" for c in TOP_COURSES)
            turning = [
                min(reach.at(math.radians(k * step), w) for w in (TOP_TURN, -TOP_TURN))
                for k in range(len(table))
            ]
            slowest = int(np.argmin(turning))
            at_turning = " | ".join(
                f"{turning[round(float(c) / step) % len(table)]:.2f}" for c in TOP_COURSES
            )
            out.append(
                f"| {name} | {surface} | {ROBOTS[name].top:.2f} | {at} | {table[worst]:.2f} at {worst * step:.0f} deg | "
                f"{PLAN_FLOOR_USE * table[worst]:.2f} | {at_turning} | {turning[slowest]:.2f} at {slowest * step:.0f} deg |"
            )
    return "\n".join(out)


def suite_goals(results: list[dict[str, Any]], title: str) -> str:
    """The tracker's goals over one suite: how many runs meet each and the worst."""
    ours = [r for r in results if r["follower"] == "tracker"]
    if not ours:
        return ""
    lines = [f"\n### Goals for `tracker`: {title}\n", "| goal | met in | worst |", "|---|---|---|"]
    checks = (
        ("RMS <= 1 cm", "rms_cross_track_m", 0.01, 100.0, "cm"),
        ("max <= 3 cm", "max_cross_track_m", 0.03, 100.0, "cm"),
        ("time <= 1.25x minimum", "time_ratio", 1.25, 1.0, "x"),
    )
    for name, key, bound, scale, unit in checks:
        worst = max(ours, key=lambda r: r[key])
        lines.append(
            f"| {name} | {sum(r[key] <= bound for r in ours)}/{len(ours)} | "
            f"{scale * worst[key]:.2f} {unit} ({worst['robot']} {worst['surface']} {worst['path']}) |"
        )
    own = max(ours, key=lambda r: r["own_rms_cross_track_m"])
    lines.append(
        f"| RMS <= 1 cm against its own estimate | {sum(r['own_rms_cross_track_m'] <= 0.01 for r in ours)}/{len(ours)} | "
        f"{100 * own['own_rms_cross_track_m']:.2f} cm ({own['robot']} {own['surface']} {own['path']}) |"
    )
    lines.append(f"| completed | {sum(r['completed'] for r in ours)}/{len(ours)} | |")
    return "\n".join(lines)


def seed002_experiment(target: FsPath, seed: int = 1, slip: bool = True) -> str:
    """Seed 002's S path on omni3 (wood) with and without reduced overshoot; the plot and a summary."""
    from omnibot.control import standard_path
    from omnibot.navigation import FollowOptions, summary
    from omnibot.navigation.plot import plot_runs
    from omnibot.navigation.session import simulate_follow
    from omnibot.robot import load_robot

    robot = load_robot("omni3")
    speed = ROBOTS["omni3"].speed
    path = standard_path("s_curve", size=ROBOTS["omni3"].size)
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
    p.add_argument("--suites", default=",".join(SUITES), help=f"comma-separated, of {', '.join(SUITES)}")
    p.add_argument("--robots", default=",".join(ROBOTS))
    p.add_argument("--surfaces", default=",".join(SURFACES))
    p.add_argument("--paths", default=STANDARD_PATHS, help="the standard suite's shapes")
    p.add_argument("--followers", default=",".join(FOLLOWERS))
    p.add_argument(
        "--heading", default="fixed", choices=("fixed", "tangent", "swing"), help="the standard suite's"
    )
    p.add_argument("--seeds", default="1,2,3", help="simulator seeds, comma-separated (default 1,2,3)")
    p.add_argument(
        "--random-count", type=int, default=4, help="random paths per robot, floor and family (default 4)"
    )
    p.add_argument(
        "--families",
        default=",".join(FAMILIES),
        help=f"the random suite's path families, comma-separated, of {', '.join(FAMILIES)} (default all)",
    )
    p.add_argument(
        "--tracker-option",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a tracker option (number) for every run, e.g. lead=0.05 (repeatable; for tuning)",
    )
    p.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    p.add_argument(
        "--calibrate-gyro", action="store_true", help="gyro calibration spin before each standard run"
    )
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
    suites = args.suites.split(",")
    robots = args.robots.split(",")
    families = args.families.split(",")
    for name, given, known in (
        ("suite", suites, SUITES),
        ("robot", robots, tuple(ROBOTS)),
        ("family", families, FAMILIES),
    ):
        bad = [g for g in given if g not in known]
        if bad:
            p.error(f"unknown {name} {', '.join(bad)}; expected some of: {', '.join(known)}")
    followers = args.followers.split(",")
    seeds = [int(v) for v in args.seeds.split(",")]
    tuning = []
    for item in args.tracker_option:
        name, sep, value = item.partition("=")
        try:
            tuning.append((name, float(value)))
        except ValueError:
            sep = ""
        if not sep:
            p.error(f"--tracker-option takes NAME=NUMBER, got {item!r}")
    started = time.perf_counter()
    work: list[Job] = []
    for suite in suites:
        work += suite_jobs(
            suite,
            robots,
            args.surfaces.split(","),
            followers,
            seeds,
            paths=args.paths.split(","),
            heading=args.heading,
            random_count=args.random_count,
            calibrate=args.calibrate_gyro,
            slip=args.slip,
            tuning=tuple(tuning),
            families=tuple(families),
        )
    results = run_jobs(work, args.jobs)
    slip = "floor slip calibrated" if args.slip else "no slip calibration"
    pair = [f for f in followers if f in SUITE_FOLLOWERS] or followers
    by_suite = {suite: [r for r in results if r["suite"] == suite] for suite in suites}
    if by_suite.get("standard"):
        spin = ", gyro calibration spin first" if args.calibrate_gyro else ""
        per = f"mean over seeds {args.seeds}, max the worst" if len(seeds) > 1 else f"seed {args.seeds}"
        print(
            f"## Path tracking, standard paths (heading {args.heading}{spin}, {slip}; {per}; {len(by_suite['standard'])} runs)"
        )
        print(format_tables(aggregate(by_suite["standard"]), followers))
    if by_suite.get("heading"):
        rs = by_suite["heading"]
        print(
            f"\n## Heading changing along the path (top speed, gyro calibration spin, {slip}; seed {seeds[0]}; {len(rs)} runs)"
        )
        print(format_pairs(rs, "Turning body", pair, speeds=False))
        print(suite_goals(rs, "heading changing along the path"))
    if by_suite.get("random"):
        rs = by_suite["random"]
        print(
            f"\n## Random paths ({', '.join(families)}; top speed, gyro calibration spin, {slip}; {len(rs)} runs)"
        )
        for fam in families:
            if rows := [r for r in rs if family(r["path"]) == fam]:
                print(format_random(rows, pair, FAMILY_TITLES[fam]))
        print(
            suite_goals(rs, f"{args.random_count} paths per robot, floor and family ({', '.join(families)})")
        )
    if by_suite.get("top"):
        rs = by_suite["top"]
        print(
            f"\n## Top speed (straight runs of {', '.join(f'{r} {top_length(r)} m' for r in robots)}; {slip}; seed {seeds[0]}; {len(rs)} runs)"
        )
        print(format_bounds(robots))
        print(format_floor_bounds(robots, args.surfaces.split(",")))
        print(format_pairs(rs, "Top speed", pair, speeds=True))
        print(suite_goals(rs, "top speed"))
    if args.seed002_plot and "standard" in suites:
        target = FsPath(args.seed002_plot)
        target.parent.mkdir(parents=True, exist_ok=True)
        print("\n### Seed 002's experiment: the S path (omni3, wood)\n")
        print(seed002_experiment(target, seeds[0], args.slip))
        print(f"  plot: {target}")
    print(f"\n({time.perf_counter() - started:.0f} s wall)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
