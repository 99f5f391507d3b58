"""The ``path`` source: a nav_msgs/Path repeated by the tracker on the simulated robot, in lockstep
(no DDS: the reader is a stand-in handing over the DDS samples a subscription would)."""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

from omnibot.client import robot_session
from omnibot.logs import header, quaternion, schemas
from omnibot.motion import Estimate, Pose2D
from omnibot.protocol import codes
from omnibot.ros2.odometry import yaw_of
from omnibot.ros2.path import PATH_TYPE, PathSource, path_from_message
from omnibot.ros2.types import to_dds
from omnibot.runtime import Runtime
from omnibot.transport import find_simulator

PERIOD = 0.02


class Reader:
    """A DataReader stand-in: what was put is taken once."""

    def __init__(self) -> None:
        self.samples: list[Any] = []

    def take(self, N: int = 1) -> list[Any]:
        taken, self.samples = self.samples[:N], self.samples[N:]
        return taken


class Node:
    def __init__(self) -> None:
        self.readers: dict[str, Reader] = {}

    def reader(self, name: str, typename: str) -> Reader:
        return self.readers.setdefault(name, Reader())


def pose_message(x: float, y: float, yaw: float | None) -> Any:
    """A geometry_msgs/Pose at (x, y) facing ``yaw`` (None: an all-zero quaternion)."""
    q = (
        quaternion(yaw)
        if yaw is not None
        else schemas.new("geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=0.0, w=0.0)
    )
    return schemas.new(
        "geometry_msgs/msg/Pose",
        position=schemas.new("geometry_msgs/msg/Point", x=x, y=y, z=0.0),
        orientation=q,
    )


def path_message(points: Sequence[tuple[float, float, float | None]], frame: str = "odom") -> Any:
    """A nav_msgs/Path through (x, y, yaw) points (yaw None: an all-zero quaternion)."""
    poses = []
    for x, y, yaw in points:
        pose = pose_message(x, y, yaw)
        poses.append(schemas.new("geometry_msgs/msg/PoseStamped", header=header(0, frame), pose=pose))
    return schemas.new(PATH_TYPE, header=header(0, frame), poses=poses)


def test_yaw_of_a_quaternion() -> None:
    for yaw in (0.0, 0.5, -2.0, math.pi - 0.01):
        assert yaw_of(quaternion(yaw)) == pytest.approx(yaw)
    assert yaw_of(schemas.new("geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=0.0, w=0.0)) is None


def test_a_path_starts_from_the_robot_and_keeps_headings_it_lacks() -> None:
    here = Estimate(0.0, 0.0, 0.0, 0.3)
    path = path_from_message(path_message([(0.5, 0.0, None), (1.0, 0.0, 1.0), (1.5, 0.0, None)]), here)
    assert path is not None
    assert list(path.x) == [0.0, 0.5, 1.0, 1.5]  # a straight run from the robot to the first pose
    assert list(path.theta) == pytest.approx([0.3, 0.3, 1.0, 1.0])
    on_it = path_from_message(path_message([(0.01, 0.0, 0.0), (1.0, 0.0, 0.0)]), Estimate(0.0, 0.0, 0.0, 0.0))
    assert on_it is not None and len(on_it) == 2  # within 2 cm of the first pose: no run to it
    one = path_from_message(path_message([(0.4, 0.2, 0.0)]), here)
    assert one is not None and len(one) == 2
    assert path_from_message(path_message([(math.nan, 0.0, 0.0)]), here) is None


@pytest.fixture(params=[False, True], ids=["own-verdict", "judged"])
def bench(
    request: pytest.FixtureRequest,
) -> Iterator[tuple[Runtime, PathSource, Reader, Any, list[tuple[str, str]]]]:
    """The path source on the simulated omni4, judged on the runtime's cycles (as ``omnibot ros2``
    attaches it) or by its follower alone."""
    with robot_session("sim://omni4?seed=3", "omni4", timeout=0.5) as session:
        from omnibot.estimation import make_estimator

        node = Node()
        said: list[tuple[str, str]] = []
        runtime = Runtime(session.client, period=PERIOD, estimator=make_estimator("fused", session.robot))
        source = PathSource(
            node,  # type: ignore[arg-type]
            session.robot,
            PERIOD,
            odom_frame="r1/odom",
            notify=lambda level, text: said.append((level, text)),
            runtime=runtime if request.param else None,
        )
        runtime.add_source(source)
        runtime.start()
        session.client.telemetry(PERIOD, codes.TEL_MASK)
        yield runtime, source, node.readers["path"], find_simulator(session.client.link), said
        runtime.close()


def _send(reader: Reader, msg: Any) -> None:
    reader.samples.append(to_dds(msg, PATH_TYPE))


def _run(runtime: Runtime, until: Any, seconds: float) -> None:
    for _ in range(int(seconds / PERIOD)):
        runtime.step()
        if until():
            return
        runtime.pacer.wait()


def test_the_tracker_repeats_a_path_and_says_when_it_is_done(bench: Any) -> None:
    runtime, source, reader, sim, said = bench
    _run(runtime, lambda: False, 0.5)  # telemetry: an estimate to start from
    start = sim.pose
    # 0.6 m along x then 0.3 m to the left, heading held: poses every 5 cm in the robot's odom frame
    points = [(0.05 * i, 0.0, 0.0) for i in range(13)] + [(0.6, 0.05 * i, 0.0) for i in range(1, 7)]
    _send(reader, path_message(points, frame="r1/odom"))
    _run(runtime, lambda: source.state not in ("following", "judging"), 30.0)
    assert source.state == "completed", (source.detail, said)
    if source.judge is not None:  # judged as `omnibot follow` judges a run, from the truth
        verdict = "path completed (within 15.0 cm of the path's end, never more than 30.0 cm off it)"
        assert ("info", verdict) in said, said
        assert any(t.startswith("path: RMS") and "[simulator ground truth]" in t for _, t in said), said
    dx, dy = sim.pose.x - start.x, sim.pose.y - start.y
    c, s = math.cos(start.theta), math.sin(start.theta)
    forward, left = c * dx + s * dy, -s * dx + c * dy
    assert forward == pytest.approx(0.6, abs=0.03) and left == pytest.approx(0.3, abs=0.03), (forward, left)
    assert abs(sim.pose.theta - start.theta) < math.radians(3)
    assert ("info", "path received: following 19 poses, 0.90 m") in said, said
    assert any(text.startswith("path completed") for _, text in said), said
    done = source.status()
    assert done.level == 0 and done.message.startswith("completed")
    values = {kv.key: kv.value for kv in done.values}
    assert values["state"] == "completed" and float(values["progress"]) == pytest.approx(0.9, abs=0.05)


def test_a_new_path_replaces_the_old_and_an_empty_one_cancels(bench: Any) -> None:
    runtime, source, reader, sim, said = bench
    _run(runtime, lambda: False, 0.5)
    _send(reader, path_message([(0.1 * i, 0.0, 0.0) for i in range(11)], frame="r1/odom"))
    _run(runtime, lambda: False, 1.0)
    first = source.current
    _send(reader, path_message([(0.0, -0.1 * i, 0.0) for i in range(11)], frame=""))  # no frame: odom
    _run(runtime, lambda: False, 1.0)
    assert source.current is not first and first is not None and first.finished
    assert any(text.startswith("path replaced") for _, text in said), said
    assert source.state == "following"
    _send(reader, path_message([], frame="r1/odom"))
    _run(runtime, lambda: False, 1.0)
    assert source.state == "cancelled" and ("info", "path cancelled: an empty path") in said
    assert math.hypot(sim.twist.vx, sim.twist.vy) < 0.01  # stopped (the follower's watchdog)
    _send(reader, path_message([(1.0, 0.0, 0.0)], frame="map"))
    _run(runtime, lambda: False, 0.2)
    assert said[-1] == ("warn", "path in frame 'map' ignored: only 'r1/odom' is known here (no map)")
    assert source.state == "cancelled"


def test_a_robot_carried_far_off_the_path_is_not_chased_and_the_abort_is_on_the_diagnostics(
    bench: Any,
) -> None:
    runtime, source, reader, sim, said = bench
    _run(runtime, lambda: False, 0.5)
    _send(reader, path_message([(0.1 * i, 0.0, 0.0) for i in range(16)], frame="r1/odom"))
    _run(runtime, lambda: source.progress > 0.3, 10.0)
    here = runtime.estimator.estimate.pose
    runtime.estimator.reset(Pose2D(here.x, here.y + 0.8, here.theta))  # a correction puts it 80 cm off
    _run(runtime, lambda: source.state != "following", 1.0)
    assert source.state == "failed", (source.detail, said)
    assert source.detail.startswith("off the path: 80.0 cm from it"), source.detail
    assert ("warn", f"path NOT completed: {source.detail}") in said, said
    status = source.status()
    assert status.level == 1 and status.message == f"failed: {source.detail}"
    _run(runtime, lambda: False, 0.6)  # braked at its accelerations (2 m/s^2) from 1 m/s
    assert math.hypot(sim.twist.vx, sim.twist.vy) < 0.01  # at rest where it was, not driving back
