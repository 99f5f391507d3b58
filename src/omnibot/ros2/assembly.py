"""The ROS 2 bridge assembled on a host runtime: its settings (:class:`BridgeSettings`), one robot's
namespace and tf frame prefix (:class:`RobotSpec`) and :func:`attach`, which adds the bridge's
sources and sinks to a :class:`~omnibot.runtime.runtime.Runtime` on a node of the chosen backend.

The bridge is the runtime's ``cmd_vel`` and ``path`` sources, its ``initialpose`` /
``reset_odometry`` sink and its publishing sink (:mod:`omnibot.ros2.bridge`); with a map, the
localiser and the ``goal_pose`` source too. ``omnibot ros2``, ``omnibot run --ros2`` and ``omnibot
map --ros2`` (:mod:`omnibot.apps.ros2`) turn their options into these values. Imports here are light:
the bridge's modules load when :func:`attach` runs.
"""

from __future__ import annotations

import importlib
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from omnibot.errors import ConfigError

if TYPE_CHECKING:
    from omnibot.mapping import OccupancyGrid
    from omnibot.ros2.backend import RosNode
    from omnibot.ros2.clock import Timeline

PERIOD = 0.02
"""s: the runtime's cycle with ROS 2 (odom, tf, joint states at 50 Hz)."""
INSTALL = "the ROS 2 bridge needs cyclonedds: pip install 'omnibot[ros2]'"
SONAR_PERIOD = 0.1
"""s between pings of each sonar (the controller pings only the sonars it is told to; without this
every ``range/<sonar>`` would say +inf, no echo, for a sonar that never pinged)."""


@dataclass(frozen=True)
class RobotSpec:
    """One robot of the bridge: its link URL (None: the simulated one the command describes), ROS
    namespace (without slashes) and tf frame prefix (``""`` or ending in ``/``)."""

    url: str | None = None
    namespace: str = ""
    prefix: str = ""
    scanner: str | None = None
    """The RPLIDAR's device (None: the simulator's scanner on ``sim://``, else none)."""

    @classmethod
    def named(
        cls,
        namespace: str = "",
        prefix: str | None = None,
        url: str | None = None,
        scanner: str | None = None,
    ) -> RobotSpec:
        """The robot in ``namespace`` (checked, slashes stripped) with its frames under ``prefix``
        (None: the namespace, as ros2_controllers' ``tf_frame_prefix``)."""
        from omnibot.ros2.frames import check_namespace, frame_prefix

        name = check_namespace(namespace)
        return cls(url, name, frame_prefix(prefix, name), scanner)


@dataclass(frozen=True)
class BridgeMap:
    """A saved map the robot is localised in (``goal_pose`` and ``navigate_to_pose`` go in it)."""

    grid: OccupancyGrid
    source: str
    """Where it was read from (named in the notice)."""
    start: tuple[float, float, float] | None = None
    """Where the robot stands in it (m, m, rad); None: the simulator's pose (a simulated robot, or the UNO with the physics in the loop, only)."""


@dataclass(frozen=True)
class BridgeSettings:
    """How the bridge runs, whatever command runs it."""

    backend: str = "dds"
    """``rclpy``, ``dds`` or ``auto`` (:func:`~omnibot.ros2.backend.choose` resolves it)."""
    twist_only: bool = False
    """``cmd_vel`` taken as geometry_msgs/Twist only (else Twist and TwistStamped)."""
    cmd_vel_timeout: float = 0.5
    """s a ``cmd_vel`` stays in force."""
    follower: str = "tracker"
    """The follower of a ``path``."""
    speed: float | None = None
    """Speed cap of the path follower, m/s (None: the robot's limit)."""
    map: BridgeMap | None = None
    """A map to localise in and go to ``goal_pose`` in (None: odometry and ``path`` only)."""
    seed: int = 0
    """The localiser's seed (with :attr:`map`)."""
    surface: str | None = None
    """The floor driven on (``--surface``): ``cmd_vel``'s ramp within its grip (None: not known)."""


