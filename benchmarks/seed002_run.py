"""Seed 002's headline run: its robot up to 5 m/s on an S path, slowing from 5 to 2 m/s within 1 s
at each change of direction, taught by sampling and repeated with and without its reduced overshoot.

Run: ``python -m benchmarks.seed002_run`` (about 1.5 minutes; ``--plot FILE.png`` draws the speed
profiles, the paths and the path error beside the seed's numbers; ``--quick`` runs only the robot
description that can make the seed's numbers).

What the seed gives (section V): omni3's robot (about 30 kg, 6" omni wheels, Maxon RE 50 on a
22.5 V Li-Po) on painted plywood, an "S" shaped path "where sudden acceleration and deceleration
were required for smooth direction change"; without its algorithm 0 to its top speed of 5 m/s took
2 s of pickup (wheel slip, low friction); with reduced overshoot the pickup improved and the robot
slowed from 5 m/s to 2 m/s in 1 s at each change of direction. It gives no dimensions, so the S here
is the seed's description made concrete: three straight legs of :data:`LEG` m (long enough to reach
5 m/s from 2 m/s and brake again: 2 s of pickup at 2.5 m/s^2 is 5 m, 1 s from 5 to 2 m/s is 3.5 m)
joined by two half circles, left then right, whose radius :data:`RADIUS` is where the seed's 2 m/s
takes the same 3 m/s^2 sideways as its braking (2^2 / 3), the body's heading held (seed 002 keeps
its orientation by a gyro PID).

The run, as the seed does it: the S is taught by pushing the robot along it (motors off, the
simulated hand, 1 m/s) and sampling the robot's own estimate every 10 cm (seed 002's sampling of
straight lines); the taught path is then repeated at up to 5 m/s by ``seed002-plain`` (its method
without reduced overshoot), ``seed002`` (with it: (14)-(17)) and our ``tracker``, on wood, in
lockstep (firmware, physics with wheel slip, noise), errors against the simulator's ground truth.
Each is run on three descriptions of the robot:

* ``omni3``: the preset as it is (acceleration_max 2.5 m/s^2, gear 9.5, rollers' grip 0.75);
* ``omni3+accel``: the seed's accelerations allowed (acceleration_max so that the followers, which
  plan with 70 % of it, brake at 3 m/s^2: 4.29 m/s^2);
* ``omni3+seed``: also what the physics needs for them (:func:`seed_changes`): a gear ratio that
  puts 5 m/s within the 85 % of the wheels' free-running speed followers plan with, and rollers'
  grip enough for the 3 m/s^2 the followers then ask on wood, beside the turn's acceleration they
  ask at once (:func:`grip_needed`).

Each run reports the peak speed, the pickup (time to 4.9 m/s, or to 95 % of its own peak), the
speed through each turn and how long the slow-down into it took, the path error (RMS and largest)
and the overshoot (the largest error in a turn and the 3 m after it: "deviation from actual path").
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass
from pathlib import Path as FsPath
from typing import Any

import numpy as np

from omnibot.control import Path
from omnibot.robot import RobotDescription

TOP = 5.0
"""m/s: seed 002's top speed."""
TURN = 2.0
"""m/s: its speed at a change of direction."""
PICKUP_S = 2.0
"""s: 0 to 5 m/s without its algorithm."""
BRAKE_S = 1.0
"""s: 5 to 2 m/s with it."""
BRAKE = (TOP - TURN) / BRAKE_S
"""m/s^2: the braking the seed reports (3)."""
LEG = 10.0
"""m: each straight leg of the S."""
RADIUS = TURN**2 / BRAKE
"""m: the half circles' radius, where 2 m/s takes 3 m/s^2 sideways (1.33)."""
SAMPLE = 0.10
"""m: the teach-in's sampling (seed 002's straight lines; the seed002 follower's segment)."""
TEACH_SPEED = 1.0
"""m/s: the hand's speed while teaching."""
OVERSHOOT_AFTER = 3.0
"""m: how far past a turn's exit the overshoot is looked for."""
VARIANTS = ("omni3", "omni3+accel", "omni3+seed")
FOLLOWERS = ("seed002-plain", "seed002", "tracker")
LABELS = {
    "seed002-plain": "seed 002 without reduced overshoot",
    "seed002": "seed 002 with reduced overshoot",
    "tracker": "tracker (ours)",
}


