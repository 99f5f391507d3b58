"""One goto leg on the lockstep simulator: what ends it, and the robot's state when it hands back.

omni3 (30 kg, 2.5 m/s^2 on its motors, 0.32 m/s^2 coasting) is the robot where it matters: a leg an
obstacle ends at speed must leave the robot at rest where the pose says it is, not coasting on
from a pose read before it stopped (what drove it into the cabinet and the box on benchmarks.goto
seed 18 through ``omnibot goto``).
"""

from __future__ import annotations

import math

import numpy as np
from benchmarks.planner import rasterise

from omnibot.mapping import inflate, plan_path
from omnibot.motion import Pose2D
from omnibot.navigation.goal import GotoOptions
from omnibot.navigation.goto import navigation_runtime
from omnibot.navigation.leg import Leg
from omnibot.navigation.session import simulated_client
from omnibot.robot import load_robot
from omnibot.runtime import StallWatch
from omnibot.sim import load_world
from omnibot.transport import find_simulator

START = Pose2D(1.0, 2.0, 0.0)
GOAL = Pose2D(4.3, 2.0, 0.0)
"""Straight across the room, clear of the cabinet and the bin."""
SEEN_AT = 1.0
"""m/s: the robot's speed when the fake box comes into view, 1.2 m ahead on the path."""


def test_a_leg_an_obstacle_ends_at_speed_hands_back_a_robot_at_rest_where_the_pose_says() -> None:
    robot = load_robot("omni3")
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
                if not seen and v < SEEN_AT:
                    return None
                if not seen:
                    seen.append((p.x, v))
                return np.array([[seen[0][0] + 1.2, 2.0], [seen[0][0] + 1.2, 2.05]])

            est = runtime.estimate_now()
            assert est is not None
            leg = Leg(robot, cmap, plan, START, est.pose, runtime.period, "goal", opts, pose, scan)
            stalls = StallWatch(runtime, robot, truth=sim)
            try:
                ended = leg.run(runtime, math.inf, stalls)
            finally:
                stalls.close()
            assert ended == "obstacle", leg.why
            here = pose()
        truth, twist = sim.pose, sim.twist
        x0, v0 = seen[0]
        # at rest when the leg hands back (cut, omni3 coasts on at 0.32 m/s^2: ~0.8 m/s after the settle)
        assert math.hypot(twist.vx, twist.vy) < 0.02 and abs(twist.w) < math.radians(2)
        # braked on the motors: within the braking distance at the robot's acceleration from the speed
        # seen (plus a scan period's travel), not the metres a coast takes
        assert truth.x - x0 < v0 * v0 / (2 * robot.limits.acceleration_max) + 0.1 * v0 + 0.05
        # the pose handed back is where the robot stands (the estimate followed it to rest)
        assert here is not None and math.hypot(here.x - truth.x, here.y - truth.y) < 0.02
        assert not sim.collisions
