"""ScanPoints: the scanner's returns in the map frame for goto's watch, on the lockstep simulator.

The robot stands still at the room's start; its estimator starts in a frame of its own (turned, at
the origin) and a provider maps that frame onto the room's, as a localiser would. The returns are
right when the room's walls explain them (the simulator has nothing else in the room's empty world
but its furniture, which the rasterised map has too).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from benchmarks.goto import run_goal, world_with_obstacle
from benchmarks.planner import rasterise

from omnibot.lidar import open_scanner
from omnibot.mapping import compose, inflate, inverse, transform
from omnibot.motion import Pose2D
from omnibot.navigation import ScanPoints, navigation_runtime
from omnibot.navigation.obstacles import EXPLAINED
from omnibot.navigation.session import simulated_client
from omnibot.robot import load_robot
from omnibot.runtime import Runtime
from omnibot.sim import load_world

ROOM_START = Pose2D(1.0, 1.0, 0.0)
ODOM_START = Pose2D(0.0, 0.0, -0.5)
MAP_FROM_ODOM = compose(ROOM_START, inverse(ODOM_START))
BOX = {"shape": "box", "center": [2.0, 1.8], "size": [0.3, 0.3]}
ACROSS = Pose2D(3.0, 2.6, 0.5)


def _explained(points: np.ndarray) -> float:
    """The share of ``points`` a wall of the room's map explains."""
    cmap = inflate(rasterise(load_world("room")), robot_radius=0.01, margin=0.0)
    return float(np.mean([cmap.clearance_at(float(x), float(y)) < EXPLAINED for x, y in points]))


def _still_scan(placed: bool) -> np.ndarray:
    """The points of a ScanPoints after 1 s standing at the room's start, its odometry frame placed
    on the map by a provider (``placed``) or taken for the map's."""
    robot = load_robot("mecanum4")
    with simulated_client(robot, world="room", start=ROOM_START, seed=5) as client:
        scans = open_scanner(None, client.link, robot)
        with navigation_runtime(client, robot, ODOM_START, standstill=0.2) as runtime:

            def provider(rt: Runtime = runtime) -> Pose2D | None:
                est = rt.estimate_now()
                return None if est is None else compose(MAP_FROM_ODOM, est.pose)

            sink = ScanPoints(scans, provider if placed else None)
            runtime.add_sink(sink)
            runtime.run(duration=1.0)
            scans.close()
            points = sink.points()
            assert points is not None and sink.received >= 5
            return points


def test_the_returns_land_on_the_walls_where_the_provider_places_the_odometry() -> None:
    points = _still_scan(placed=True)
    assert len(points) > 200
    assert _explained(points) > 0.95


def test_without_a_provider_the_returns_stay_in_the_odometry_frame() -> None:
    # the same returns (the same seeded run) in the estimator's own frame: placing that frame on
    # the map gives the provider's points
    own, placed = _still_scan(placed=False), _still_scan(placed=True)
    assert own.shape == placed.shape
    assert np.allclose(transform(MAP_FROM_ODOM, own), placed, atol=1e-6)
    assert np.min(np.hypot(*(own - placed).T)) > 0.5


def test_mecanum4_with_its_scanner_sees_the_box_the_map_lacks_and_goes_round(tmp_path: Path) -> None:
    # without the scanner it is blind and stalls against the box (test_goto's blind test, same seed)
    sim_world = world_with_obstacle("room", BOX, tmp_path)
    o = run_goal("mecanum4", ACROSS, seed=3, sim_world=sim_world, scanner=True)
    # arrived by goto's verdict and by the truth, with no contact, after stopping for the box
    assert (o.result.arrived, o.within(), o.contacts) == (True, True, 0), o.result.summary()
    assert o.result.replans >= 1
    marked = np.array(o.result.obstacles)
    # what was marked is the box's near faces (within its half-diagonal and the scanner's noise)
    assert np.all(np.hypot(marked[:, 0] - 2.0, marked[:, 1] - 1.8) < 0.25)
