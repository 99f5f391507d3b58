"""goto on the lockstep simulator: seeded goals in the room, obstacles the map lacks, failures.

The map is the room world rasterised (benchmarks.planner.rasterise); the robot stands at the
world's start with its estimator started there, so the map frame is the world's. Arrival is checked
against the simulator's truth, and contacts are its collision events.
"""

from __future__ import annotations

import functools
import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from benchmarks.goto import goals, run_goal, world_with_obstacle

from omnibot.client import Telemetry
from omnibot.control import Path as Route
from omnibot.errors import BlockedError, ConfigError, OffMapError
from omnibot.mapping import OccupancyGrid, PlannedPath, compose, inflate, inverse
from omnibot.mapping.score import world_grid as rasterise
from omnibot.motion import Pose2D
from omnibot.navigation.goal import GotoOptions, GotoResult, PoseProvider
from omnibot.navigation.goto import go_to, goto, navigation_runtime
from omnibot.navigation.obstacles import ObstacleWatch, stopping_reach
from omnibot.navigation.planned import mark, planned_path
from omnibot.navigation.session import simulated_client
from omnibot.robot import load_robot
from omnibot.runtime import Cycle, Runtime
from omnibot.sim import load_world
from omnibot.transport import find_simulator

ROOM_START = Pose2D(1.0, 1.0, 0.0)
BOX = {"shape": "box", "center": [2.0, 1.8], "size": [0.3, 0.3]}
"""In the way of the straight run from the start to ACROSS; not on the map."""
ACROSS = Pose2D(3.0, 2.6, 0.5)


def truth_error(outcome_truth: Pose2D, goal: Pose2D) -> tuple[float, float]:
    d = math.hypot(outcome_truth.x - goal.x, outcome_truth.y - goal.y)
    return d, abs((outcome_truth.theta - goal.theta + math.pi) % (2 * math.pi) - math.pi)


@pytest.mark.parametrize("robot", ["omni4", "omni3", "mecanum4"])
def test_seeded_goals_in_the_room_are_reached_without_contact(robot: str) -> None:
    for k, goal in enumerate(goals(robot, 3, seed=7)):
        o = run_goal(robot, goal, seed=k + 1)
        assert o.result.arrived, o.result.summary()
        assert o.contacts == 0
        assert o.within(0.05, math.radians(5)), (o.error, math.degrees(o.heading_error))
        assert o.result.error <= 0.05 and o.result.heading_error <= math.radians(5)
        assert o.result.plans and o.result.plans[0].planner == "grid"


def test_a_box_the_map_lacks_is_seen_by_the_sonar_stopped_for_and_gone_round(tmp_path: Path) -> None:
    sim_world = world_with_obstacle("room", BOX, tmp_path)
    o = run_goal("omni4", ACROSS, seed=3, sim_world=sim_world)
    assert o.result.arrived, o.result.summary()
    assert o.contacts == 0
    assert o.within()
    assert o.result.replans >= 1
    marked = np.array(o.result.obstacles)
    # the marks lie on the box's near side (the sonar's arc, within its cone's width)
    assert np.all(np.hypot(marked[:, 0] - 2.0, marked[:, 1] - 1.8) < 0.45)
    assert (
        o.result.grid is not None
        and (o.result.grid.data >= 65).sum() > (rasterise(load_world("room")).data >= 65).sum()
    )
    # the plan after the stop keeps the box's marks out of its inflated corridor
    last = o.result.plans[-1]
    assert float(np.min(np.hypot(*(_dense(last)[:, None, :] - marked[None, :, :]).transpose(2, 0, 1)))) > 0.14


def _dense(plan: PlannedPath, step: float = 0.02) -> np.ndarray:
    pts = [plan.waypoints[:1]]
    for a, b in itertools.pairwise(plan.waypoints):
        n = max(1, math.ceil(float(np.hypot(*(b - a))) / step))
        pts.append(a + (b - a) * (np.arange(1, n + 1)[:, None] / n))
    return np.vstack(pts)


