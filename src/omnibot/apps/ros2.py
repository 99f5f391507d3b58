"""``omnibot ros2``: robots on ROS 2, as rclpy nodes or on the DDS wire without a ROS installation.

::

    omnibot ros2 [ROBOT OPTIONS] [--ros-backend auto|rclpy|dds] [--namespace NS] [--frame-prefix P]
                 [--twist] [--cmd-vel-timeout S] [--speed M/S] [--duration S]
    omnibot ros2 --port URL1 --namespace r1 --port URL2 --namespace r2 ...   # several robots

Each robot has its own runtime (wall-clock paced at :data:`~omnibot.ros2.assembly.PERIOD`),
participant, namespace and tf frame prefix, and one ROS node ``omnibot`` in that namespace (on the
backend ``--ros-backend`` names, :mod:`omnibot.ros2.backend`; the bridge's options are its
parameters); :func:`omnibot.ros2.attach` adds the bridge to it. With several robots the i-th
``--namespace`` (and ``--frame-prefix``, when given) goes with the i-th ``--port``; every robot's
link is opened first (one that cannot be opened ends the command before any robot moves), then each
robot runs in a thread of its own, and one robot failing ends them all.

The bridge's options are ``omnibot run --ros2``'s and ``omnibot map --ros2``'s too
(:func:`add_bridge_options`): :func:`check` refuses bad ones in one line and turns them into the
bridge's :class:`~omnibot.ros2.assembly.BridgeSettings`, which :func:`attach_bridge` hands on.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import threading
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from omnibot.errors import ConfigError

if TYPE_CHECKING:
    from omnibot.client import RobotSession
    from omnibot.ros2 import BridgeMap, BridgeSettings, RobotSpec, Timeline


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


def _listed(value: Any) -> list[str]:
    if value is None:
        return []
    return list(value) if isinstance(value, list) else [value]


def robot_specs(args: argparse.Namespace) -> list[RobotSpec]:
    """The robots the options describe (one line for mismatched counts or a shared namespace or
    prefix)."""
    from omnibot.ros2 import RobotSpec, check_namespace, frame_prefix

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
    """Refuse bad bridge options with one line; the robots they describe. The bridge's settings (the
    backend resolved, a ``--map`` loaded) are left in ``args.ros2_bridge`` for :func:`attach_bridge`."""
    from omnibot.cliargs import calibrated_floor
    from omnibot.ros2 import BridgeSettings, choose

    timeout = args.cmd_vel_timeout
    if not (math.isfinite(timeout) and timeout > 0):
        raise ConfigError(f"expected a positive number of seconds, got {timeout}", key="--cmd-vel-timeout")
    duration = getattr(args, "duration", None)
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise ConfigError(f"expected a positive number of seconds, got {duration}", key="--duration")
    speed = getattr(args, "speed", None)
    if speed is not None and not (math.isfinite(speed) and speed > 0):
        raise ConfigError(f"expected a positive speed in m/s, got {speed}", key="--speed")
    backend = choose(getattr(args, "ros_backend", "auto"))
    specs = robot_specs(args)
    if len(specs) > 1 and (getattr(args, "log", None) or getattr(args, "foxglove", None)):
        raise ConfigError("--log and --foxglove record one robot: not with several --port", key="--log")
    args.ros2_bridge = BridgeSettings(
        backend=backend,
        twist_only=args.twist,
        cmd_vel_timeout=timeout,
        follower=getattr(args, "follower", "tracker"),
        speed=speed,
        map=check_map(args, specs),
        seed=getattr(args, "seed", None) or 0,
        surface=calibrated_floor(args),
    )
    return specs


def check_map(args: argparse.Namespace, specs: list[RobotSpec]) -> BridgeMap | None:
    """``--map`` and ``--initial-pose`` checked (one line each): the map loaded, with where the robot
    stands in it (None without ``--map``)."""
    path = getattr(args, "map", None)
    initial = getattr(args, "initial_pose", None)
    if path is None:
        if initial is not None:
            raise ConfigError(
                "--initial-pose places the robot in a --map: give the map", key="--initial-pose"
            )
        return None
    from omnibot.cliargs import physics_behind
    from omnibot.mapping import load_map
    from omnibot.motion import parse_pose
    from omnibot.ros2 import BridgeMap

    if len(specs) > 1:
        raise ConfigError("--map localises one robot: not with several --port", key="--map")
    url = specs[0].url
    start = None
    if initial is not None:
        x, y, theta = parse_pose(initial, "--initial-pose")
        start = (x, y, theta or 0.0)
    elif not physics_behind(url):
        raise ConfigError(
            "where does the robot stand in the map? give --initial-pose X,Y,THETA", key="--initial-pose"
        )
    return BridgeMap(load_map(path), path, start)


def attach_bridge(
    runtime: Any,
    robot: Any,
    args: argparse.Namespace,
    spec: RobotSpec | None = None,
    timeline: Timeline | None = None,
    *,
    announce: bool = True,
) -> Any:
    """:func:`omnibot.ros2.attach` with the settings :func:`check` left in ``args`` and ``spec`` (None:
    the one robot the options describe), stamping on ``timeline`` (None: a new one) placed as the
    command's ``--log`` places its messages (the bridge stamps as the recorder does). Returns the node
    (close it)."""
    from omnibot.cliargs import recording_of
    from omnibot.ros2 import Timeline, attach

    settings: BridgeSettings = args.ros2_bridge
    spec = spec or robot_specs(args)[0]
    timeline = timeline or Timeline()
    recording = recording_of(args)
    recorder = recording.recorder if recording is not None else None
    if recorder is not None:
        timeline.adopt(recorder.placing)
    return attach(runtime, robot, settings, spec, timeline, announce=announce)


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
    args: argparse.Namespace, spec: RobotSpec, session: Any, url: str, label: str, timeline: Timeline
) -> _Robot:
    """The robot's runtime with the bridge attached (not yet running), stamping on ``timeline``."""
    from omnibot.cliargs import recording_of, use_calibration
    from omnibot.ros2 import PERIOD
    from omnibot.runtime import NoticePrinter, Runtime

    slip = use_calibration(args, session.client, session.robot)
    runtime = Runtime(
        session.client, period=PERIOD, wheel_loop=not args.open_loop, slip=slip, recording=recording_of(args)
    )
    node = attach_bridge(runtime, session.robot, args, spec, timeline, announce=False)
    runtime.add_sink(NoticePrinter(lambda text: _say(f"{label}{text}"), control=True))
    return _Robot(spec, url, session.client, session.robot, runtime, node, label)