def s_path(leg: float = LEG, radius: float = RADIUS, spacing: float = 0.01) -> Path:
    """The S: ``leg`` m along +x, a left half circle of ``radius``, ``leg`` m back, a right half
    circle, ``leg`` m along +x again; heading held at 0, a point every ``spacing`` m."""
    if not (leg > 0 and radius > 0 and spacing > 0):
        raise ValueError(f"the S needs a positive leg, radius and spacing, got {leg}, {radius}, {spacing}")
    n_leg = max(2, math.ceil(leg / spacing) + 1)
    n_arc = max(2, math.ceil(math.pi * radius / spacing) + 1)
    along = np.linspace(0.0, leg, n_leg)
    up = np.linspace(-math.pi / 2, math.pi / 2, n_arc)[1:]
    down = np.linspace(-math.pi / 2, -1.5 * math.pi, n_arc)[1:]
    x = np.concatenate((along, leg + radius * np.cos(up), leg - along[1:], radius * np.cos(down), along[1:]))
    y = np.concatenate(
        (
            np.zeros(n_leg),
            radius + radius * np.sin(up),
            np.full(n_leg - 1, 2 * radius),
            3 * radius + radius * np.sin(down),
            np.full(n_leg - 1, 4 * radius),
        )
    )
    return Path(x, y, np.zeros(len(x)))


def turns(leg: float = LEG, radius: float = RADIUS) -> list[tuple[float, float]]:
    """The S's two changes of direction as (start, end) arc lengths along it, m."""
    arc = math.pi * radius
    return [(leg, leg + arc), (2 * leg + arc, 2 * leg + 2 * arc)]


def with_limits(robot: RobotDescription, **limits: float) -> RobotDescription:
    """``robot`` with some of its limits changed (``acceleration_max=...``)."""
    return robot.model_copy(update={"limits": robot.limits.model_copy(update=limits)})


def with_drive(robot: RobotDescription, gear_ratio: float, grip: float) -> RobotDescription:
    """``robot`` with every motor's gear ratio and every wheel's rollers' grip changed."""
    wheels = tuple(
        w.model_copy(
            update={
                "motor": w.motor.model_copy(update={"gear_ratio": gear_ratio}),
                "rollers": w.rollers.model_copy(update={"grip": grip}),
            }
        )
        for w in robot.wheels
    )
    return robot.model_copy(update={"wheels": wheels})


def grip_needed(robot: RobotDescription, surface: str = "wood", top: float = TOP) -> float:
    """The rollers' grip (the factor on the floor's mu) at which the robot's accelerations (its
    ``acceleration_max`` along any course with half its angular acceleration, what the planner asks
    at once) are held at every speed up to ``top``: :func:`omnibot.control.reach.floor_grip`'s
    fraction reaches 1."""
    from omnibot.control.reach import floor_grip

    def held(grip: float) -> bool:
        variant = with_drive(robot, robot.wheels[0].motor.gear_ratio, grip)
        return min(floor_grip(variant, surface, top)[1]) >= 1.0

    lo, hi = robot.wheels[0].rollers.grip, 4.0
    if held(lo):
        return lo
    if not held(hi):
        raise ValueError(f"no grip up to {hi} holds {robot.limits.acceleration_max} m/s^2 on {surface}")
    for _ in range(12):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if held(mid) else (mid, hi)
    return hi


def gear_needed(robot: RobotDescription, course: float = 0.0, top: float = TOP) -> float:
    """The gear ratio at which ``top`` m/s along ``course`` (rad, body frame) is within the share of
    the wheels' free-running speed followers plan with (``PLAN_WHEEL_USE``)."""
    from omnibot.control.followers.base import PLAN_WHEEL_USE
    from omnibot.control.reach import course_speed_bound

    free = course_speed_bound(robot, course)
    gear = robot.wheels[0].motor.gear_ratio
    # a wheel's free-running speed goes nearly as 1 / gear (the motor's friction is small beside it)
    for _ in range(3):
        need = top / PLAN_WHEEL_USE
        gear *= free / need
        free = course_speed_bound(with_drive(robot, gear, robot.wheels[0].rollers.grip), course)
    return gear