def test_a_scan_source_stops_a_robot_without_sonars_for_what_the_map_lacks(tmp_path: Path) -> None:
    robot = load_robot("mecanum4")
    sim_world = world_with_obstacle("room", BOX, tmp_path)
    grid = rasterise(load_world("room"))
    with simulated_client(robot, world=sim_world, start=ROOM_START, seed=2) as client:
        sim = find_simulator(client.link)
        assert sim is not None
        angles = np.radians(np.arange(0, 360, 2.0))

        def scan() -> np.ndarray:
            # a 180-ray scanner at the body's centre from the simulator's truth (the test's stand-in)
            p = sim.pose
            r = sim.world.raycast((p.x, p.y), p.theta + angles, 4.0)
            ok = np.isfinite(r)
            a = p.theta + angles[ok]
            return np.column_stack((p.x + r[ok] * np.cos(a), p.y + r[ok] * np.sin(a)))

        result = goto(client, robot, grid, ACROSS, ROOM_START, pose=None, scan=scan)
        assert result.arrived, result.summary()
        assert result.replans >= 1
        assert not sim.collisions
        p = sim.pose
        assert truth_error(Pose2D(p.x, p.y, p.theta), ACROSS)[0] <= 0.05


def test_the_pose_comes_from_the_provider_in_the_map_frame() -> None:
    # the estimator starts at the origin of its own (odometry) frame, turned; the provider maps
    # it into the map frame (as a localiser would): the plan is moved into the estimate's frame
    robot = load_robot("omni3")
    grid = rasterise(load_world("room"))
    odom_start = Pose2D(0.0, 0.0, -0.5)
    map_from_odom = compose(ROOM_START, inverse(odom_start))
    goal = Pose2D(3.5, 2.8, 2.0)
    with simulated_client(robot, world="room", start=ROOM_START, seed=4) as client:
        sim = find_simulator(client.link)
        assert sim is not None
        seen: list[Pose2D] = []

        def localiser(runtime: Runtime) -> PoseProvider:
            def provider() -> Pose2D | None:
                est = runtime.estimate_now()
                if est is None:
                    return None
                seen.append(est.pose)
                return compose(map_from_odom, est.pose)

            return provider

        result = goto(client, robot, grid, goal, odom_start, pose_from=localiser)
        assert result.arrived, result.summary()
        p = sim.pose
        d, h = truth_error(Pose2D(p.x, p.y, p.theta), goal)
        assert d <= 0.05 and h <= math.radians(5)
        assert not sim.collisions
        # the estimate's own frame is not the map's
        assert math.hypot(seen[-1].x - goal.x, seen[-1].y - goal.y) > 0.5


def test_a_goal_in_a_wall_or_off_the_map_is_refused_before_anything_moves() -> None:
    robot = load_robot("omni4")
    grid = rasterise(load_world("room"))
    with simulated_client(robot, world="room", start=ROOM_START, seed=1) as client:
        sim = find_simulator(client.link)
        assert sim is not None
        with pytest.raises(BlockedError, match=r"goal \(1.20, 3.00\) is inside a wall or obstacle"):
            goto(client, robot, grid, Pose2D(1.2, 3.0, 0.0), ROOM_START, standstill=0.2)  # the bin
        with pytest.raises(OffMapError, match=r"goal \(7.00, 1.00\) is off the map"):
            goto(client, robot, grid, Pose2D(7.0, 1.0, 0.0), ROOM_START, standstill=0.2)
        assert math.hypot(sim.pose.x - 1.0, sim.pose.y - 1.0) < 0.01
    assert issubclass(BlockedError, ConfigError) and issubclass(OffMapError, ConfigError)  # exit 2


def test_a_map_with_no_way_there_says_no_path() -> None:
    data = rasterise(load_world("room"))
    walled = data.data.copy()
    cells = data.world_to_cell([(2.5, y) for y in np.arange(0.0, 4.0, 0.01)])
    walled[cells[:, 0], cells[:, 1]] = 100  # the room cut in two
    grid = OccupancyGrid(walled, data.resolution, data.origin)
    robot = load_robot("omni3")
    with simulated_client(robot, world="room", start=ROOM_START, seed=1) as client:
        result = goto(client, robot, grid, Pose2D(4.0, 2.0, 0.0), ROOM_START, standstill=0.2)
    assert result.outcome == "no path" and not result.arrived
    assert result.reason.startswith("no path from (1.00, 1.00) to (4.00, 2.00)")


def test_a_box_in_the_way_with_no_replans_left_is_blocked(tmp_path: Path) -> None:
    sim_world = world_with_obstacle("room", BOX, tmp_path)
    o = run_goal("omni4", ACROSS, seed=3, sim_world=sim_world, options=GotoOptions(max_replans=0))
    assert o.result.outcome == "blocked"
    assert "an obstacle the map does not have at" in o.result.reason
    assert o.contacts == 0


