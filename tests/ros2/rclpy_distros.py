"""The ROS 2 distributions whose genuine rclpy the interop tests run, and how to find each.

* ``jazzy``: the ``ros2-test`` extra in this interpreter's environment (``pip install
  'omnibot[ros2-test]'``);
* ``kilted``: its own venv, ``.cache/ros2-kilted`` (``make ros2-kilted``): its wheels share names with
  Jazzy's and cannot be installed beside them.

:func:`interpreter` gives the Python that runs ``rclpy_node.py`` for a distribution, or skips the test
with the reason.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
NODE = Path(__file__).with_name("rclpy_node.py")
KILTED = ROOT / ".cache" / "ros2-kilted" / "bin" / "python"
DISTROS = ("jazzy", "kilted")
BOOTSTRAP = ("_ROS_WHEELS_BOOTSTRAP_COMPLETE", "LD_LIBRARY_PATH")
"""What the ROS wheels' bootstrapper (a .pth that sets the library path and re-executes Python) leaves
in the environment: inherited by another distribution's interpreter, it would load this one's
libraries (or none). Dropped from a peer's environment so its own bootstrapper runs."""


def peer_env() -> dict[str, str]:
    """This process's environment without :data:`BOOTSTRAP`."""
    return {k: v for k, v in os.environ.items() if k not in BOOTSTRAP}


@cache
def _imports_rclpy(python: str) -> bool:
    """``python`` imports rclpy and the messages the node uses."""
    code = "import rclpy.node, geometry_msgs.msg, nav_msgs.msg, sensor_msgs.msg"
    result = subprocess.run(
        [python, "-c", code], capture_output=True, check=False, timeout=60, env=peer_env()
    )
    return result.returncode == 0


def interpreter(distro: str) -> str:
    """The Python with ``distro``'s rclpy, or skip with the reason."""
    if distro == "jazzy":
        if importlib.util.find_spec("rclpy") is None:
            pytest.skip(
                "rclpy (Jazzy) is not installed: the test-only extra, pip install 'omnibot[ros2-test]'"
            )
        return sys.executable
    if not KILTED.exists():
        pytest.skip(f"ROS 2 Kilted's rclpy is not installed in {KILTED.parent.parent}: make ros2-kilted")
    if not _imports_rclpy(str(KILTED)):
        pytest.skip(f"ROS 2 Kilted's rclpy in {KILTED.parent.parent} does not import: make ros2-kilted")
    return str(KILTED)
