"""``omnibot ros2``: the robot on ROS 2 (DDS) without a ROS installation.

::

    omnibot ros2 [ROBOT OPTIONS] [--namespace NS] [--twist] [--cmd-vel-timeout S] [--duration S]

One runtime owns the robot (wall-clock paced at :data:`PERIOD`); the bridge is its ``cmd_vel`` source
and its publishing sink (:mod:`omnibot.ros2.bridge`). ``omnibot run --ros2`` adds the same to the
other front ends. Imports here are light: :func:`add_arguments` runs whenever ``omnibot`` builds its
parser.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from omnibot.errors import ConfigError

PERIOD = 0.02
"""s: the runtime's cycle with ROS 2 (odom, tf, joint states at 50 Hz)."""
INSTALL = "the ROS 2 bridge needs cyclonedds: pip install 'omnibot[ros2]'"
SONAR_PERIOD = 0.1
"""s between pings of each sonar (the controller pings only the sonars it is told to; without this
every ``range/<sonar>`` would say +inf, no echo, for a sonar that never pinged)."""


def add_bridge_options(p: argparse.ArgumentParser) -> None:
    """The bridge's own options (``omnibot ros2`` and ``omnibot run --ros2``)."""
    p.add_argument("--namespace", default="", help="ROS namespace of the robot's topics (default: none)")
    p.add_argument(
        "--twist",
        action="store_true",
        help="cmd_vel is geometry_msgs/Twist (default: TwistStamped, as Nav2 sends)",
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
    from omnibot.cliargs import add_robot_options

    add_robot_options(p, world="room", port_help="the simulated --robot, paced to the wall clock")
    add_bridge_options(p)
    p.add_argument("--duration", type=float, metavar="S", help="run for S seconds (default: until Ctrl-C)")


def check(args: argparse.Namespace) -> None:
    """Refuse bad bridge options with one line."""
    timeout = args.cmd_vel_timeout
    if not (math.isfinite(timeout) and timeout > 0):
        raise ConfigError(f"expected a positive number of seconds, got {timeout}", key="--cmd-vel-timeout")
    duration = getattr(args, "duration", None)
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise ConfigError(f"expected a positive number of seconds, got {duration}", key="--duration")
    bad = [part for part in args.namespace.strip("/").split("/") if args.namespace.strip("/")]
    if any(
        not part or not (part[0].isalpha() or part[0] == "_") or not part.replace("_", "").isalnum()
        for part in bad
    ):
        raise ConfigError(f"not a valid ROS namespace: {args.namespace!r}", key="--namespace")


def attach(runtime: Any, robot: Any, args: argparse.Namespace) -> Any:
    """Add the cmd_vel source and the publishing sink to ``runtime``; returns the node (close it)."""
    try:
        from omnibot.ros2.bridge import CmdVelSource, Ros2Sink
        from omnibot.ros2.dds import Node
    except ImportError:
        raise ConfigError(INSTALL) from None
    from omnibot.ros2.netns import UnsafeNetwork

    try:
        node = Node(args.namespace)
    except UnsafeNetwork as exc:
        raise ConfigError(str(exc)) from None
    runtime.add_source(CmdVelSource(node, stamped=not args.twist, timeout=args.cmd_vel_timeout))
    runtime.add_sink(Ros2Sink(node, robot))
    start_sonars(runtime.client, robot)
    return node


def start_sonars(client: Any, robot: Any) -> None:
    """Have the controller ping every sonar each :data:`SONAR_PERIOD` (their readings ride in TEL)."""
    for number in range(1, len(robot.sonars) + 1):
        client.sonar(number, SONAR_PERIOD)


def run(args: argparse.Namespace) -> int:
    """``omnibot ros2``: run the bridge until Ctrl-C or ``--duration``."""
    from omnibot.cliargs import check_sim_options, sim_url
    from omnibot.client.session import robot_session
    from omnibot.protocol import codes
    from omnibot.runtime.runtime import Runtime
    from omnibot.runtime.sinks import NoticePrinter
    from omnibot.teleop.pacing import Pacer

    check(args)
    check_sim_options(args)
    url = sim_url(args)
    with robot_session(url, args.robot, timeout=0.5) as session:
        client, robot = session.client, session.robot
        runtime = Runtime(client, period=PERIOD)
        node = attach(runtime, robot, args)
        runtime.add_sink(NoticePrinter(lambda text: print(f"ros2: {text}", flush=True), control=True))
        try:
            runtime.start()
            client.telemetry(PERIOD, codes.TEL_MASK)
            runtime.pacer = Pacer(client, PERIOD)
            ns = f" namespace /{node.namespace}" if node.namespace else ""
            print(
                f"ros2: {robot.name} on {url}: domain {node.domain_id}{ns}, discovery {node.scope.lower()}",
                flush=True,
            )
            runtime.run(duration=args.duration)
        finally:
            runtime.close()
            node.close()
    return 0
