"""``omnibot ros2``: robots on ROS 2, as rclpy nodes or on the DDS wire without a ROS installation.

::

    omnibot ros2 [ROBOT OPTIONS] [--ros-backend auto|rclpy|dds] [--namespace NS] [--frame-prefix P]
                 [--twist] [--cmd-vel-timeout S] [--speed M/S] [--duration S]
    omnibot ros2 --port URL1 --namespace r1 --port URL2 --namespace r2 ...   # several robots

Each robot has its own runtime (wall-clock paced at :data:`PERIOD`), participant, namespace and tf
frame prefix, and one ROS node ``omnibot`` in that namespace (on the backend ``--ros-backend`` names,
:mod:`omnibot.ros2.backend`; the bridge's options are its parameters); the bridge is its ``cmd_vel`` and ``path`` sources, its ``initialpose`` /
``reset_odometry`` sink and its publishing sink (:mod:`omnibot.ros2.bridge`). With several robots
the i-th ``--namespace`` (and ``--frame-prefix``, when given) goes with the i-th ``--port``; every
robot's link is opened first (one that cannot be opened ends the command before any robot moves),
then each robot runs in a thread of its own, and one robot failing ends them all. ``omnibot run
--ros2`` adds the same to the other front ends (one robot). Imports here are light:
:func:`add_arguments` runs whenever ``omnibot`` builds its parser.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import math
import threading
from dataclasses import dataclass
from typing import Any

from omnibot.errors import ConfigError

PERIOD = 0.02
"""s: the runtime's cycle with ROS 2 (odom, tf, joint states at 50 Hz)."""
INSTALL = "the ROS 2 bridge needs cyclonedds: pip install 'omnibot[ros2]'"
SONAR_PERIOD = 0.1
"""s between pings of each sonar (the controller pings only the sonars it is told to; without this
every ``range/<sonar>`` would say +inf, no echo, for a sonar that never pinged)."""


def add_bridge_options(p: argparse.ArgumentParser, *, several: bool = False, scanner: bool = True) -> None:
    """The bridge's own options (``omnibot ros2``, where ``several`` robots may be given, and ``omnibot
    run --ros2``; ``omnibot map --ros2`` has its own ``--scanner``, so not ``scanner``)."""
    more = "; one per --port, in the same order" if several else ""
    p.add_argument(
        "--ros-backend",
        choices=("auto", "rclpy", "dds"),
        default="auto",
        help="rclpy: a ROS node on your rmw (parameters, services for every rmw); dds: the DDS wire "
        "with cyclonedds only, no ROS install needed; auto (default): rclpy when it can be imported",
    )
    if scanner:
        p.add_argument(
            "--scanner",
            action="append" if several else "store",
            metavar="DEV",
            help="the RPLIDAR's serial port of a real robot (or the scanner pty of omnibot sim --pty), "
            f"published on scan (a simulated robot's scanner is published without it){more}",
        )
    p.add_argument(
        "--namespace",
        action="append" if several else "store",
        default=None if several else "",
        help=f"ROS namespace of the robot's topics (default: none){more}",
    )
    p.add_argument(
        "--frame-prefix",
        action="append" if several else "store",
        metavar="PREFIX",
        help="tf frame prefix of the robot's frames, e.g. r1/ (default: the namespace, as "
        f"ros2_controllers' tf_frame_prefix; '' for none){more}",
    )
    p.add_argument(
        "--twist",
        action="store_true",
        help="take cmd_vel as geometry_msgs/Twist only (default: Twist and TwistStamped, by what the "
        "publishers offer)",
    )
    p.add_argument(
        "--cmd-vel-timeout",
        type=float,
        default=0.5,
        metavar="S",
        help="s a cmd_vel stays in force (default 0.5, ros2_controllers')",
    )


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Declare ``omnibot ros2``'s options."""
    from omnibot.cliargs import add_calibration_option, add_robot_options, add_wheel_loop_option

    add_robot_options(
        p, world="room", port_help="the simulated --robot, paced to the wall clock", several=True
    )
    add_wheel_loop_option(p)
    add_calibration_option(p)
    add_bridge_options(p, several=True)
    p.add_argument(
        "--speed",
        type=float,
        metavar="M/S",
        help="speed cap of the path follower (default: the robot's limit)",
    )
    p.add_argument("--duration", type=float, metavar="S", help="run for S seconds (default: until Ctrl-C)")
    p.add_argument(
        "--map",
        metavar="MAP.yaml",
        help="a saved map (map_server's YAML + image): localise in it with the scanner, publish map and "
        "map -> odom, and go to each goal_pose (geometry_msgs/PoseStamped in map); one robot",
    )
    p.add_argument(
        "--initial-pose",
        metavar="X,Y,THETA",
        help="with --map: where the robot stands in the map, m, m, degrees (default on the simulator: the "
        "world's start; the simulated robot is put there)",
    )


