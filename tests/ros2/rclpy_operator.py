"""A genuine rclpy operator of ``omnibot ros2`` for the backend suite (tests/ros2/test_backends.py).

Run by a ROS 2 distribution's interpreter in the test's private network namespace, beside a running
bridge whose pid ``argv[1]``'s JSON plan names (``pid``); it imports nothing of omnibot. With
``use_sim_time`` true it reads odom and ``/clock``, then, in order: the graph (node names, the node
of ``/odom``'s publisher), the bridge's parameters through rclpy's parameter client, the
``reset_odometry`` service (std_srvs, when this interpreter has it), a drive on Twist then on
TwistStamped (each from a node of its own: Fast DDS takes one type per topic name in a
participant), and a host stall (SIGSTOP of the bridge for ``stall`` s). Prints one JSON line.
"""

from __future__ import annotations

import itertools
import json
import os
import signal
import sys
import time
from typing import Any

import rclpy
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from rosgraph_msgs.msg import Clock

WAIT = 60.0
"""s to wait for the bridge's first odom (discovery and the simulator's start on a loaded machine)."""
IDLE = 0.05
"""s a spin waits at most with nothing due: each message ends it sooner (an idle spin costs rclpy
0.3-0.6 ms of CPU: 5.6 % of a core at 10 ms timeouts, 1.2 % at 50 ms)."""


def ns(stamp: Any) -> int:
    """A builtin_interfaces/Time in ns."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def main() -> None:
    """See the module docstring."""
    plan = json.loads(sys.argv[1])
    rclpy.init()
    node = Node("operator", parameter_overrides=[Parameter("use_sim_time", value=True)])
    odom: list[dict[str, Any]] = []
    clocks: list[int] = []

    def on_odom(m: Any) -> None:
        now = node.get_clock().now().nanoseconds
        p = m.pose.pose.position
        odom.append({"stamp": ns(m.header.stamp), "sim": now, "wall": time.time_ns(), "x": p.x, "y": p.y})

    node.create_subscription(Odometry, "odom", on_odom, 10)

    def on_clock(m: Any) -> None:
        clocks.append(ns(m.clock))

    node.create_subscription(Clock, "/clock", on_clock, 10)

    def spin_until(done: Any, seconds: float, publish: Any = None) -> bool:
        end, next_pub = time.monotonic() + seconds, 0.0
        while time.monotonic() < end:
            if done():
                return True
            if publish is not None and time.monotonic() >= next_pub:
                publish()
                next_pub = time.monotonic() + 0.05
            due = (next_pub if publish is not None else end) - time.monotonic()
            rclpy.spin_once(node, timeout_sec=min(IDLE, max(due, 0.0)))
        return bool(done())

    out: dict[str, Any] = {}
    out["odom_seen"] = spin_until(lambda: odom and clocks, WAIT)

    def graph() -> tuple[list[list[str]], list[list[str]]]:
        names = [[n, s] for n, s in node.get_node_names_and_namespaces()]
        publishers = [[i.node_name, i.node_namespace] for i in node.get_publishers_info_by_topic("/odom")]
        return names, publishers

    spin_until(lambda: ["omnibot", "/"] in graph()[0], 10.0)
    out["nodes"], out["odom_publishers"] = graph()

    params = AsyncParameterClient(node, "/omnibot")
    out["parameter_services"] = params.wait_for_services(
        timeout_sec=10.0 if plan["backend"] == "rclpy" else 3.0
    )
    if out["parameter_services"]:

        def call(future: Any) -> Any:
            spin_until(future.done, 10.0)
            return future.result()

        def get(name: str) -> Any:
            (value,) = call(params.get_parameters([name])).values
            return [value.double_value, value.string_value, value.bool_value]

        def set_(name: str, value: Any) -> list[Any]:
            result = call(params.set_parameters([Parameter(name, value=value)])).results[0]
            return [result.successful, result.reason]

        out["timeout_before"] = get("cmd_vel_timeout")
        out["set_timeout"] = set_("cmd_vel_timeout", 0.8)
        out["timeout_after"] = get("cmd_vel_timeout")
        out["set_negative"] = set_("cmd_vel_timeout", -1.0)
        out["set_robot"] = set_("robot", "other")
        out["robot"] = get("robot")
        out["use_sim_time"] = get("use_sim_time")

    try:
        from std_srvs.srv import Trigger
    except ImportError:
        out["reset"] = "no std_srvs"
    else:
        client = node.create_client(Trigger, "reset_odometry")
        if client.wait_for_service(timeout_sec=10.0):
            future = client.call_async(Trigger.Request())
            spin_until(future.done, 10.0)
            result = future.result()
            out["reset"] = [result.success, result.message] if result is not None else "no answer"
        else:
            out["reset"] = "no service"

    def helper(name: str) -> Node:
        context = Context()
        context.init()
        return Node(name, context=context)

    plain = node.create_publisher(Twist, "cmd_vel", 10)
    stamped = helper("nav2_stand_in").create_publisher(TwistStamped, "cmd_vel", 10)
    spin_until(lambda: plain.get_subscription_count() and stamped.get_subscription_count(), 30.0)

    def send_plain() -> None:
        msg = Twist()
        msg.linear.x = 0.2
        plain.publish(msg)

    def send_stamped() -> None:
        msg = TwistStamped()
        msg.header.stamp = node.get_clock().now().to_msg()
        msg.header.frame_id = "base_link"
        msg.twist.linear.y = 0.2
        stamped.publish(msg)

    def still() -> bool:
        return len(odom) > 10 and all(
            abs(a["x"] - b["x"]) + abs(a["y"] - b["y"]) < 1e-3 for a, b in itertools.pairwise(odom[-10:])
        )

    x0, y0 = odom[-1]["x"], odom[-1]["y"]
    spin_until(lambda: odom[-1]["x"] - x0 > 0.2, 20.0, send_plain)
    spin_until(still, 20.0)
    x1, y1 = odom[-1]["x"], odom[-1]["y"]
    spin_until(lambda: odom[-1]["y"] - y1 > 0.2, 20.0, send_stamped)
    spin_until(still, 20.0)
    out["drive"] = [[x0, y0], [x1, y1], [odom[-1]["x"], odom[-1]["y"]]]

    mark = len(odom)
    os.kill(plan["pid"], signal.SIGSTOP)
    stopped = time.time_ns()
    spin_until(lambda: False, plan["stall"])
    os.kill(plan["pid"], signal.SIGCONT)
    resumed = time.time_ns()
    spin_until(lambda: False, 3.0)
    out["stall"] = {"stopped": stopped, "resumed": resumed, "odom": odom[mark - 20 :]}
    out["stamps"] = [o["stamp"] for o in odom]
    out["clocks"] = len(clocks)
    print(json.dumps(out), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