def attach(
    runtime: Any,
    robot: Any,
    settings: BridgeSettings = BridgeSettings(),
    spec: RobotSpec = RobotSpec(),
    timeline: Timeline | None = None,
    *,
    announce: bool = True,
) -> RosNode:
    """Add the bridge to ``runtime``: the cmd_vel and path sources, the odometry reset and publishing
    sinks (stamping on ``timeline``, the process's :class:`~omnibot.ros2.clock.Timeline`, a new one
    when None; ``/clock`` when the link is a simulator's); gives the runtime the fused estimator at
    its first cycle when it has none; gives it the robot's scanner when it has none (the RPLIDAR on
    the spec's ``scanner``, else the simulator's on ``sim://``; closed with the node), whose scans the
    sink publishes on ``scan``. The node is on ``settings.backend`` (as
    :func:`~omnibot.ros2.backend.choose` resolves it), and the settings are its parameters
    (:func:`parameters`); ``announce``: a notice names the node and its backend (``omnibot ros2``
    names them in its own first line). Returns the node (close it)."""
    _require_bridge()
    from omnibot.ros2.backend import choose
    from omnibot.ros2.clock import Timeline
    from omnibot.runtime import StallWatch, start_sonars
    from omnibot.transport import find_simulator

    timeline = timeline or Timeline()
    backend = choose(settings.backend)
    sim = find_simulator(runtime.client.link)
    simulated = sim is not None
    node = _open_with_scanner(runtime, robot, settings, spec, backend, simulated)

    def notify(level: Any, text: str) -> None:
        runtime.notify(level, text)

    cmd_vel = _add_bridge(runtime, robot, settings, spec, node, timeline, simulated, notify)
    node.declare(parameters(robot, runtime, spec, cmd_vel, node.backend))
    if announce:
        notify("info", f"ros2: node {fqn(node)} on the {node.backend} backend")
    StallWatch.on(runtime, robot, truth=sim)  # wheels that turn while the body does not: stop, say so
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
    settings: BridgeSettings,
    spec: RobotSpec,
    node: Any,
    timeline: Timeline,
    simulated: bool,
    notify: Any,
) -> Any:
    """Add :func:`attach`'s sources and sinks on ``node`` to ``runtime`` (the goal pose's too with
    a map); returns the cmd_vel source."""
    from omnibot.ros2.bridge import Ros2Sink
    from omnibot.ros2.diagnostics import Diagnosed
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
        follower=settings.follower,
        speed=settings.speed,
        runtime=runtime,
        diagnosed=diagnosed,
    )
    cancels = [path.cancel]  # an odometry reset moves the frame under what is being driven

    def cancel(why: str) -> None:
        for one in cancels:
            one(why)

    reset = OdometryReset(node, runtime, odom_frame=odom, notify=notify, on_reset=cancel, diagnosed=diagnosed)
    EstimatorWhenMissing.add(runtime, robot)
    cmd_vel = _add_cmd_vel(runtime, robot, node, settings, notify)
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
    if settings.map is not None:
        goal = _goal_pose(runtime, robot, settings.map, settings.seed, node, bridge, spec, notify, diagnosed)
        cancels.append(goal.cancel)
        reset.placer = goal.initial_pose
    return cmd_vel


def _open_with_scanner(
    runtime: Any, robot: Any, settings: BridgeSettings, spec: RobotSpec, backend: str, simulated: bool
) -> RosNode:
    """The bridge's node on ``backend``, the robot's scanner given to ``runtime`` (when it has none)
    and closed with the node. A bad scanner device, or a map without a scanner, is refused
    before any participant starts; the scanner is closed again when the node does not open."""
    from omnibot.ros2.netns import UnsafeNetwork
    from omnibot.ros2.opening import open_node

    scans = _scanner(runtime, robot, spec)
    if settings.map is not None and runtime.scanner is None:
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


def _add_cmd_vel(runtime: Any, robot: Any, node: Any, settings: BridgeSettings, notify: Any) -> Any:
    """The ``cmd_vel`` source (``twist_only`` forces its message type), limited to what the robot and
    its controller allow, added to ``runtime``."""
    from omnibot.ros2.cmd_vel import TWIST, CmdVelSource
    from omnibot.teleop import TwistLimits

    cmd_vel = CmdVelSource(
        node,
        forced=TWIST if settings.twist_only else None,
        timeout=settings.cmd_vel_timeout,
        limits=TwistLimits.from_limits(runtime.client.limits, None, robot, settings.surface),
        period=runtime.period,
        notify=notify,
    )
    runtime.add_source(cmd_vel)
    return cmd_vel


def _goal_pose(
    runtime: Any,
    robot: Any,
    saved: BridgeMap,
    seed: int,
    node: Any,
    bridge: Any,
    spec: RobotSpec,
    notify: Any,
    diagnosed: Any,
) -> Any:
    """The localiser in ``saved`` (started at its start or the simulator's pose) publishing the map
    and ``map -> odom``, and the ``goal_pose`` source on it (:mod:`omnibot.ros2.goal`)."""
    from omnibot.mapping import Localiser
    from omnibot.motion import Pose2D
    from omnibot.ros2.goal import GoalPoseSource, Localisation, PlaceableSink
    from omnibot.ros2.navigate import NavigateToPose
    from omnibot.transport import find_simulator

    grid = saved.grid
    if saved.start is not None:
        start = Pose2D(*saved.start)
    else:
        sim = find_simulator(runtime.client.link)
        assert sim is not None  # a real robot's map comes with its start
        start = Pose2D(sim.pose.x, sim.pose.y, sim.pose.theta)
    localiser = Localiser(grid, seed=seed)
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
        f"localising in {saved.source} from ({start.x:.2f}, {start.y:.2f}, {math.degrees(start.theta):.0f} deg); "
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