def test_a_goto_out_of_time_says_so() -> None:
    o = run_goal("omni4", ACROSS, seed=1, options=GotoOptions(timeout=1.0))
    assert o.result.outcome == "timed out"
    assert "timed out" in o.result.reason


def test_paths_face_their_travel_or_turn_towards_the_goal() -> None:
    plan = PlannedPath(
        np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]), Pose2D(1.0, 1.0, math.pi), "grid", 0.3, 0.0
    )
    travel = planned_path(plan, 0.5, "travel")
    # turns in place: to face +x, at the corner to face +y, at the end to the goal's heading
    assert travel.start == (0.0, 0.0, 0.5)
    assert travel.theta[1] == pytest.approx(0.0)
    at_corner = np.isclose(travel.x, 1.0) & np.isclose(travel.y, 0.0)
    assert set(np.round(travel.theta[at_corner], 6)) == {0.0, round(math.pi / 2, 6)}
    assert travel.end[2] == pytest.approx(math.pi)
    goal = planned_path(plan, 0.5, "goal")
    assert goal.start[2] == 0.5 and goal.end[2] == pytest.approx(math.pi)
    assert np.all(np.diff(goal.theta) >= 0)
    tiny = PlannedPath(np.array([[0.0, 0.0], [0.001, 0.0]]), Pose2D(0.001, 0.0, 1.0), "grid", 0.3, 0.0)
    short = planned_path(tiny, 0.0, "travel")
    assert short.length > 0.01 and short.end == pytest.approx((0.001, 0.0, 1.0))


def test_marks_and_frames() -> None:
    grid = rasterise(load_world("room"))
    marked = mark(grid, np.array([[2.0, 2.0], [99.0, 99.0]]))
    cell = grid.world_to_cell([(2.0, 2.0)])[0]
    assert marked.data[cell[0], cell[1]] == 100 and grid.data[cell[0], cell[1]] == 0
    a = Pose2D(1.0, 2.0, 0.7)
    back = compose(a, inverse(a))
    assert back.x == pytest.approx(0.0, abs=1e-12) and back.y == pytest.approx(0.0, abs=1e-12)
    assert back.theta == pytest.approx(0.0)


def _watch(pose: Pose2D, path: np.ndarray, scan: np.ndarray | None = None) -> tuple[ObstacleWatch, list[str]]:
    robot = load_robot("omni4")
    grid = rasterise(load_world("room"))
    cmap = inflate(grid, robot_radius=robot.footprint.bounding_radius)
    stops: list[str] = []
    route = Route.from_points(path)
    watch = ObstacleWatch(robot, cmap, route, lambda: pose, stops.append, lookahead=1.0, scan=(lambda: scan))
    return watch, stops


def test_the_watch_looks_as_far_ahead_as_the_planned_speed_needs_to_stop() -> None:
    """At the leg's planned speed the watched reach grows to the stop distance: an echo 2.5 m ahead is
    beyond the 1 m watched at a walk, and inside what 3 m/s needs on omni4's stop deceleration (2.2 m/s^2)."""
    robot = load_robot("omni4")
    pose, route = Pose2D(1.0, 2.0, 0.0), np.array([[1.0, 2.0], [4.0, 2.0]])
    cmap = inflate(rasterise(load_world("room")), robot_radius=robot.footprint.bounding_radius)
    assert stopping_reach(robot, 0.0, cmap.inflated) == cmap.inflated
    fast = stopping_reach(robot, 3.0, cmap.inflated)
    assert fast == pytest.approx(cmap.inflated + 3.0 * 0.2 + 3.0**2 / (2 * robot.stop_deceleration))
    assert fast > 2.5 and stopping_reach(robot, 0.3, cmap.inflated) < 1.0
    for speed, stopped in ((0.3, False), (3.0, True)):
        stops: list[str] = []
        watch = ObstacleWatch(
            robot,
            cmap,
            Route.from_points(route),
            lambda: pose,
            stops.append,
            lookahead=1.0,
            speed_at=functools.partial(_constant, speed),
        )
        watch(_cycle((2.5,)))
        assert (watch.points is not None) is stopped and len(stops) == int(stopped)


def _constant(value: float, _s: float) -> float:
    return value


def _cycle(ranges: tuple[float | None, ...]) -> Cycle:
    return Cycle(0, 0.0, 0.0, None, telemetry=[Telemetry(time=0.0, controller_time=0.0, ranges=ranges)])