def seed_changes(robot: RobotDescription, surface: str = "wood") -> dict[str, float]:
    """What the description needs for the seed's run: the acceleration limit that plans 3 m/s^2,
    the gear ratio for 5 m/s, the rollers' grip for 3 m/s^2 on ``surface``."""
    from omnibot.control.followers.base import PLAN_MARGIN

    accel = BRAKE / PLAN_MARGIN
    gear = gear_needed(robot)
    # what the followers ask at once: 3 m/s^2 along the course, the turn at 70 % of half its limit
    asked = with_limits(
        with_drive(robot, gear, robot.wheels[0].rollers.grip),
        acceleration_max=BRAKE,
        angular_acceleration_max=PLAN_MARGIN * robot.limits.angular_acceleration_max,
    )
    return {"acceleration_max": accel, "gear_ratio": gear, "grip": grip_needed(asked, surface)}


def grip_table(robot: RobotDescription, gear: float) -> str:
    """Per floor of :mod:`omnibot.floor.surfaces`: the preset's grip (rollers' grip times mu), the
    accelerations it holds (``floor_grip``'s worst fraction of the planned 3 m/s^2 with the turn's),
    the rollers' grip the seed's run needs there and the mu that is."""
    from omnibot.control.followers.base import PLAN_MARGIN
    from omnibot.control.reach import floor_grip
    from omnibot.floor import SURFACES

    asked = with_limits(
        with_drive(robot, gear, robot.wheels[0].rollers.grip),
        acceleration_max=BRAKE,
        angular_acceleration_max=PLAN_MARGIN * robot.limits.angular_acceleration_max,
    )
    grip = robot.wheels[0].rollers.grip
    lines = [
        "| floor | mu | with the preset's rollers (grip x mu) | of the seed's 3 m/s^2 held | rollers' grip needed | mu needed |",
        "|---|---|---|---|---|---|",
    ]
    for name, surface in SURFACES.items():
        held = min(floor_grip(asked, name, TOP)[1])
        need = grip_needed(asked, name)
        lines.append(
            f"| {name} | {surface.mu:.2f} | {grip * surface.mu:.2f} | {100 * held:.0f} % "
            f"({held * BRAKE:.1f} m/s^2) | {need:.2f} | {need * surface.mu:.2f} |"
        )
    return "\n".join(lines)


def variant(name: str, robot: RobotDescription, changes: dict[str, float]) -> RobotDescription:
    """One of :data:`VARIANTS` of ``robot``."""
    if name == "omni3":
        return robot
    faster = with_limits(robot, acceleration_max=changes["acceleration_max"])
    if name == "omni3+accel":
        return faster
    if name == "omni3+seed":
        return with_drive(faster, changes["gear_ratio"], changes["grip"])
    raise ValueError(f"no variant {name!r}: {', '.join(VARIANTS)}")


