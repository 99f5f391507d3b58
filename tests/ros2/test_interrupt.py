"""``omnibot ros2`` ends soon after Ctrl-C (issue 27: the bridge took up to 8.5 s to exit on SIGINT),
run in a private network namespace (tests/ros2/netns_helper.py)."""

from __future__ import annotations

import json

import pytest

from tests.ros2.netns_helper import run_in_namespace

EXIT_WITHIN = 5.0
"""s from SIGINT to the exit: 1.2-2.1 s measured on the shared 2-core machine under load (most of it
the interpreter's own teardown), against the 8.5 s issue 27 saw."""

SCRIPT = r"""
import json, os, signal, subprocess, sys, time
bridge = subprocess.Popen(
    [sys.executable, "-m", "omnibot", "ros2", "--port", "sim://omni4", "--ros-backend", BACKEND],
    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
)
lines = []
for line in bridge.stdout:  # up once it names its node
    lines.append(line)
    if line.startswith("ros2: omni4 on sim://omni4"):
        break
time.sleep(1.0)  # a second of cycles: odometry, tf, the clock
start = time.monotonic()
bridge.send_signal(signal.SIGINT)
rest = bridge.communicate(timeout=60)[0]
print(json.dumps({"status": bridge.returncode, "seconds": time.monotonic() - start, "output": "".join(lines) + rest}))
"""


@pytest.mark.parametrize("backend", ["dds", "rclpy"])
def test_the_bridge_ends_soon_after_sigint(backend: str) -> None:
    result = run_in_namespace(SCRIPT.replace("BACKEND", repr(backend)), timeout=120)
    outcome = json.loads(result.stdout.strip().splitlines()[-1])
    assert outcome["status"] == 130, outcome["output"]
    assert "interrupted (SIGINT)" in outcome["output"]
    assert outcome["seconds"] < EXIT_WITHIN, outcome