def test_the_watch_stops_for_an_echo_ahead_that_no_wall_explains() -> None:
    # heading east along y = 2 from x = 1: the east wall is 4 m ahead, the front sonar (x 0.10) sees it
    pose = Pose2D(1.0, 2.0, 0.0)
    route = np.array([[1.0, 2.0], [4.0, 2.0]])
    watch, stops = _watch(pose, route)
    watch(_cycle((3.85,)))  # the wall at x = 5: explained
    assert watch.points is None and not stops
    watch(_cycle((2.5,)))  # 2.5 m ahead: beyond the 1 m watched
    assert watch.points is None
    watch(_cycle((None,)))  # no echo
    assert watch.points is None
    watch(_cycle((0.6,)))  # 0.6 m ahead, in the corridor, nothing on the map there
    assert watch.points is not None and len(stops) == 1
    assert "an obstacle the map does not have at (1.70, 2.00)" in stops[0]
    assert np.allclose(np.hypot(watch.points[:, 0] - 1.1, watch.points[:, 1] - 2.0), 0.6)


def test_the_watch_ignores_scan_points_of_walls_and_beside_the_path() -> None:
    pose = Pose2D(1.0, 2.0, 0.0)
    route = np.array([[1.0, 2.0], [4.0, 2.0]])
    walls = np.array([[5.0, 2.0], [1.0, 4.0], [3.0, 0.0]])
    beside = np.array([[1.5, 2.8]])  # 0.8 m off the path: outside its corridor
    watch, stops = _watch(pose, route, np.vstack([walls, beside]))
    watch(_cycle(()))
    assert watch.points is None and not stops
    ahead = np.array([[1.6, 2.1], [1.6, 2.15]])
    watch, stops = _watch(pose, route, np.vstack([walls, ahead]))
    watch(_cycle(()))
    assert watch.points is not None and np.allclose(watch.points, ahead)


def test_a_robot_blind_to_a_box_the_map_lacks_stalls_against_it_and_says_so(tmp_path: Path) -> None:
    # mecanum4 has no sonar and no scan is given: it drives into the box, the stall watch ends it
    sim_world = world_with_obstacle("room", BOX, tmp_path)
    o = run_goal("mecanum4", ACROSS, seed=3, sim_world=sim_world)
    assert o.result.outcome == "stalled"
    assert o.result.reason.startswith("stalled: the wheels say")
    assert not o.result.arrived and o.contacts >= 1


def shoved_goto(max_replans: int) -> tuple[GotoResult, Pose2D, int]:
    """omni3 going across the room, shoved by a hand 1 s into its leg (8 N/kg for 0.3 s, to the left of
    its travel: past the 50 cm the follower chases); the result, the truth at the end, contacts."""
    robot = load_robot("omni3")
    client = simulated_client(robot, world="room", start=ROOM_START, seed=4)
    sim = find_simulator(client.link)
    assert sim is not None
    push = (-0.58 * 8.0 * robot.mass, 0.81 * 8.0 * robot.mass)
    shoved: list[float] = []

    def hand(cycle: Cycle) -> None:
        if not shoved and cycle.now > 1.5:
            sim.push(push, duration=0.3, motors_off=False)
            shoved.append(cycle.now)

    grid, options = rasterise(load_world("room")), GotoOptions(max_replans=max_replans)
    with client, navigation_runtime(client, robot, ROOM_START, standstill=0.5, sinks=[hand]) as runtime:
        result = go_to(runtime, robot, grid, Pose2D(3.5, 2.8, 0.0), options)
    assert shoved
    return result, sim.pose, len(sim.collisions)


def test_a_robot_shoved_off_its_leg_is_not_chased_and_goto_plans_again_from_where_it_is() -> None:
    result, truth, contacts = shoved_goto(max_replans=5)
    assert result.arrived and result.strays == 1, result.summary()
    assert truth_error(truth, result.goal)[0] <= 0.05 and contacts == 0


def test_a_shove_with_no_replans_left_ends_the_goto_off_path() -> None:
    result, truth, _ = shoved_goto(max_replans=0)
    assert result.outcome == "off path" and result.strays == 0
    assert result.reason.startswith("off the path: 5") and result.reason.endswith("still after 0 re-plans")
    assert math.hypot(truth.x - result.goal.x, truth.y - result.goal.y) > 0.5  # stopped there