def speeds(t: np.ndarray, xy: np.ndarray, window: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Speed over ``window`` s (central differences) at the middle of each window: (times, m/s)."""
    if len(t) < 3:
        return np.zeros(0), np.zeros(0)
    dt = float(np.median(np.diff(t)))
    step = max(1, round(window / dt))
    if len(t) <= step:
        return np.zeros(0), np.zeros(0)
    d = np.hypot(xy[step:, 0] - xy[:-step, 0], xy[step:, 1] - xy[:-step, 1])
    span = np.maximum(t[step:] - t[:-step], 1e-9)
    return 0.5 * (t[step:] + t[:-step]), d / span


@dataclass
class Metrics:
    """What one run showed (times from its start, s; speeds m/s; errors m)."""

    peak: float
    pickup_to_top: float | None
    """s from the start to :data:`TOP` - 0.1 m/s, None if never reached."""
    pickup_to_peak: float
    """s from the start to 95 % of the run's own peak."""
    turn_speed: list[float]
    """the least speed in each turn."""
    brake: list[tuple[float, float, float]]
    """per turn: (speed before, speed in the turn, s it took): from the last 98 % of the leg's
    peak before the turn to the first point within 0.1 m/s of the turn's least speed."""
    rms: float
    max_error: float
    overshoot: float
    """the largest error in a turn or the :data:`OVERSHOOT_AFTER` m after it."""
    duration: float


def metrics(
    path: Path, t: np.ndarray, xy: np.ndarray, bends: list[tuple[float, float]] | None = None
) -> Metrics:
    """The run's numbers from its times and driven positions (path frame)."""
    bends = turns() if bends is None else bends
    if len(t) < 3:
        raise ValueError("a run of fewer than 3 samples has no speeds")
    tv, v = speeds(t, xy)
    t0 = float(t[0])
    err, arc = path.nearest(xy)
    _, arc_v = path.nearest(0.5 * (xy[: len(v)] + xy[len(xy) - len(v) :]))
    peak = float(v.max())
    fast = np.nonzero(v >= TOP - 0.1)[0]
    pickup_top = float(tv[fast[0]] - t0) if len(fast) else None
    pickup_peak = float(tv[np.nonzero(v >= 0.95 * peak)[0][0]] - t0)
    turn_speed, brake = [], []
    leg_start = 0.0
    for start, end in bends:
        inside = (arc_v >= start) & (arc_v <= end)
        low = float(v[inside].min()) if inside.any() else math.nan
        turn_speed.append(low)
        before = np.nonzero((arc_v >= leg_start) & (arc_v < start))[0]
        if len(before) and inside.any():
            hi = float(v[before].max())
            k_hi = before[np.nonzero(v[before] >= 0.98 * hi)[0][-1]]
            after = np.nonzero((np.arange(len(v)) > k_hi) & (v <= low + 0.1))[0]
            took = float(tv[after[0]] - tv[k_hi]) if len(after) else math.nan
            brake.append((hi, low, took))
        else:
            brake.append((math.nan, low, math.nan))
        leg_start = end
    near = np.zeros(len(err), dtype=bool)
    for start, end in bends:
        near |= (arc >= start) & (arc <= end + OVERSHOOT_AFTER)
    return Metrics(
        peak=peak,
        pickup_to_top=pickup_top,
        pickup_to_peak=pickup_peak,
        turn_speed=turn_speed,
        brake=brake,
        rms=float(np.sqrt(np.mean(err**2))),
        max_error=float(err.max()),
        overshoot=float(err[near].max()) if near.any() else math.nan,
        duration=float(t[-1] - t0),
    )


def taught_path(robot: RobotDescription, seed: int = 1) -> Path:
    """The S taught as seed 002 teaches: pushed by hand (motors off) at :data:`TEACH_SPEED`, the
    robot's own estimate sampled every :data:`SAMPLE` m, heading stored."""
    from omnibot.control import PathRecorder
    from omnibot.motion import Pose2D
    from omnibot.navigation import simulated_client, teach

    shape = s_path()
    with simulated_client(robot, surface="wood", seed=seed, start=Pose2D(*shape.start)) as client:
        result = teach(
            client, robot, PathRecorder("distance", SAMPLE), mode="push", shape=shape, speed=TEACH_SPEED
        )
    if result.path is None:
        raise RuntimeError("the teach-in recorded nothing")
    return result.path


def one_run(
    robot: RobotDescription, path: Path, follower: str, seed: int
) -> tuple[Any, dict[str, Any], Metrics]:
    """Repeat ``path`` with ``follower`` at up to 5 m/s on wood; the run, its report, its metrics."""
    from omnibot.navigation import FollowOptions
    from omnibot.navigation.session import simulate_follow

    run, report = simulate_follow(
        robot, path, FollowOptions(follower=follower, speed=TOP), surface="wood", seed=seed
    )
    a = run.arrays()
    return run, report, metrics(path, a["t"], a["truth"][:, :2])


def planned(robot: RobotDescription, path: Path, follower: str = "tracker") -> tuple[np.ndarray, np.ndarray]:
    """The followers' time-optimal plan for ``path`` at up to 5 m/s: (times, speeds)."""
    from omnibot.control import make_follower
    from omnibot.navigation.session import follower_limits

    profile = make_follower(follower, follower_limits(robot, TOP)).plan(path)
    ds = np.gradient(profile.s)
    dt = np.maximum(np.gradient(profile.t), 1e-9)
    return profile.t, ds / dt


def _fmt(x: float | None, digits: int = 2) -> str:
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{digits}f}"