@dataclass(frozen=True)
class RobotSpec:
    """One robot of ``omnibot ros2``: its link URL (None: the simulated one the options describe), ROS
    namespace and tf frame prefix."""

    url: str | None
    namespace: str
    prefix: str
    scanner: str | None = None
    """The RPLIDAR's device (None: the simulator's scanner on ``sim://``, else none)."""


def _listed(value: Any) -> list[str]:
    if value is None:
        return []
    return list(value) if isinstance(value, list) else [value]


def check_namespace(namespace: str) -> str:
    """``namespace`` without its slashes, or a one-line error."""
    text = namespace.strip("/")
    parts = text.split("/") if text else []
    if any(
        not part or not (part[0].isalpha() or part[0] == "_") or not part.replace("_", "").isalnum()
        for part in parts
    ):
        raise ConfigError(f"not a valid ROS namespace: {namespace!r}", key="--namespace")
    return text


def robot_specs(args: argparse.Namespace) -> list[RobotSpec]:
    """The robots the options describe (one line for mismatched counts or a shared namespace or
    prefix)."""
    from omnibot.ros2.frames import frame_prefix

    ports = _listed(getattr(args, "port", None))
    namespaces = _listed(args.namespace)
    prefixes = _listed(args.frame_prefix)
    count = max(1, len(ports))
    if count > 1 and len(namespaces) != count:
        raise ConfigError(
            f"{count} robots (--port) but {len(namespaces)} --namespace: give each robot its own "
            "namespace, in the order of the --port options",
            key="--namespace",
        )
    if len(namespaces) > count or len(prefixes) > count or (prefixes and len(prefixes) != count):
        raise ConfigError(
            f"{count} robot{'s' if count > 1 else ''} (--port) but {len(namespaces)} --namespace and "
            f"{len(prefixes)} --frame-prefix: give at most one of each per robot, in the order of --port",
            key="--namespace" if len(namespaces) > count else "--frame-prefix",
        )
    names = [check_namespace(ns) for ns in namespaces] or [""]
    given: list[str | None] = list(prefixes) or [None] * count
    frames = [frame_prefix(p, ns) for p, ns in zip(given, names, strict=True)]
    for label, values, key in (
        ("namespace", names, "--namespace"),
        ("tf frame prefix", frames, "--frame-prefix"),
    ):
        seen = [v for i, v in enumerate(values) if v in values[:i]]
        if seen:
            raise ConfigError(
                f"two robots with the {label} {seen[0] or '(none)'!r}: each robot needs its own", key=key
            )
    scanners = _listed(getattr(args, "scanner", None))
    if scanners and len(scanners) != count:
        raise ConfigError(
            f"{count} robots (--port) but {len(scanners)} --scanner: give each robot's scanner, in the "
            "order of --port (or none)",
            key="--scanner",
        )
    devices: list[str | None] = list(scanners) or [None] * count
    urls: list[str | None] = list(ports) or [None]
    return [
        RobotSpec(url, ns, prefix, dev)
        for url, ns, prefix, dev in zip(urls, names, frames, devices, strict=True)
    ]


def check(args: argparse.Namespace) -> list[RobotSpec]:
    """Refuse bad bridge options with one line; the robots they describe."""
    timeout = args.cmd_vel_timeout
    if not (math.isfinite(timeout) and timeout > 0):
        raise ConfigError(f"expected a positive number of seconds, got {timeout}", key="--cmd-vel-timeout")
    duration = getattr(args, "duration", None)
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise ConfigError(f"expected a positive number of seconds, got {duration}", key="--duration")
    speed = getattr(args, "speed", None)
    if speed is not None and not (math.isfinite(speed) and speed > 0):
        raise ConfigError(f"expected a positive speed in m/s, got {speed}", key="--speed")
    from omnibot.ros2.backend import choose

    args.ros_backend = choose(getattr(args, "ros_backend", "auto"))
    specs = robot_specs(args)
    if len(specs) > 1 and (getattr(args, "log", None) or getattr(args, "foxglove", None)):
        raise ConfigError("--log and --foxglove record one robot: not with several --port", key="--log")
    check_map(args, specs)
    return specs


