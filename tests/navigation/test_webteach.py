"""Teach and repeat from the dashboard: the link, period by period, with the navigation teacher."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest

from omnibot.client import RobotClient
from omnibot.navigation.session import follower_limits
from omnibot.navigation.webteach import PathTeacher, gains_for
from omnibot.protocol import codes
from omnibot.robot import load_robot
from omnibot.runtime.core import LATCHED_TEXT
from omnibot.web.link import RobotLink
from omnibot.web.messages import Drive, EStop, Teach
from tests.teleop.fakes import truth
from tests.web.test_link import Stepper


@pytest.fixture
def taught() -> Iterator[tuple[Stepper, PathTeacher]]:
    """The simulated omni4 on wood, taught an L: 0.8 s forward, 0.8 s left, then stopped."""
    client = RobotClient.open("sim://omni4?seed=2", timeout=0.5)
    robot = load_robot("omni4")
    teacher = PathTeacher(robot, period=0.05, speed=0.3)
    link = RobotLink(client, robot, teach=teacher)
    stepper = Stepper(link)
    stepper.run(1.0)  # standing: the gyro's bias is learned
    link.submit(Teach(type="teach", action="record"))
    stepper.run(0.8, Drive(type="drive", vx=0.5))
    stepper.run(0.8, Drive(type="drive", vy=0.5))
    stepper.run(0.5, Drive(type="drive", enable=False))
    link.submit(Teach(type="teach", action="stop"))
    stepper.run(0.1)
    yield stepper, teacher
    link.stop()
    assert client.link.closed


def test_teach_records_the_driven_path_in_the_pages_frame(taught: tuple[Stepper, PathTeacher]) -> None:
    stepper, teacher = taught
    path = teacher.path
    assert path is not None and 0.4 < path.length < 1.0
    # the path starts where the page showed the robot and ends where it is
    assert path.start[:2] == pytest.approx((0.0, 0.0), abs=0.01)
    end = truth(stepper.link.client).pose
    assert (path.x[-1], path.y[-1]) == pytest.approx((end.x, end.y), abs=0.02)
    assert any(text.startswith("taught ") for text in stepper.logs())


def test_repeat_drives_back_to_the_start_then_follows_the_path(taught: tuple[Stepper, PathTeacher]) -> None:
    stepper, teacher = taught
    path = teacher.path
    assert path is not None
    stepper.link.submit(Teach(type="teach", action="follow"))
    state = stepper.run(0.5)
    assert state["drive"]["state"] == "following" and state["drive"]["control"] == "repeat"
    assert any("driving" in text and "to its start first" in text for text in stepper.logs())
    trail = []
    for _ in range(200):
        state = stepper.run(0.1)
        p = truth(stepper.link.client).pose
        trail.append((p.x, p.y))
        if state["drive"]["state"] != "following":
            break
    assert state["drive"]["state"] != "following", "the repeat did not finish"
    end = truth(stepper.link.client).pose
    assert math.hypot(end.x - path.x[-1], end.y - path.y[-1]) < 0.02
    # once at the start (after the approach), the robot stays near the taught path
    points = np.array(trail)
    at_start = int(np.argmax(np.hypot(points[:, 0] - path.x[0], points[:, 1] - path.y[0]) < 0.03))
    dist, _ = path.nearest(points[at_start:])
    assert float(np.max(dist)) < 0.035


def test_estop_ends_a_repeat_and_bad_order_is_explained(taught: tuple[Stepper, PathTeacher]) -> None:
    stepper, teacher = taught
    stepper.link.submit(Teach(type="teach", action="follow"))
    stepper.run(0.3)
    stepper.link.submit(EStop(type="estop"))
    state = stepper.run(0.3)
    assert state["drive"]["state"] == "estop" and teacher.source is None
    assert any(t.startswith("repeat ended") and "emergency stop (page)" in t for t in stepper.logs())
    assert teacher.command("record", None).startswith("teaching")
    assert teacher.command("follow", None) == "stop teaching first"
    assert "too short" in teacher.command("stop", None)
    assert teacher.command("stop", None) == "nothing to stop"
    with pytest.raises(ValueError, match="unknown teach action"):
        teacher.command("dance", None)


def test_the_page_takes_over_from_a_repeat_and_hands_back(taught: tuple[Stepper, PathTeacher]) -> None:
    stepper, teacher = taught
    path = teacher.path
    assert path is not None
    stepper.link.submit(Teach(type="teach", action="follow"))
    stepper.run(0.6)
    state = stepper.run(0.4, Drive(type="drive", vy=-0.5))  # the page outranks the repeat
    assert state["drive"]["state"] == "driving" and state["drive"]["control"] == "page"
    assert "page (priority 100) over repeat" in state["drive"]["reason"]
    assert teacher.source is not None and teacher.source.overrides == 1
    stepper.run(1.0, Drive(type="drive", enable=False))  # let go: the stop sequence, then the repeat
    state = stepper.run(0.1)
    assert state["drive"]["control"] == "repeat" and state["drive"]["state"] == "following"
    for _ in range(200):
        state = stepper.run(0.1)
        if state["drive"]["state"] != "following":
            break
    assert teacher.source is None, "the repeat did not finish after it was handed back"
    est = stepper.link.runtime.estimate_now()
    assert est is not None and math.hypot(est.x - path.x[-1], est.y - path.y[-1]) < 0.02
    end = truth(stepper.link.client).pose  # the hard sideways push cost the odometry ~3 cm
    assert math.hypot(end.x - path.x[-1], end.y - path.y[-1]) < 0.05
    stepper.run(0.7)  # judged 0.5 s after its end (settled); a sink's notice reaches the page next cycle
    logs = stepper.logs()
    # judged as `omnibot follow` judges a run: from the simulator's truth, against the tolerances
    assert any(t.startswith("repeat: RMS") and "[simulator ground truth]" in t for t in logs), logs
    assert any(t.startswith("repeat completed (within 15.0 cm of the path's end") for t in logs), logs
    assert teacher.judge is not None and teacher.judge.report is not None
    assert teacher.judge.report["final_error_m"] < 0.05 and teacher.watch is None


def test_gains_scale_with_the_control_period() -> None:
    assert gains_for(0.01)["cross"] == 30.0
    assert gains_for(0.05, follower_limits(load_robot("omni3"), 1.0))["heading"] == pytest.approx(0.2 * 4.0)
    assert gains_for(0.05, follower_limits(load_robot("omni4"), 1.0))["heading"] == pytest.approx(0.2 * 8.0)
    slow = gains_for(0.05)
    assert slow["cross"] * 0.05 < 0.5 and slow["lead"] == pytest.approx(0.065)
    with pytest.raises(ValueError, match="must be positive"):
        PathTeacher(load_robot("omni4"), period=0.0)


def teach_l(url: str) -> tuple[Stepper, PathTeacher]:
    """The L of the ``taught`` fixture, taught on ``url``."""
    client = RobotClient.open(url, timeout=0.5)
    robot = load_robot("omni4")
    teacher = PathTeacher(robot, period=0.05, speed=0.3)
    stepper = Stepper(RobotLink(client, robot, teach=teacher))
    stepper.run(1.0)
    stepper.link.submit(Teach(type="teach", action="record"))
    stepper.run(0.8, Drive(type="drive", vx=0.5))
    stepper.run(0.8, Drive(type="drive", vy=0.5))
    stepper.run(0.5, Drive(type="drive", enable=False))
    stepper.link.submit(Teach(type="teach", action="stop"))
    stepper.run(0.1)
    assert teacher.path is not None
    return stepper, teacher


def test_repeat_reports_a_latched_sonar_stop() -> None:
    stepper, teacher = teach_l("sim://omni4?world=room&seed=2")
    try:
        client = stepper.link.client
        client.sonar(1, period=0.06, stop=5.0)  # every wall is nearer than 5 m: moving latches the stop
        stepper.link.submit(Teach(type="teach", action="follow"))
        state = stepper.run(1.0)
        logs = stepper.logs()
        assert teacher.source is None and state["drive"]["state"] != "following"
        assert state["drive"]["latched"] is True
        assert LATCHED_TEXT in logs
        assert "repeat ended: emergency stop latched on the controller" in logs
        # ending the repeat did not release the latch (no STOP): a fresh input from the page does
        x0 = truth(client).pose.x
        state = stepper.run(0.5, Drive(type="drive", vx=-0.5))
        assert state["drive"]["latched"] is False and truth(client).pose.x < x0 - 0.03
    finally:
        stepper.link.stop()


def test_repeat_reports_a_refused_command() -> None:
    stepper, teacher = teach_l("sim://omni4?world=room&seed=2")
    try:
        client = stepper.link.client
        # only the front sonar armed (too short a stop distance to latch here), and travel it does not
        # cover refused: the repeat's first leg, back to the start, is refused (ERROR 41)
        client.sonar(1, period=0.06, stop=0.05)
        client.mode((client.mode_bits or 0) | codes.MODE_REFUSE_UNCOVERED)
        stepper.link.submit(Teach(type="teach", action="follow"))
        state = stepper.run(1.0)
        logs = stepper.logs()
        assert teacher.source is None and state["drive"]["state"] != "following"
        refused = [line for line in logs if line.startswith("the controller refused VEL")]
        assert refused and "no sonar covers this direction" in refused[0]
        assert any(line.startswith("repeat ended: the controller refused VEL") for line in logs)
        assert state["link"]["errors"] >= 1
    finally:
        stepper.link.stop()
