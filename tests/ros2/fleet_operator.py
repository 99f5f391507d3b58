"""A genuine rclpy operator on the other "host" of a fleet test (Jazzy's wheels, their default rmw).

Run in its host's network namespace; it imports nothing of omnibot. ``argv[1]`` is a JSON plan:
``namespace`` (the robot's), ``speed`` (m/s ahead), ``distance`` (m, by the robot's odom), ``wait``
(s for discovery). It waits for the robot's ``odom`` and for the bridge to match its ``cmd_vel``
(geometry_msgs/Twist, teleop_twist_joy's default), drives the robot ahead at 20 Hz until its odom
says ``distance``, stops publishing, waits until odom says it stands still, and prints one JSON line:
the odom positions (start, end), each odom's delivery latency (rmw's received minus source
timestamp, ns: the two hosts share one clock), the nodes and types rclpy's graph shows on odom,
``/tf`` and ``cmd_vel``, and what it sent.
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.node import Node

IDLE = 0.05
"""s a spin waits at most with nothing due: each message ends it sooner (an idle spin costs rclpy
0.3-0.6 ms of CPU: 5.6 % of a core at 10 ms timeouts, 1.2 % at 50 ms)."""


def main() -> None:
    """See the module docstring."""
    plan = json.loads(sys.argv[1])
    ns = "/" + plan["namespace"]
    rclpy.init()
    node = Node("fleet_operator")
    odom: list[tuple[float, float, float, float]] = []  # x, y, vx, vy
    latency: list[int] = []

    def on_odom(msg: Any, info: Any) -> None:
        p, v = msg.pose.pose.position, msg.twist.twist.linear
        odom.append((p.x, p.y, v.x, v.y))
        latency.append(int(info["received_timestamp"]) - int(info["source_timestamp"]))

    callback: Any = on_odom  # rclpy hands the message info over too (typed as one argument)
    node.create_subscription(Odometry, f"{ns}/odom", callback, 10)
    publisher = node.create_publisher(Twist, f"{ns}/cmd_vel", 10)

    def spin_until(done: Any, seconds: float, publish: Any = None) -> bool:
        end, next_publish = time.monotonic() + seconds, 0.0
        while time.monotonic() < end and not done():
            if publish is not None and time.monotonic() >= next_publish:
                publish()
                next_publish = time.monotonic() + 0.05
            due = (next_publish if publish is not None else end) - time.monotonic()
            rclpy.spin_once(node, timeout_sec=min(IDLE, max(due, 0.0)))  # a message ends it sooner
        return bool(done())

    found = spin_until(lambda: len(odom) > 5 and publisher.get_subscription_count() > 0, plan["wait"])
    graph = {
        topic: sorted(
            {(i.node_name, i.topic_type) for i in node.get_publishers_info_by_topic(topic)}
            | {(i.node_name, i.topic_type) for i in node.get_subscriptions_info_by_topic(topic)}
        )
        for topic in (f"{ns}/odom", "/tf", f"{ns}/cmd_vel")
    }
    result: dict[str, Any] = {"found": found, "graph": graph, "sent": 0}
    if found:
        start = odom[-1]
        sent = [0]

        def ahead() -> None:
            msg = Twist()
            msg.linear.x = float(plan["speed"])
            publisher.publish(msg)
            sent[0] += 1

        moved = spin_until(lambda: odom[-1][0] - start[0] >= plan["distance"], 30, ahead)
        still = spin_until(
            lambda: len(odom) > 10 and all(abs(o[2]) + abs(o[3]) < 0.01 for o in odom[-10:]), 20
        )
        result.update(start=start[:2], end=odom[-1][:2], moved=moved, still=still, sent=sent[0])
    result["latency_ns"] = latency
    print(json.dumps(result), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