def check_map(args: argparse.Namespace, specs: list[RobotSpec]) -> None:
    """``--map`` and ``--initial-pose`` checked (one line each); the map loaded into ``args.map_grid``
    (None without ``--map``) and the pose parsed into ``args.map_start``."""
    path = getattr(args, "map", None)
    initial = getattr(args, "initial_pose", None)
    args.map_grid = args.map_start = None
    if path is None:
        if initial is not None:
            raise ConfigError(
                "--initial-pose places the robot in a --map: give the map", key="--initial-pose"
            )
        return
    from omnibot.mapping import load_map
    from omnibot.motion import parse_pose

    if len(specs) > 1:
        raise ConfigError("--map localises one robot: not with several --port", key="--map")
    url = specs[0].url
    if initial is not None:
        x, y, theta = parse_pose(initial, "--initial-pose")
        args.map_start = (x, y, theta or 0.0)
    elif url is not None and not url.split("+")[-1].startswith("sim:"):
        raise ConfigError(
            "where does the robot stand in the map? give --initial-pose X,Y,THETA", key="--initial-pose"
        )
    args.map_grid = load_map(path)


def attach(
    runtime: Any,
    robot: Any,
    args: argparse.Namespace,
    spec: RobotSpec | None = None,
    timeline: Any = None,
    *,
    announce: bool = True,
) -> Any:
    """Add the bridge to ``runtime``: the cmd_vel and path sources, the odometry reset and publishing
    sinks (stamping on ``timeline``, the process's :class:`~omnibot.ros2.clock.Timeline`; ``/clock``
    when the link is a simulator's); gives the runtime the fused estimator at its first cycle when
    it has none; gives it the robot's scanner when it has none (the RPLIDAR on the spec's
    ``--scanner``, else the simulator's on ``sim://``; closed with the node), whose scans the sink
    publishes on ``scan``. The node is ``args.ros_backend``'s (``rclpy`` or ``dds``, as :func:`check`
    resolved it; ``dds`` when ``args`` has none), and the bridge's options are its parameters
    (:func:`parameters`); ``announce``: a notice names the node and its backend (``omnibot ros2``
    names them in its own first line). Returns the node (close it)."""
    _require_bridge()
    from omnibot.ros2.backend import choose
    from omnibot.runtime import StallWatch, start_sonars
    from omnibot.transport import find_simulator

    spec = spec or robot_specs(args)[0]
    timeline = _timeline_of(args, timeline)
    backend = choose(getattr(args, "ros_backend", "dds"))
    simulated = find_simulator(runtime.client.link) is not None
    node = _open_with_scanner(runtime, robot, args, spec, backend, simulated)

    def notify(level: Any, text: str) -> None:
        runtime.notify(level, text)

    cmd_vel = _add_bridge(runtime, robot, args, spec, node, timeline, simulated, notify)
    node.declare(parameters(robot, runtime, spec, cmd_vel, node.backend))
    if announce:
        notify("info", f"ros2: node {fqn(node)} on the {node.backend} backend")
    StallWatch.on(runtime, robot)  # wheels that turn while the body does not: stop, say so
    start_sonars(runtime.client, robot, SONAR_PERIOD)  # in TEL: the ranges out, the stall watch's witnesses
    return node


def _require_bridge() -> None:
    """A :class:`ConfigError` naming the extra to install unless the bridge's modules import (their
    message types need cyclonedds, the helpers' imports too)."""
    try:
        for name in ("backend", "bridge", "odometry", "path"):
            importlib.import_module(f"omnibot.ros2.{name}")
    except ImportError:
        raise ConfigError(INSTALL) from None


