"""A follower far off its path: what it asks and what the robot does (issues 24/25: a goto leg
planned from a stale pose asked 3.8 m/s to reach a path already behind it).

    python -m benchmarks.off_path [--robots omni4,omni3,mecanum4] [--followers tracker,...]
                                  [--scenarios push,shove,offset,far] [--speed M/S]

Each run: the lockstep simulator (firmware and physics, seed 1) and ``omnibot follow``'s navigator
on a 3 m straight line (heading held), at the robot's own limits unless ``--speed`` caps them:

* ``push``: 2 s after the start a hand pushes the robot sideways (6 N per kg of the robot for 0.3 s,
  the motors on);
* ``shove``: the same, 15 N/kg (far enough for omni3's estimate to leave the path by more than the
  0.5 m a follower chases);
* ``offset``: the estimate starts 0.3 m beside the path's start (a localiser's correction, a run
  started away from the path);
* ``far``: 1 m beside it.

Per run: the path's planned peak speed (the follower's own profile), the largest translation the
follower asked (the VEL) and the body's (the simulator's truth, over 50 ms), the truth's largest
distance from the path, and the outcome (completed, or why not). Deterministic; about a minute of
CPU for the default grid.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass

import numpy as np

from omnibot.control import Follower, Path, make_follower
from omnibot.motion import Pose2D
from omnibot.navigation import FollowRun, Navigator, simulated_client
from omnibot.navigation.session import follower_limits
from omnibot.robot import load_robot
from omnibot.runtime import Cycle

SCENARIOS = {"push": 6.0, "shove": 15.0, "offset": 0.3, "far": 1.0}
"""The push's force in N per kg of the robot (``push``, ``shove``) or how far beside the path the
estimate starts, m (``offset``, ``far``)."""
PUSH_AT = 2.0
"""s after the run's start (its standstill included) the hand pushes."""
LENGTH = 3.0


@dataclass
class Outcome:
    """One run: planned peak, largest asked and true speeds (m/s), largest true distance off (m)."""

    robot: str
    follower: str
    scenario: str
    planned: float
    asked: float
    true: float
    off: float
    completed: bool
    why: str


def line() -> Path:
    """The 3 m straight line along x, heading held, points every 5 cm."""
    n = int(LENGTH / 0.05) + 1
    return Path(np.linspace(0.0, LENGTH, n), np.zeros(n), np.zeros(n))


def follow_line(
    robot_name: str, follower_name: str, scenario: str, speed: float | None = None, seed: int = 1
) -> tuple[FollowRun, Follower]:
    """Follow the line in ``scenario`` (see the module docstring): the run and its follower."""

    robot = load_robot(robot_name)
    path = line()
    beside = SCENARIOS[scenario] if scenario in ("offset", "far") else 0.0
    follower = make_follower(follower_name, follower_limits(robot, speed), rate=100.0)
    with simulated_client(robot, seed=seed, start=Pose2D(0.0, 0.0, 0.0)) as client:
        nav = Navigator(client, robot, start=Pose2D(0.0, -beside, 0.0))
        sim = nav.sim
        assert sim is not None
        pushed: list[float] = []

        def hand(cycle: Cycle) -> None:
            if scenario in ("push", "shove") and not pushed and cycle.now >= PUSH_AT:
                sim.push((0.0, SCENARIOS[scenario] * robot.mass), duration=0.3, motors_off=False)
                pushed.append(cycle.now)

        try:
            nav.prepare(0.5)
            nav.runtime.add_sink(hand)
            return nav.follow(path, follower), follower
        finally:
            nav.close()


def run(robot_name: str, follower_name: str, scenario: str, speed: float | None, seed: int = 1) -> Outcome:
    """Follow the line in ``scenario`` and measure it."""
    trace, follower = follow_line(robot_name, follower_name, scenario, speed, seed)
    path = trace.path
    a = trace.arrays()
    profile = getattr(follower, "profile", None)
    planned = float(profile.speed.max()) if profile is not None else math.nan
    asked = float(np.hypot(a["command"][:, 0], a["command"][:, 1]).max()) if len(a["t"]) else 0.0
    true = off = 0.0
    truth, t = a["truth"], a["t"]
    if len(t) > 5:
        k = 5  # 50 ms
        step = np.hypot(truth[k:, 0] - truth[:-k, 0], truth[k:, 1] - truth[:-k, 1])
        true = float((step / np.maximum(t[k:] - t[:-k], 1e-6)).max())
        off = float(path.nearest(truth[:, :2])[0].max())
    why = trace.failure or ("" if trace.completed else "not done")
    return Outcome(robot_name, follower_name, scenario, planned, asked, true, off, trace.completed, why)


def main(argv: list[str] | None = None) -> None:
    """Print one row per robot, follower and scenario."""

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robots", default="omni4,omni3,mecanum4")
    ap.add_argument("--followers", default="tracker,pure_pursuit,seed002")
    ap.add_argument("--scenarios", default=",".join(SCENARIOS))
    ap.add_argument("--speed", type=float, help="speed cap, m/s (default: each robot's own limit)")
    args = ap.parse_args(argv)
    print(
        "| robot | follower | scenario | limit (m/s) | planned peak | asked at most | body at most | off at most (m) | outcome |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for robot in args.robots.split(","):
        limit = follower_limits(load_robot(robot), args.speed).v_max
        for name in args.followers.split(","):
            for scenario in args.scenarios.split(","):
                o = run(robot, name, scenario, args.speed)
                outcome = "completed" if o.completed else f"NOT COMPLETED: {o.why}"
                print(
                    f"| {robot} | {name} | {scenario} | {limit:.2f} | {o.planned:.2f} | {o.asked:.2f} | "
                    f"{o.true:.2f} | {o.off:.2f} | {outcome} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
