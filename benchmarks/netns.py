"""Run a ROS 2 benchmark inside a private network namespace (``unshare -n``, ``lo`` up), as the tests
do: DDS never reaches a real network. :func:`ensure_private` re-executes the benchmark there, or says
why it cannot and returns the exit status to use."""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys

from omnibot.ros2.netns import in_private_namespace

MARK = "OMNIBOT_BENCH_NETNS"


def ensure_private(module: str, argv: list[str]) -> int | None:
    """None when this process may start DDS (it is in a private namespace); else run ``python -m
    module argv`` in a new one and return its exit status (0 with the reason printed when no namespace
    can be made: the benchmark is skipped, never run on the host's network)."""
    if in_private_namespace():
        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        return None
    if os.environ.get(MARK):
        print(f"{module}: skipped: the namespace made for it still has other interfaces than lo")
        return 0
    if importlib.util.find_spec("cyclonedds") is None:
        print(f"{module}: skipped: cyclonedds is not installed (pip install 'omnibot[ros2]')")
        return 0
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        print(f"{module}: skipped: unshare or ip is missing (no private network namespace for DDS)")
        return 0
    probe = subprocess.run(["unshare", "-n", "true"], capture_output=True, text=True, check=False)
    if probe.returncode != 0:
        print(f"{module}: skipped: cannot make a private network namespace: {probe.stderr.strip()}")
        return 0
    env = dict(os.environ, **{MARK: "1"})
    command = 'ip link set lo up && exec "$0" -m "$@"'
    return subprocess.call(["unshare", "-n", "sh", "-c", command, sys.executable, module, *argv], env=env)