def _add_bridge(
    runtime: Any,
    robot: Any,
    args: argparse.Namespace,
    spec: RobotSpec,
    node: Any,
    timeline: Any,
    simulated: bool,
    notify: Any,
) -> Any:
    """Add :func:`attach`'s sources and sinks on ``node`` to ``runtime`` (the goal pose's too with
    ``--map``); returns the cmd_vel source."""
    from omnibot.ros2.bridge import Diagnosed, Ros2Sink
    from omnibot.ros2.odometry import OdometryReset
    from omnibot.ros2.path import PathSource
    from omnibot.runtime import EstimatorWhenMissing

    odom = spec.prefix + "odom"
    diagnosed = Diagnosed.of(robot.name, spec.namespace)
    path = PathSource(
        node,
        robot,
        runtime.period,
        odom_frame=odom,
        notify=notify,
        follower=getattr(args, "follower", "tracker"),
        speed=getattr(args, "speed", None),
        runtime=runtime,
        diagnosed=diagnosed,
    )
    cancels = [path.cancel]  # an odometry reset moves the frame under what is being driven

    def cancel(why: str) -> None:
        for one in cancels:
            one(why)

    reset = OdometryReset(node, runtime, odom_frame=odom, notify=notify, on_reset=cancel, diagnosed=diagnosed)
    EstimatorWhenMissing.add(runtime, robot)
    cmd_vel = _add_cmd_vel(runtime, robot, node, args, notify)
    runtime.add_source(path)
    runtime.add_sink(reset)
    bridge = Ros2Sink(
        node,
        robot,
        prefix=spec.prefix,
        reporters=[path.status, reset.status],
        timeline=timeline,
        sim_time=simulated,
        diagnosed=diagnosed,
    )
    runtime.add_sink(bridge)
    if getattr(args, "map_grid", None) is not None:
        goal = _goal_pose(runtime, robot, args, node, bridge, spec, notify, diagnosed)
        cancels.append(goal.cancel)
        reset.placer = goal.initial_pose
    return cmd_vel


def _timeline_of(args: argparse.Namespace, timeline: Any) -> Any:
    """``timeline``, else a new :class:`~omnibot.ros2.clock.Timeline`; with ``--log`` placed as the
    recorder places its messages (the bridge stamps as it does)."""
    from omnibot.cliargs import recording_of
    from omnibot.ros2.clock import Timeline

    timeline = timeline or Timeline()
    recording = recording_of(args)
    recorder = recording.recorder if recording is not None else None
    if recorder is not None:
        timeline.adopt(recorder.placing)
    return timeline


def _open_with_scanner(
    runtime: Any, robot: Any, args: argparse.Namespace, spec: RobotSpec, backend: str, simulated: bool
) -> Any:
    """The bridge's node on ``backend``, the robot's scanner given to ``runtime`` (when it has none)
    and closed with the node. A bad ``--scanner``, or a ``--map`` without a scanner, is refused
    before any participant starts; the scanner is closed again when the node does not open."""
    from omnibot.ros2.netns import UnsafeNetwork
    from omnibot.ros2.opening import open_node

    scans = _scanner(runtime, robot, spec)
    if getattr(args, "map_grid", None) is not None and runtime.scanner is None:
        raise ConfigError(
            f"robot {robot.name!r} has no scanner to localise in --map with (give --scanner DEV)", key="--map"
        )
    try:
        node = open_node(backend, spec.namespace, sim_time=simulated)
    except BaseException as exc:
        if scans is not None:
            runtime.scanner = None
            scans.close()
        if isinstance(exc, UnsafeNetwork):
            raise ConfigError(str(exc)) from None
        raise
    if scans is not None:
        node.closers.append(scans.close)
    return node


def _add_cmd_vel(runtime: Any, robot: Any, node: Any, args: argparse.Namespace, notify: Any) -> Any:
    """The ``cmd_vel`` source (``--twist`` forces its message type), limited to what the robot and
    its controller allow, added to ``runtime``."""
    from omnibot.ros2.cmd_vel import TWIST, CmdVelSource
    from omnibot.teleop import TwistLimits

    cmd_vel = CmdVelSource(
        node,
        forced=TWIST if args.twist else None,
        timeout=args.cmd_vel_timeout,
        limits=TwistLimits.from_limits(runtime.client.limits, None, robot),
        period=runtime.period,
        notify=notify,
    )
    runtime.add_source(cmd_vel)
    return cmd_vel