def table(rows: list[tuple[str, str, dict[str, Any], Metrics]], plans: dict[str, tuple[float, float]]) -> str:
    """The results as a Markdown table, the seed's row first."""
    head = (
        "| robot | follower | planned peak / turn (m/s) | peak (m/s) | pickup to 4.9 m/s (s) | "
        "to 95 % of peak (s) | into turn 1 (m/s in s) | into turn 2 | RMS / max error (cm) | "
        "overshoot (cm) | time (s) |"
    )
    lines = [head, "|" + "---|" * 11]
    lines.append(
        f"| seed 002 (its text) | with reduced overshoot | | {TOP:.1f} | {PICKUP_S:.1f} (without it) | | "
        f"{TOP:.0f} -> {TURN:.0f} in {BRAKE_S:.0f} | {TOP:.0f} -> {TURN:.0f} in {BRAKE_S:.0f} | not given | not given | |"
    )
    for name, follower, report, m in rows:
        brakes = [f"{_fmt(hi, 1)} -> {_fmt(lo, 1)} in {_fmt(took)}" for hi, lo, took in m.brake]
        peak_plan, turn_plan = plans[name]
        lines.append(
            f"| {name} | {follower} | {peak_plan:.2f} / {turn_plan:.2f} | {m.peak:.2f} | {_fmt(m.pickup_to_top)} | "
            f"{m.pickup_to_peak:.2f} | {brakes[0]} | {brakes[1]} | {100 * m.rms:.1f} / {100 * m.max_error:.1f} | "
            f"{100 * m.overshoot:.1f} | {m.duration:.1f}{'' if report.get('completed', True) else ' (not completed)'} |"
        )
    return "\n".join(lines)


def plot(
    target: FsPath,
    runs: list[tuple[str, str, Any]],
    plans: dict[str, tuple[np.ndarray, np.ndarray]],
) -> None:
    """Speed against time (planned and driven) beside the seed's numbers, the driven paths, the error
    along the path; one row per robot description."""
    from omnibot.navigation.metrics import error_along_path
    from omnibot.plots import new_figure, save

    names = list(dict.fromkeys(name for name, _, _ in runs))
    fig, axes = new_figure(len(names), 3, size=(17.0, 4.6 * len(names)))
    shape = runs[0][2].path
    for row, name in enumerate(names):
        ax_v, ax_xy, ax_e = axes[row]
        tp, vp = plans[name]
        ax_v.plot(tp, vp, color="0.3", lw=2.5, alpha=0.4, label="planned (tracker's profile)")
        ax_xy.plot(shape.x, shape.y, color="0.2", lw=2.5, alpha=0.35, label="taught S")
        for k, follower in enumerate(FOLLOWERS):
            run = next((r for n, f, r in runs if n == name and f == follower), None)
            if run is None:
                continue
            a = run.arrays()
            tv, v = speeds(a["t"], a["truth"][:, :2])
            ax_v.plot(tv - a["t"][0], v, color=f"C{k}", lw=1.2, label=LABELS[follower])
            ax_xy.plot(a["truth"][:, 0], a["truth"][:, 1], color=f"C{k}", lw=1.2, label=LABELS[follower])
            s, d = error_along_path(run)
            ax_e.plot(s, 100 * d, color=f"C{k}", lw=1.0, label=LABELS[follower])
        # the seed's numbers: 0 -> 5 m/s in 2 s; 5 -> 2 m/s in 1 s at a change of direction (drawn
        # where the plan first brakes from its peak)
        ax_v.plot([0.0, PICKUP_S], [0.0, TOP], "k:", lw=1.5, label="seed 002: 0 -> 5 m/s in 2 s")
        ax_v.axhline(TOP, color="k", lw=0.6, ls="--")
        ax_v.axhline(TURN, color="k", lw=0.6, ls="--")
        top = int(np.argmax(vp))
        braking = np.nonzero(vp[top:] < 0.98 * vp[top])[0]
        t_brake = float(tp[top + braking[0]]) if len(braking) else 0.0
        ax_v.plot(
            [t_brake, t_brake + BRAKE_S],
            [TOP, TURN],
            "k-",
            lw=3,
            alpha=0.5,
            label="seed 002: 5 -> 2 m/s in 1 s",
        )
        ax_v.set_title(f"{name}: speed (ground truth over 0.1 s)")
        ax_v.set_xlabel("time (s)")
        ax_v.set_ylabel("m/s")
        ax_v.legend(fontsize=7, loc="lower center")
        ax_xy.set_aspect("equal")
        ax_xy.set_title(f"{name}: repeated (ground truth)")
        ax_xy.legend(fontsize=7, loc="center")
        for start, end in turns():
            ax_e.axvspan(start, end, color="0.85", lw=0)
        ax_e.set_title(f"{name}: error from the taught path (turns shaded)")
        ax_e.set_xlabel("along the path (m)")
        ax_e.set_ylabel("cm")
        ax_e.legend(fontsize=7)
    save(fig, str(target))


