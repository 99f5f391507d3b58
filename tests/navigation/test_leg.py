"""One goto leg on the lockstep simulator: what ends it, and the robot's state when it hands back.

omni3 (30 kg, 2.5 m/s^2 on its motors, 0.32 m/s^2 coasting) is the robot where it matters: a leg an
obstacle ends at speed must leave the robot at rest where the pose says it is, not coasting on
from a pose read before it stopped (what drove it into the cabinet and the box on benchmarks.goto
seed 18 through ``omnibot goto``); it is braked on its motors. omni4, which its friction stops as
soon, has its motors cut, and is handed back at rest all the same.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from benchmarks.planner import rasterise

from omnibot.mapping import inflate, plan_path
from omnibot.motion import Pose2D
from omnibot.navigation.goal import GotoOptions
from omnibot.navigation.goto import navigation_runtime
from omnibot.navigation.leg import Leg
from omnibot.navigation.obstacles import REACTION
from omnibot.navigation.session import simulated_client
from omnibot.robot import load_robot
from omnibot.runtime import Cycle, StallWatch
from omnibot.sim import load_world
from omnibot.transport import find_simulator

START = Pose2D(1.0, 2.0, 0.0)
GOAL = Pose2D(4.3, 2.0, 0.0)
"""Straight across the room, clear of the cabinet and the bin."""


@pytest.mark.parametrize(
    ("name", "seen_at", "braked"),
    [("omni3", 1.0, True), ("omni4", 0.6, False)],
)
def test_a_leg_an_obstacle_ends_at_speed_hands_back_a_robot_at_rest_where_the_pose_says(
    name: str, seen_at: float, braked: bool
) -> None:
    # seen_at: the speed (m/s) when the fake box comes into view, 1.2 m ahead on the path; braked:
    # on the motors (omni3's coast is long) or cut (omni4's friction stops it as soon)
    robot = load_robot(name)
    grid = rasterise(load_world("room"))
    opts = GotoOptions()
    cmap = inflate(grid, robot_radius=robot.footprint.bounding_radius, margin=opts.margin)
    plan = plan_path(cmap, START, GOAL)
    with simulated_client(robot, world="room", start=START, seed=1) as client:
        sim = find_simulator(client.link)
        assert sim is not None
        with navigation_runtime(client, robot, START) as runtime:
            seen: list[tuple[float, float]] = []  # the truth's x and speed when the box came into view

            def pose() -> Pose2D | None:
                est = runtime.estimate_now()
                return None if est is None else est.pose

            def scan() -> np.ndarray | None:
                # a box the map lacks, in view once the robot is at speed (the test's stand-in scan)
                p, v = sim.pose, math.hypot(sim.twist.vx, sim.twist.vy)
                if not seen and v < seen_at:
                    return None
                if not seen:
                    seen.append((p.x, v))
                return np.array([[seen[0][0] + 1.2, 2.0], [seen[0][0] + 1.2, 2.05]])

            est = runtime.estimate_now()
            assert est is not None
            leg = Leg(robot, cmap, plan, START, est.pose, runtime.period, "goal", opts, pose, scan)
            stalls = StallWatch(runtime, robot, truth=sim)
            after: list[bool] = []  # a VEL sent in each cycle after the follower ended
            ended_at: list[tuple[float, float]] = []  # the truth's x and speed when it ended

            def sends(cycle: Cycle) -> None:
                if leg.source.finished:
                    after.append(cycle.sent is not None)
                    if not ended_at:
                        ended_at.append((sim.pose.x, math.hypot(sim.twist.vx, sim.twist.vy)))

            runtime.add_sink(sends)
            try:
                ended = leg.run(runtime, math.inf, stalls)
            finally:
                stalls.close()
            assert ended == "obstacle", leg.why
            assert any(after) is braked and all(after[: int(0.2 / runtime.period)]) is braked
            here = pose()
        truth, twist = sim.pose, sim.twist
        x0, v0 = ended_at[0]
        assert v0 > 0.8 * seen[0][1]
        # at rest when the leg hands back (cut, omni3 coasts on at 0.32 m/s^2: ~0.8 m/s after the settle)
        assert math.hypot(twist.vx, twist.vy) < 0.02 and abs(twist.w) < math.radians(2)
        # stopped within the reach the watch budgets from the speed at the leg's end (REACTION s until
        # the stop acts, then v^2/2a) at the deceleration used: the motors' acceleration, or the
        # coast's where they were cut; not the metres omni3's coast takes (1.6 m from 1 m/s)
        decel = robot.limits.acceleration_max if braked else robot.stop_deceleration
        assert truth.x - x0 < v0 * REACTION + v0 * v0 / (2 * decel)
        # the pose handed back is where the robot stands (the estimate followed it to rest)
        assert here is not None and math.hypot(here.x - truth.x, here.y - truth.y) < 0.02
        assert not sim.collisions