def _goal_pose(
    runtime: Any,
    robot: Any,
    args: argparse.Namespace,
    node: Any,
    bridge: Any,
    spec: RobotSpec,
    notify: Any,
    diagnosed: Any,
) -> Any:
    """``--map``: the localiser (started at ``--initial-pose`` or the simulator's pose) publishing the map
    and ``map -> odom``, and the ``goal_pose`` source on it (:mod:`omnibot.ros2.goal`)."""
    from omnibot.mapping import Localiser
    from omnibot.motion import Pose2D
    from omnibot.ros2.goal import GoalPoseSource, Localisation, PlaceableSink
    from omnibot.ros2.navigate import NavigateToPose
    from omnibot.transport import find_simulator

    grid = args.map_grid
    if args.map_start is not None:
        start = Pose2D(*args.map_start)
    else:
        sim = find_simulator(runtime.client.link)
        assert sim is not None  # check_map: a real robot needs --initial-pose
        start = Pose2D(sim.pose.x, sim.pose.y, sim.pose.theta)
    localiser = Localiser(grid, seed=getattr(args, "seed", None) or 0)
    localiser.reset(start, spread=(0.05, 0.05))
    localisation = Localisation(bridge, grid, PlaceableSink(None, localiser, threaded=True))
    node.closers.append(localisation.close)
    runtime.add_sink(localisation)
    goal = GoalPoseSource(
        node,
        robot,
        grid,
        runtime.period,
        localisation.pose,
        map_frame=spec.prefix + "map",
        notify=notify,
        scan=localisation.sink.points,
        diagnosed=diagnosed,
        place=localisation.place,
    )
    runtime.add_source(goal)
    runtime.add_sink(NavigateToPose(node, goal, stamp=bridge.recorder.ns, notify=notify, speed=_speed))
    bridge.reporters.append(goal.status)
    notify(
        "info",
        f"localising in {args.map} from ({start.x:.2f}, {start.y:.2f}, {math.degrees(start.theta):.0f} deg); "
        "goal_pose and navigate_to_pose in the map frame are gone to, initialpose there re-places the robot",
    )
    return goal


def _speed(cycle: Any) -> float:
    """The robot's speed in the cycle's estimate (0 without one)."""
    e = cycle.estimate
    return 0.0 if e is None else math.hypot(e.vx, e.vy)


def fqn(node: Any) -> str:
    """The node's fully qualified name (``/r1/omnibot``)."""
    return f"/{node.namespace}/{node.name}" if node.namespace else f"/{node.name}"


