"""``omnibot goto``: go to a place on a saved map, localised by the scanner, and say whether it arrived.

::

    omnibot goto X,Y[,THETA] --map MAP.yaml [ROBOT OPTIONS] [--initial-pose X,Y,THETA] [--scanner DEV]
                 [--tolerance M] [--heading-tolerance DEG] [--speed V] [--planner NAME]

The map is read in map_server's format (``omnibot map`` writes it; slam_toolbox's and cartographer's
load too). The robot starts at ``--initial-pose`` (map frame, degrees; on the simulator the robot is
put there, by default the world's start pose) and is localised in the map by a particle filter
refined by scan-to-map matching (:class:`~omnibot.mapping.session.LocalisingSink` on goto's
runtime); a robot without a scanner goes by its odometry alone, and says so. The path is planned on
the map inflated by the robot's radius (:mod:`omnibot.mapping.planner`), followed with the tracker,
and what the scanner and the sonars see that the map does not stops the robot and is planned around
(:mod:`omnibot.navigation.goto`).

Exit status 0 when the robot arrived within the tolerances (by its localised pose; on the simulator
the true error is printed too), 1 when it did not (the reason is printed), 2 for bad arguments: a map
that does not load, a goal off the map or inside a wall.
"""

from __future__ import annotations

import argparse
import contextlib
import math
from typing import Any

from omnibot.errors import ConfigError


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Declare ``omnibot goto``'s options."""
    from omnibot.cliargs import add_calibration_option, add_robot_options

    p.add_argument("goal", metavar="X,Y[,THETA]", help="the goal in the map frame: m, m and degrees")
    p.add_argument("--map", metavar="MAP.yaml", required=True, help="the map (map_server's YAML + image)")
    add_robot_options(p, world="room", port_help="the simulated --robot in lockstep")
    p.add_argument(
        "--initial-pose",
        metavar="X,Y,THETA",
        help="where the robot stands in the map, m, m, degrees (default on the simulator, uno:// included: where the simulated robot stands)",
    )
    p.add_argument("--scanner", metavar="DEV", help="the RPLIDAR's serial port on a real robot")
    p.add_argument("--tolerance", type=float, default=0.05, metavar="M", help="arrival distance, m (0.05)")
    p.add_argument(
        "--heading-tolerance", type=float, default=5.0, metavar="DEG", help="arrival heading, degrees (5)"
    )
    p.add_argument("--speed", type=float, metavar="V", help="speed cap, m/s (default: the robot's limits)")
    p.add_argument(
        "--planner",
        default="grid",
        choices=("grid", "rrtstar", "prmstar", "bitstar"),
        help="grid (A* with shortcuts, default) or one of OMPL's",
    )
    add_calibration_option(p)


def _say(text: str) -> None:
    print(f"goto: {text}", flush=True)


def run(args: argparse.Namespace) -> int:
    """``omnibot goto``: the exit status."""
    from omnibot.cliargs import (
        check_sim_options,
        physics_behind,
        placed_by,
        recording_of,
        sim_url,
        simulated,
    )
    from omnibot.client import robot_session
    from omnibot.mapping import check_goal, inflate, load_map
    from omnibot.motion import Pose2D, parse_pose
    from omnibot.navigation import GotoOptions

    gx, gy, gtheta = parse_pose(args.goal, "goal", optional_heading=True)
    initial = parse_pose(args.initial_pose, "--initial-pose") if args.initial_pose else None
    for name, value in (("--tolerance", args.tolerance), ("--heading-tolerance", args.heading_tolerance)):
        if not (math.isfinite(value) and value > 0):
            raise ConfigError(f"expected a positive number, got {value}", key=name)
    if args.speed is not None and not (math.isfinite(args.speed) and args.speed > 0):
        raise ConfigError(f"expected a positive speed in m/s, got {args.speed}", key="--speed")
    check_sim_options(args)
    on_sim = simulated(args)
    if args.scanner is not None and on_sim:
        raise ConfigError(
            "the simulated robot's scanner is simulated: --scanner goes with --port", key="--scanner"
        )
    if initial is None and not physics_behind(args.port):
        raise ConfigError(
            "where does the robot stand in the map? give --initial-pose X,Y,THETA", key="--initial-pose"
        )
    grid = load_map(args.map)
    url = sim_url(args)
    if initial is not None and args.port is None:
        url += f"&pose={initial[0]:.4f},{initial[1]:.4f},{math.degrees(initial[2] or 0.0):.3f}"
    options = GotoOptions(
        tolerance=args.tolerance,
        heading_tolerance=math.radians(args.heading_tolerance),
        planner=args.planner,
        speed=args.speed,
    )
    with contextlib.ExitStack() as stack:
        try:
            session = stack.enter_context(robot_session(url, args.robot, recording=recording_of(args)))
        except ConfigError as exc:
            if initial is None or args.port is not None:
                raise
            raise placed_by(exc, "--initial-pose", "--initial-pose; give a pose inside the world") from None
        client, robot = session.client, session.robot
        start = _start(client, initial)
        goal = Pose2D(gx, gy, start.theta if gtheta is None else gtheta)
        # a goal off the map or where the robot cannot stand: refused before the robot moves
        check_goal(inflate(grid, robot_radius=robot.footprint.bounding_radius, margin=options.margin), goal)
        return _go(args, client, robot, grid, goal, start, options)


