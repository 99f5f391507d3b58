"""Odometry drift on a 100 m mixed drive, in % of the distance driven.

Run: ``python -m benchmarks.odometry_drift`` (``--help`` for options). The simulated robot drives a
pseudo-random 100 m path of straights and arcs (the body turning with the path plus a +-45 degree
swing, so translation and rotation mix) in four legs with a stop between them, speed up to 0.5 m/s
(omni4) or 2 m/s (omni3), after a gyro calibration spin in place (one turn each way, where the
wheels do not slip: the estimator learns the gyro's scale error; ``--no-calibration`` skips it).
The ``tracker`` follower drives on the ``fused`` estimate; every
estimator runs on the same telemetry, and each one's position error against the simulator's ground
truth is taken at the end of every leg (at standstill).

Goals: <= 0.5 % with tracking wheels + gyro (omni3), <= 2 % with driven-wheel encoders + gyro on
carpet. Before the drive, each floor's wheel slip is calibrated (``omnibot calibrate``'s slip runs,
another seed); driven-wheel estimators are reported with and without it.

``--seeds 1,2,3,4`` drives each robot and floor once per seed (the path and the simulator's noise
both follow the seed): the table is the first seed's, and a second one gives the fused estimate's
final position and heading error on every seed, so one draw is not taken for a trend.
"""

from __future__ import annotations

import argparse
import itertools
import math
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np

ROBOTS = {"omni4": (0.5, 1.0), "omni3": (2.0, 2.0)}
"""preset: (speed cap m/s, path scale m)."""
LEGS = 4


SLIP_CORRECTED = ("encoders+gyro", "encoders")
"""Driven-wheel estimators also run with the floor's slip calibration (rows marked "slip-calibrated")."""


def drive(job: tuple[str, str, float, int, bool, bool]) -> dict[str, Any]:
    from benchmarks.tracking import floor_slip
    from omnibot.control import Path, make_follower, wrap
    from omnibot.control.paths.standard import random_path
    from omnibot.estimation import estimator_names, make_estimator
    from omnibot.motion import Pose2D
    from omnibot.navigation import Navigator, simulated_client
    from omnibot.navigation.session import follower_limits
    from omnibot.robot import load_robot

    preset, surface, length, seed, calibrate, slip_calibrate = job
    speed, size = ROBOTS[preset]
    robot = load_robot(preset)
    whole = random_path(length, seed=seed, size=size, heading="mixed")
    cuts = [int(np.searchsorted(whole.s, k * whole.length / LEGS)) for k in range(LEGS)] + [len(whole) - 1]
    legs = [
        Path(whole.x[a : b + 1], whole.y[a : b + 1], whole.theta[a : b + 1])
        for a, b in itertools.pairwise(cuts)
    ]
    names = estimator_names(robot)
    slip = floor_slip(preset, surface) if slip_calibrate else None
    corrected = [f"{n} slip" for n in SLIP_CORRECTED if slip is not None and n in names]
    started = time.perf_counter()
    errors: dict[str, list[float]] = {n: [] for n in [*names, *corrected]}
    heading_errors: dict[str, list[float]] = {n: [] for n in errors}
    travelled = 0.0
    with simulated_client(robot, surface=surface, seed=seed, start=Pose2D(*whole.start)) as client:
        start = Pose2D(*whole.start)
        observers = [make_estimator(n, robot, start) for n in names if n != "fused"]
        for name in corrected:  # the same estimators again, with the floor's slip
            est = make_estimator(name.split()[0], robot, start, slip)
            est.name = name
            observers.append(est)
        # the follower drives on the best estimate: fused, with the floor's slip when calibrated
        nav = Navigator(client, robot, estimator="fused", observers=observers, start=start, slip=slip)
        nav.prepare()
        if calibrate:
            nav.calibrate_gyro()
        last = nav.truth()
        completed = True
        for leg in legs:
            follower = make_follower("tracker", follower_limits(robot, speed))
            run = nav.follow(leg, follower)
            completed &= run.completed
            truth = np.array(run.truth)
            if last is not None and len(truth):
                pts = np.vstack(([last[:2]], truth[:, :2], [nav.truth()[:2]]))  # type: ignore[index]
                travelled += float(np.sum(np.hypot(*np.diff(pts, axis=0).T)))
            last = nav.truth()
            assert last is not None
            for name, errs in errors.items():
                est = nav.estimator if name == "fused" else nav.observers[name]
                e = est.estimate
                errs.append(math.hypot(e.x - last[0], e.y - last[1]))
                heading_errors[name].append(math.degrees(wrap(e.theta - last[2])))
        nav.close()
    return {
        "robot": preset,
        "surface": surface,
        "seed": seed,
        "distance_m": travelled,
        "errors": errors,
        "heading_errors": heading_errors,
        "completed": completed,
        "wall_s": time.perf_counter() - started,
    }


def describe(name: str) -> str:
    return {
        "fused": "fused (best available: tracking wheels if any, gyro + encoders; slip-calibrated "
        "unless --no-slip-calibration)",
        "encoders+gyro slip": "driven-wheel encoders + gyro (fused), slip-calibrated",
        "encoders slip": "driven-wheel encoders only, slip-calibrated",
        "tracking+gyro": "tracking wheels + gyro (fused)",
        "tracking+raw-gyro": "tracking wheels + raw gyro sum",
        "encoders+gyro": "driven-wheel encoders + gyro (fused)",
        "encoders+raw-gyro": "driven-wheel encoders + raw gyro sum",
        "encoders": "driven-wheel encoders only",
        "seed002": "seed 002's (8)-(12) + raw gyro (1)",
    }.get(name, name)


