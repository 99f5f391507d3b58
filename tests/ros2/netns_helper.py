"""Run a Python script in a private network namespace (``unshare -n``, ``lo`` up): the only way a
test may start a DDS participant. Skips, with the reason, where that cannot be done.

The namespace gets its own ``/dev/shm`` too (``unshare -m``, a fresh tmpfs): Fast DDS (the rclpy
peers' rmw) also talks through shared-memory segments and semaphores there, which a network namespace
does not separate; with both private, two tests' participants cannot meet, and ``make test`` may run
the ROS 2 modules on two workers at once (tests/parallel.py)."""

from __future__ import annotations

import functools
import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src"


PRIVATE = "mount -t tmpfs -o mode=1777 omnibot-shm /dev/shm && ip link set lo up"
"""Run first in the new namespaces: a private ``/dev/shm`` (unshare's default propagation is private:
the host's stays as it was) and the loopback interface up."""


@functools.cache
def _unavailable() -> str:
    """Why no private namespace can be made here ("" when one can): probed once per process (an
    ``unshare`` run), not once per script."""
    if importlib.util.find_spec("cyclonedds") is None:
        return "cyclonedds is not installed (pip install 'omnibot[ros2]')"
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return "unshare or ip is missing: no private network namespace for DDS"
    probe = subprocess.run(
        ["unshare", "-n", "-m", "sh", "-c", PRIVATE], capture_output=True, text=True, check=False
    )
    if probe.returncode != 0:
        return f"cannot make a private network and mount namespace (needs root): {probe.stderr.strip()}"
    return ""


def run_in_namespace(script: str, timeout: float = 60.0) -> subprocess.CompletedProcess[str]:
    """Run ``script`` with this interpreter in a new network namespace whose only interface is lo."""
    reason = _unavailable()
    if reason:
        pytest.skip(reason)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(SRC), env.get("PYTHONPATH", "")])
    env.setdefault("PYTEST_CURRENT_TEST", "ros2")  # the guard applies in the child too
    env.pop("ROS_AUTOMATIC_DISCOVERY_RANGE", None)
    command = f'{PRIVATE} && exec "{sys.executable}" -c "$OMNIBOT_SCRIPT"'
    env["OMNIBOT_SCRIPT"] = script
    result = subprocess.run(
        ["unshare", "-n", "-m", "sh", "-c", command],
        capture_output=True,
        text=True,
        env=env,
        timeout=timeout,
        check=False,
    )
    assert result.returncode == 0, f"rc={result.returncode}\n{result.stdout}\n{result.stderr}"
    return result