def _serve(one: _Robot, args: argparse.Namespace, stop: threading.Event) -> None:
    """Run one robot's runtime, wall-clock paced, until ``stop`` or ``--duration``."""
    from omnibot.protocol import codes
    from omnibot.ros2 import PERIOD, fqn
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
    from omnibot.cliargs import check_sim_options
    from omnibot.ros2 import Timeline

    specs = check(args)
    check_sim_options(args)
    several = len(specs) > 1
    stop = threading.Event()
    timeline = Timeline()  # the robots' stamps placed alike, one /clock
    with contextlib.ExitStack() as stack:
        robots: list[_Robot] = []
        for spec in specs:
            url = _url(args, spec)
            session = _enter_session(stack, args, spec, url)
            label = f"ros2 [{spec.namespace}]: " if several else "ros2: "
            one = _open(args, spec, session, url, label, timeline)
            stack.callback(one.node.close)
            stack.callback(one.runtime.close)
            robots.append(one)
        if several:
            _serve_fleet(robots, args, stop)
        else:
            _serve(robots[0], args, stop)
    return 0


def _enter_session(
    stack: contextlib.ExitStack[Any], args: argparse.Namespace, spec: RobotSpec, url: str
) -> RobotSession:
    """The robot's session on ``url``, entered in ``stack``; a simulated robot that cannot stand at
    ``--initial-pose`` (put into the URL by :func:`_url`) told as that option, not as the URL."""
    from omnibot.cliargs import placed_by, recording_of
    from omnibot.client import robot_session

    try:
        return stack.enter_context(robot_session(url, args.robot, timeout=0.5, recording=recording_of(args)))
    except ConfigError as exc:
        if spec.url is not None or getattr(args, "initial_pose", None) is None:
            raise
        raise placed_by(exc, "--initial-pose", "--initial-pose; give a pose inside the world") from None


def _url(args: argparse.Namespace, spec: RobotSpec) -> str:
    """The robot's link: its ``--port``, else the simulated robot the options describe (put where
    ``--map`` has it stand)."""
    from omnibot.cliargs import sim_url

    url = spec.url or sim_url(args)
    saved = args.ros2_bridge.map
    start = saved.start if saved is not None else None
    if start is not None and spec.url is None:  # the simulated robot put where the map has it
        url += f"&pose={start[0]:.4f},{start[1]:.4f},{math.degrees(start[2]):.3f}"
    return url


def _serve_fleet(robots: list[_Robot], args: argparse.Namespace, stop: threading.Event) -> None:
    """Run each robot in a thread of its own until ``stop``: the first to end, or to fail, ends them
    all (a failure is raised here)."""
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
