"""One suite, both backends (``--ros-backend rclpy`` and ``dds``), against a genuine rclpy (Jazzy, and
Kilted where its venv exists; each on its default rmw, Fast DDS) in a private network namespace.

Each (backend, distro) is one run of ``omnibot ros2`` beside :mod:`tests.ros2.rclpy_operator`; the
tests read what the operator saw. The backend and the distribution are in every test id.
"""

from __future__ import annotations

import itertools
import json
import textwrap
from typing import Any

import pytest

from tests.ros2.netns_helper import run_in_namespace
from tests.ros2.rclpy_distros import BOOTSTRAP, DISTROS, NODE, interpreter

OPERATOR = NODE.with_name("rclpy_operator.py")
BACKENDS = ("rclpy", "dds")
STALL = 1.0
"""s the bridge is stopped (SIGSTOP) for."""

RUN = r"""
import json, os, subprocess, sys, time
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
bridge = subprocess.Popen(
    [sys.executable, "-m", "omnibot", "ros2", "--ros-backend", BACKEND, "--port", "sim://omni4", "--duration", "240"],
    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
)
env = dict(os.environ)
if PEER:  # another distribution's interpreter: its own bootstrapper sets its library path, and it
    # imports nothing of omnibot (nor of this interpreter's paths)
    env = {k: v for k, v in env.items() if k not in (*BOOTSTRAP, "PYTHONPATH")}
plan = json.dumps({"pid": bridge.pid, "backend": BACKEND, "stall": STALL})
try:
    peer = subprocess.run([PYTHON, OPERATOR, plan], capture_output=True, text=True, env=env, timeout=400)
finally:
    bridge.terminate()
    out, _ = bridge.communicate(timeout=30)
lines = peer.stdout.strip().splitlines()
result = json.loads(lines[-1]) if peer.returncode == 0 and lines else {"error": peer.stderr[-3000:]}
result["bridge"] = out[-4000:]
print(json.dumps(result))
"""

_RUNS: dict[tuple[str, str], dict[str, Any]] = {}


@pytest.fixture(params=[(b, d) for b in BACKENDS for d in DISTROS], ids=lambda p: f"{p[0]}-{p[1]}")
def run(request: pytest.FixtureRequest) -> dict[str, Any]:
    """What the operator of ``distro`` saw of the bridge on ``backend`` (one run per pair)."""
    backend, distro = request.param
    python = interpreter(distro)
    if (backend, distro) not in _RUNS:
        script = textwrap.dedent(
            f"""
            BACKEND = {backend!r}
            PYTHON = {python!r}
            PEER = {distro != "jazzy"!r}
            BOOTSTRAP = {list(BOOTSTRAP)!r}
            OPERATOR = {str(OPERATOR)!r}
            STALL = {STALL!r}
            """
        )
        result = json.loads(run_in_namespace(script + RUN, timeout=500).stdout.strip().splitlines()[-1])
        _RUNS[backend, distro] = {"backend": backend, "distro": distro, **result}
    result = _RUNS[backend, distro]
    assert "error" not in result, result
    return result


def test_the_node_is_in_the_graph_by_its_name(run: dict[str, Any]) -> None:
    """``ros2 node list`` shows ``/omnibot``; the first status line names node and backend."""
    assert run["odom_seen"], run["bridge"]
    assert ["omnibot", "/"] in run["nodes"], run["nodes"]
    assert f"node /omnibot on the {run['backend']} backend" in run["bridge"], run["bridge"]


def test_topic_info_names_the_node_as_odoms_publisher(
    run: dict[str, Any], request: pytest.FixtureRequest
) -> None:
    """``ros2 topic info -v /odom`` names ``omnibot`` as the publisher. Kilted's rmw_fastrtps lists the
    dds backend's node (its ros_discovery_info is taken) but files the writers it discovered under an
    all-zero participant GID (Fast DDS 3.2 leaves ``participant_guid`` unknown for a vendor that omits
    PID_PARTICIPANT_GUID, as cyclonedds does), so none is paired with the node (Jazzy's takes the
    participant from the GUID): not fixable on our side, docs/ros2.md."""
    if run["backend"] == "dds" and run["distro"] == "kilted":
        request.applymarker(
            pytest.mark.xfail(
                strict=True,
                reason="Fast DDS 3.2 (Kilted) gives cyclonedds' endpoints no participant GID to pair them by",
            )
        )
    assert run["odom_publishers"] == [["omnibot", "/"]], run["odom_publishers"]


def test_parameters_through_rclpys_parameter_client(run: dict[str, Any]) -> None:
    """rclpy: ``cmd_vel_timeout`` is read and set; a bad value and a read-only option are refused with
    their reasons; ``use_sim_time`` is true (the robot is simulated). dds: no parameter services."""
    if run["backend"] == "dds":
        assert run["parameter_services"] is False
        return
    assert run["parameter_services"] is True, run
    assert run["timeout_before"][0] == 0.5
    assert run["set_timeout"] == [True, ""]
    assert run["timeout_after"][0] == 0.8
    assert run["set_negative"][0] is False
    assert "positive number of seconds" in run["set_negative"][1], run["set_negative"]
    assert run["set_robot"][0] is False and "read-only" in run["set_robot"][1], run["set_robot"]
    assert run["robot"][1] == "omni4"
    assert run["use_sim_time"][2] is True


def test_reset_odometry_answers_a_fast_dds_client(run: dict[str, Any]) -> None:
    """The operator's rmw is Fast DDS: the rclpy backend's service answers it."""
    if run["backend"] == "dds":
        pytest.skip("the dds backend's services answer rmw_cyclonedds clients only (docs/ros2.md)")
    if run["reset"] == "no std_srvs":
        pytest.skip(
            f"std_srvs is not installed for {run['distro']}'s rclpy (pip install 'omnibot[ros2-test]')"
        )
    success, message = run["reset"]
    assert success is True and "reset by reset_odometry" in message, run["reset"]


def test_twist_and_twist_stamped_publishers_both_drive(run: dict[str, Any]) -> None:
    """0.2 m ahead on Twist, then 0.2 m to the left on TwistStamped, as the odometry says."""
    (x0, y0), (x1, y1), (x2, y2) = run["drive"]
    assert x1 - x0 > 0.2 and abs(y1 - y0) < 0.05, run["drive"]
    assert y2 - y1 > 0.2 and abs(x2 - x1) < 0.05, run["drive"]


def test_a_sim_time_subscriber_sees_monotonic_stamps_through_a_stall(run: dict[str, Any]) -> None:
    """The bridge stopped for 1 s: odom's stamps never go back, ``/clock`` came, and on the
    subscriber's sim-time clock every message after the stall is fresh (its wall clock would call
    them a stall late)."""
    stamps = run["stamps"]
    assert run["clocks"] > 0
    assert all(b > a for a, b in itertools.pairwise(stamps)), "a stamp went back"
    stall = run["stall"]
    after = [o for o in stall["odom"] if o["wall"] > stall["resumed"] + 500_000_000]
    assert len(after) > 10, stall
    ages = [(o["sim"] - o["stamp"]) / 1e9 for o in after]
    walls = [(o["wall"] - o["stamp"]) / 1e9 for o in after]
    print(f"after the stall: sim-time age max {max(ages):.3f} s, wall-clock age min {min(walls):.3f} s")
    assert max(abs(a) for a in ages) < 0.3, ages