def format_table(results: list[dict[str, Any]]) -> str:
    cols = [(r["robot"], r["surface"]) for r in results]
    names: list[str] = []
    for r in results:
        names += [n for n in r["errors"] if n not in names]
    out = [
        "| estimator | " + " | ".join(f"{rb} {sf}" for rb, sf in cols) + " |",
        "|---|" + "---|" * len(cols),
    ]
    for n in names:
        cells = []
        for r in results:
            e = r["errors"].get(n)
            if not e:
                cells.append("-")
                continue
            final = 100 * e[-1] / r["distance_m"]
            worst = 100 * max(e) / r["distance_m"]
            cells.append(f"{final:.2f} % (max {worst:.2f} %)")
        out.append(f"| {describe(n)} | " + " | ".join(cells) + " |")
    out.append(
        "| heading error at the end (fused) | "
        + " | ".join(f"{r['heading_errors']['fused'][-1]:+.2f} degree" for r in results)
        + " |"
    )
    out.append(
        "| distance driven (truth) | " + " | ".join(f"{r['distance_m']:.1f} m" for r in results) + " |"
    )
    out.append(
        "| all legs completed | " + " | ".join("yes" if r["completed"] else "NO" for r in results) + " |"
    )
    return "\n".join(out)


def goals(results: list[dict[str, Any]]) -> str:
    lines = ["| goal | result |", "|---|---|"]
    for r in results:
        d = r["distance_m"]
        if "tracking+gyro" in r["errors"]:
            v = 100 * r["errors"]["tracking+gyro"][-1] / d
            lines.append(
                f"| tracking wheels + gyro <= 0.5 % ({r['robot']} {r['surface']}) | {v:.2f} % {'met' if v <= 0.5 else 'NOT met'} |"
            )
        for name in ("encoders+gyro", "encoders+gyro slip"):
            if r["surface"] == "carpet" and name in r["errors"]:
                v = 100 * r["errors"][name][-1] / d
                label = "encoders + gyro" + (", slip-calibrated," if name.endswith("slip") else "")
                lines.append(
                    f"| {label} on carpet <= 2 % ({r['robot']}) | {v:.2f} % {'met' if v <= 2 else 'NOT met'} |"
                )
    return "\n".join(lines)


def format_seeds(results: list[dict[str, Any]]) -> str:
    """Per robot and floor, the fused estimate's final position error (% of the distance) and heading
    error (degree) on each seed, and the worst of each."""
    combos = list(dict.fromkeys((r["robot"], r["surface"]) for r in results))
    seeds = list(dict.fromkeys(r["seed"] for r in results))
    out = [
        "| robot | floor | " + " | ".join(f"seed {s}" for s in seeds) + " | worst |",
        "|---|---|" + "---|" * (len(seeds) + 1),
    ]
    for robot, surface in combos:
        runs = {r["seed"]: r for r in results if (r["robot"], r["surface"]) == (robot, surface)}
        cells, position, heading = [], [], []
        for seed in seeds:
            r = runs.get(seed)
            if r is None:
                cells.append("-")
                continue
            position.append(100 * r["errors"]["fused"][-1] / r["distance_m"])
            heading.append(r["heading_errors"]["fused"][-1])
            cells.append(f"{position[-1]:.2f} % / {heading[-1]:+.2f} degree")
        worst = f"{max(position):.2f} % / {max(heading, key=abs):+.2f} degree" if position else "-"
        out.append(f"| {robot} | {surface} | " + " | ".join(cells) + f" | {worst} |")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--robots", default=",".join(ROBOTS))
    p.add_argument("--surfaces", default="wood,carpet")
    p.add_argument("--length", type=float, default=100.0, help="m (default 100)")
    p.add_argument(
        "--seeds",
        default="1",
        help="simulator (and path) seeds, comma-separated (default 1); the table is the first one's",
    )
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument(
        "--no-calibration", action="store_true", help="skip the gyro calibration spin before the drive"
    )
    p.add_argument(
        "--no-slip-calibration",
        dest="slip",
        action="store_false",
        help="no floor slip calibration (the fused estimate then uses uncorrected encoders)",
    )
    args = p.parse_args(argv)
    try:
        seeds = [int(s) for s in args.seeds.split(",")]
    except ValueError:
        p.error(f"--seeds: expected comma-separated integers, got {args.seeds!r}")
    work = [
        (r, s, args.length, seed, not args.no_calibration, args.slip)
        for seed in seeds
        for r in args.robots.split(",")
        for s in args.surfaces.split(",")
    ]
    started = time.perf_counter()
    if args.jobs <= 1:
        results = [drive(j) for j in work]
    else:
        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            results = list(pool.map(drive, work))
    print(
        f"## Odometry drift: {args.length:.0f} m mixed drive in {LEGS} legs, final error (max at a stop), % of distance\n"
    )
    first = [r for r in results if r["seed"] == seeds[0]]
    print(format_table(first))
    print()
    print(goals(first))
    if len(seeds) > 1:
        print("\n## The fused estimate's final error on each seed: position (% of distance) / heading\n")
        print(format_seeds(results))
    print(f"\n({time.perf_counter() - started:.0f} s wall)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
