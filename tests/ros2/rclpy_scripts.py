"""How the scripts that put a genuine rclpy beside ``omnibot ros2`` begin (each run in a private network
namespace by :func:`~tests.ros2.netns_helper.run_in_namespace`): the bridge on the ``dds`` backend,
the contract these tests have held it to (tests/ros2/test_backends.py runs both backends)."""

from __future__ import annotations

import json

PRELUDE = r"""
import json, os, signal, subprocess, sys, time
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
bridge = subprocess.Popen(
    [sys.executable, "-m", "omnibot", "ros2", "--ros-backend", "dds", *BRIDGE_ARGS], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
)
import rclpy
from rclpy.node import Node

rclpy.init()

def spin_until(done, seconds, publish=None):
    # Spin ``node`` (calling publish() at 20 Hz, as teleop_twist_joy, if given) until done() or
    # seconds pass: judged on what the bridge says, not on wall time, since on a loaded machine
    # its messages arrive late and bunched, and a fixed spin would see a shorter drive.
    end, next_pub = time.monotonic() + seconds, 0.0
    while time.monotonic() < end and not done():
        if publish and time.monotonic() >= next_pub:
            publish()
            next_pub = time.monotonic() + 0.05
        # at most 50 ms with nothing due (a message ends it sooner): an idle spin costs rclpy 0.3-0.6 ms
        due = (next_pub if publish else end) - time.monotonic()
        rclpy.spin_once(node, timeout_sec=min(0.05, max(due, 0.0)))
"""
"""Starts the bridge (``bridge``, its output piped) and rclpy, defines ``spin_until``; the script then
makes its ``node``."""


def beside_bridge(bridge_args: list[str], body: str) -> str:
    """A script that starts ``omnibot ros2 BRIDGE_ARGS`` and rclpy, then runs ``body``."""
    return f"BRIDGE_ARGS = {json.dumps(bridge_args)}\n" + PRELUDE + body