def main(argv: list[str] | None = None) -> int:
    """Teach the S, repeat it with each follower on each description; print the tables."""
    from omnibot.robot import load_robot

    p = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    p.add_argument("--seed", type=int, default=1, help="simulator seed (teach and repeat)")
    p.add_argument("--plot", type=FsPath, default=None, help="write the figure here (PNG)")
    p.add_argument(
        "--quick", action="store_true", help="only the description that can make the seed's numbers"
    )
    args = p.parse_args(argv)
    started = time.perf_counter()
    robot = load_robot("omni3")
    changes = seed_changes(robot)
    print(
        "description changes for the seed's run: acceleration_max {acceleration_max:.2f} m/s^2 (preset {a:.2f}), "
        "gear ratio {gear_ratio:.2f} (preset {g:.2f}), rollers' grip {grip:.2f} (preset {r:.2f}; wood mu {mu:.2f})".format(
            **changes,
            a=robot.limits.acceleration_max,
            g=robot.wheels[0].motor.gear_ratio,
            r=robot.wheels[0].rollers.grip,
            mu=_wood_mu(),
        )
    )
    print(grip_table(robot, changes["gear_ratio"]))
    path = taught_path(robot, args.seed)
    shape = s_path()
    gap, _ = shape.nearest(np.column_stack((path.x, path.y)))
    print(
        f"taught: {len(path)} samples every {SAMPLE:.2f} m, {path.length:.2f} m "
        f"(the S {shape.length:.2f} m), at most {100 * gap.max():.1f} cm from it"
    )
    names = ["omni3+seed"] if args.quick else list(VARIANTS)
    rows, runs, plans, profile = [], [], {}, {}
    for name in names:
        described = variant(name, robot, changes)
        tp, vp = planned(described, path)
        profile[name] = (tp, vp)
        arc = np.interp(tp, tp, np.cumsum(np.concatenate(([0.0], np.diff(tp) * vp[1:]))))
        first = turns()[0]
        in_turn = (arc >= first[0]) & (arc <= first[1])
        plans[name] = (float(vp.max()), float(vp[in_turn].min()) if in_turn.any() else math.nan)
        for follower in FOLLOWERS:
            run, report, m = one_run(described, path, follower, args.seed)
            rows.append((name, follower, report, m))
            runs.append((name, follower, run))
    print(table(rows, plans))
    if args.plot is not None:
        plot(args.plot, runs, profile)
        print(f"plot: {args.plot}")
    print(f"({time.perf_counter() - started:.0f} s)")
    return 0


def _wood_mu() -> float:
    from omnibot.floor import get_surface

    return get_surface("wood").mu


if __name__ == "__main__":
    raise SystemExit(main())