def positive_seconds(value: Any) -> str | None:
    """None for a positive finite number of seconds, else why not."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"expected seconds as a number, got {value!r}"
    if not (math.isfinite(value) and value > 0):
        return f"expected a positive number of seconds, got {value}"
    return None


def parameters(robot: Any, runtime: Any, spec: RobotSpec, cmd_vel: Any, backend: str) -> list[Any]:
    """The bridge's options as ROS parameters: ``cmd_vel_timeout`` may be set while it runs (checked,
    then given to the cmd_vel source); the others say how it was started (read-only)."""
    from omnibot.ros2.backend import Parameter

    def set_timeout(value: Any) -> None:
        cmd_vel.timeout = float(value)

    return [
        Parameter("robot", robot.name, "the robot's description (its HELLO's name)"),
        Parameter("frame_prefix", spec.prefix, "tf frame prefix of the robot's frames (--frame-prefix)"),
        Parameter("twist_only", cmd_vel.forced is not None, "cmd_vel taken as Twist only (--twist)"),
        Parameter("cycle_period", float(runtime.period), "s between two runtime cycles (and odom messages)"),
        Parameter("ros_backend", backend, "rclpy or dds (--ros-backend)"),
        Parameter(
            "cmd_vel_timeout",
            float(cmd_vel.timeout),
            "s a cmd_vel stays in force (--cmd-vel-timeout); settable while running",
            positive_seconds,
            set_timeout,
        ),
    ]


def _scanner(runtime: Any, robot: Any, spec: RobotSpec) -> Any:
    """The robot's scanner, made the runtime's (see :func:`attach`); None when the runtime has one
    already or the robot gets none (whoever gets it closes it)."""
    from omnibot.lidar import open_scanner
    from omnibot.transport import find_simulator

    if runtime.scanner is not None:
        return None  # the command's own (omnibot map's, the dashboard's)
    link = runtime.client.link
    if spec.scanner is None and (robot.scanner is None or find_simulator(link) is None):
        return None  # a real robot without --scanner: no scan
    scans = open_scanner(spec.scanner, link, robot)
    runtime.scanner = scans
    return scans


_PRINTING = threading.Lock()


def _say(text: str) -> None:
    """A status line, whole (the robots' threads print at once)."""
    with _PRINTING:
        print(text, flush=True)


@dataclass
class _Robot:
    """One robot of the process: its spec, client, runtime and node."""

    spec: RobotSpec
    url: str
    client: Any
    robot: Any
    runtime: Any
    node: Any
    label: str


def _open(
    args: argparse.Namespace, spec: RobotSpec, session: Any, url: str, label: str, timeline: Any
) -> _Robot:
    """The robot's runtime with the bridge attached (not yet running), stamping on ``timeline``."""
    from omnibot.cliargs import recording_of, use_calibration
    from omnibot.runtime import NoticePrinter, Runtime

    slip = use_calibration(args, session.client, session.robot)
    runtime = Runtime(
        session.client, period=PERIOD, wheel_loop=not args.open_loop, slip=slip, recording=recording_of(args)
    )
    node = attach(runtime, session.robot, args, spec, timeline, announce=False)
    runtime.add_sink(NoticePrinter(lambda text: _say(f"{label}{text}"), control=True))
    return _Robot(spec, url, session.client, session.robot, runtime, node, label)


def _serve(one: _Robot, args: argparse.Namespace, stop: threading.Event) -> None:
    """Run one robot's runtime, wall-clock paced, until ``stop`` or ``--duration``."""
    from omnibot.protocol import codes
    from omnibot.teleop import Pacer

    runtime, client, node, spec = one.runtime, one.client, one.node, one.spec
    runtime.start()
    client.telemetry(PERIOD, codes.TEL_MASK)
    runtime.pacer = Pacer(client, PERIOD)
    frames = f", frames {spec.prefix}odom" if spec.prefix else ""
    static = getattr(node, "static_peers", ())
    peers = f", static peers {';'.join(static)}" if static and node.scope != "OFF" else ""
    _say(
        f"{one.label}{one.robot.name} on {one.url}: node {fqn(node)} on the {node.backend} backend, domain "
        f"{node.domain_id}{frames}, discovery {node.scope.lower()}{peers}"
    )
    runtime.run(until=stop.is_set, duration=args.duration)


def run(args: argparse.Namespace) -> int:
    """``omnibot ros2``: run the bridge for each robot until Ctrl-C or ``--duration``.

    Every robot's link is opened (and its controller greeted) first, in this thread, one after the
    other: a robot that cannot be opened ends the command before any robot moves, and the links of a
    shared simulated world are all open before any runtime waits on one. Then one robot runs here;
    several run a thread each (the first to end, or to fail, ends them all)."""
    from omnibot.cliargs import check_sim_options, recording_of, sim_url
    from omnibot.client import robot_session
    from omnibot.ros2.clock import Timeline

    specs = check(args)
    check_sim_options(args)
    several = len(specs) > 1
    stop = threading.Event()
    timeline = Timeline()  # the robots' stamps placed alike, one /clock
    with contextlib.ExitStack() as stack:
        robots: list[_Robot] = []
        for spec in specs:
            url = spec.url or sim_url(args)
            start = getattr(args, "map_start", None)
            if start is not None and spec.url is None:  # the simulated robot put where the map has it
                url += f"&pose={start[0]:.4f},{start[1]:.4f},{math.degrees(start[2]):.3f}"
            session = stack.enter_context(
                robot_session(url, args.robot, timeout=0.5, recording=recording_of(args))
            )
            label = f"ros2 [{spec.namespace}]: " if several else "ros2: "
            one = _open(args, spec, session, url, label, timeline)
            stack.callback(one.node.close)
            stack.callback(one.runtime.close)
            robots.append(one)
        if not several:
            _serve(robots[0], args, stop)
            return 0
        failures: list[BaseException] = []

        def serve(one: _Robot) -> None:
            try:
                _serve(one, args, stop)
            except BaseException as exc:  # handed to this thread, which reports it
                failures.append(exc)
            finally:
                stop.set()  # one robot's end (--duration, a failure) ends the fleet

        threads = [
            threading.Thread(target=serve, args=(one,), name=f"ros2-{one.spec.namespace}") for one in robots
        ]
        try:
            for thread in threads:
                thread.start()
            while any(thread.is_alive() for thread in threads):
                for thread in threads:
                    thread.join(timeout=0.1)
        finally:
            stop.set()
            for thread in threads:
                thread.join()
        if failures:
            raise failures[0]
    return 0