def _start(client: Any, initial: tuple[float, float, float | None] | None) -> Any:
    """The robot's pose in the map at the start: ``--initial-pose``, else the simulator's."""
    from omnibot.motion import Pose2D
    from omnibot.transport import find_simulator

    if initial is not None:
        return Pose2D(initial[0], initial[1], initial[2] or 0.0)
    sim = find_simulator(client.link)
    assert sim is not None  # checked: a real robot needs --initial-pose
    return sim.pose


def _go(
    args: argparse.Namespace, client: Any, robot: Any, grid: Any, goal: Any, start: Any, options: Any
) -> int:
    from omnibot.cliargs import recording_of, use_calibration
    from omnibot.lidar import open_scanner
    from omnibot.mapping import Localiser, LocalisingSink
    from omnibot.navigation import goto
    from omnibot.transport import find_simulator

    sim = find_simulator(client.link)
    slip = use_calibration(args, client, robot)
    sink: LocalisingSink | None = None
    if robot.scanner is not None:
        scans = open_scanner(args.scanner, client.link, robot)
        localiser = Localiser(grid, seed=args.seed or 0)
        localiser.reset(start, spread=(0.05, 0.05))
        sink = LocalisingSink(scans, localiser, threaded=sim is None)
        _say("localising in the map with the scanner (particle filter and scan-to-map matching)")
    else:
        _say(f"robot {robot.name!r} has no scanner: it goes by its odometry alone")

    def provider(runtime: Any) -> Any:
        assert sink is not None
        runtime.add_sink(sink)
        return sink.pose_now

    _say(
        f"from ({start.x:.2f}, {start.y:.2f}, {math.degrees(start.theta):.0f} deg) to ({goal.x:.2f}, {goal.y:.2f}, {math.degrees(goal.theta):.0f} deg)"
    )
    try:
        result = goto.goto(
            client,
            robot,
            grid,
            goal,
            start,
            options,
            pose_from=provider if sink is not None else None,
            scan=sink.points if sink is not None else None,
            slip=slip,
            recording=recording_of(args),
        )
    finally:
        if sink is not None:
            sink.close()
    _say(result.summary())
    if sink is not None and sink.failure is not None:
        _say(f"the localiser failed: {sink.failure}")
    if result.replans:
        _say(f"{result.replans} re-plans around {len(result.obstacles)} points the map did not have")
    if sim is not None:
        true = sim.pose
        err = math.hypot(true.x - goal.x, true.y - goal.y)
        dth = math.degrees(abs(math.remainder(true.theta - goal.theta, math.tau)))
        _say(f"the simulator's truth: {err * 100:.1f} cm, {dth:.1f} degrees from the goal")
    # arrival judged by a localiser that stopped is arrival by odometry alone: not what was asked
    return 0 if result.arrived and (sink is None or sink.failure is None) else 1
