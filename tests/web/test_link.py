"""The robot link, period by period with no thread: driving, the deadman, e-stop, teach hook."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest

from omnibot.client import RobotClient
from omnibot.errors import LinkError
from omnibot.motion import Twist
from omnibot.robot import load_robot
from omnibot.teleop import Pacer
from omnibot.web.inbox import PageGone
from omnibot.web.link import RobotLink
from omnibot.web.messages import Drive, EStop, Joy, Resume, Teach
from tests.runtime.test_wakeup import Pushed
from tests.teleop.fakes import FakeWall, truth


class Stepper:
    """Runs a RobotLink's periods by hand on a fake wall clock (simulated time follows it)."""

    def __init__(self, link: RobotLink) -> None:
        self.link = link
        self.wall = FakeWall()
        link.setup()
        self.pacer = Pacer(link.client, link.config.period, wall=self.wall, sleep=self.wall.sleep)
        self.frames: list[dict[str, Any]] = []

    def run(self, seconds: float, request: Any = None) -> dict[str, Any]:
        """Run ``seconds``, submitting ``request`` every period (as a page repeats its input)."""
        end = self.wall() + seconds
        while self.wall() < end - 1e-9:
            if request is not None:
                self.link.submit(request)
            self.link.tick(self.wall())
            self.pacer.wait()
        while not self.link.outbox.empty():
            self.frames.append(self.link.outbox.get_nowait())
        states = [f for f in self.frames if f["type"] == "state"]
        return states[-1]

    def logs(self) -> list[str]:
        return [f["text"] for f in self.frames if f["type"] == "log"]


@pytest.fixture
def stepper() -> Iterator[Stepper]:
    client = RobotClient.open("sim://omni4?world=room&seed=1", timeout=0.5)
    link = RobotLink(client, load_robot("omni4"))
    yield Stepper(link)
    link.stop()  # no thread: closes the client
    assert client.link.closed


def speed(stepper: Stepper) -> float:
    twist = truth(stepper.link.client).twist
    return float(abs(twist.vx) + abs(twist.vy) + abs(twist.w) * 0.1)


def test_drive_then_let_go(stepper: Stepper) -> None:
    x0 = truth(stepper.link.client).pose.x
    state = stepper.run(1.0, Drive(type="drive", vx=0.5))
    assert state["drive"]["state"] == "driving" and state["drive"]["twist"] == [0.495, 0.0, 0.0]
    assert truth(stepper.link.client).pose.x - x0 > 0.3
    state = stepper.run(0.6, Drive(type="drive", enable=False))
    assert state["drive"]["ended"] == "released"
    assert speed(stepper) < 0.01
    assert state["pose_source"] == "truth" and state["link"]["tel_hz"] > 15


@pytest.mark.parametrize(("gone", "why"), [(PageGone(), "lost"), (None, "quiet")])
def test_a_page_that_goes_away_or_quiet_stops_the_robot(stepper: Stepper, gone: Any, why: str) -> None:
    stepper.run(0.5, Drive(type="drive", vx=0.5))
    if gone is not None:
        stepper.link.submit(gone)
    state = stepper.run(1.0)  # nothing more from the page
    assert state["drive"]["ended"] == why
    assert speed(stepper) < 0.01


def test_estop_ignores_driving_until_resume(stepper: Stepper) -> None:
    stepper.run(0.5, Drive(type="drive", vx=0.5))
    stepper.link.submit(EStop(type="estop"))
    state = stepper.run(0.5, Drive(type="drive", vx=0.5))
    assert state["drive"]["state"] == "estop" and speed(stepper) < 0.01
    stepper.link.submit(Resume(type="resume"))
    state = stepper.run(0.3, Drive(type="drive", vx=0.5))
    assert state["drive"]["state"] == "driving"
    assert any("emergency stop" in text for text in stepper.logs())


def test_gamepad_goes_through_the_teleop_mapping(stepper: Stepper) -> None:
    # browser axes: up negative; seed 003: axis 3 (joy convention) times -3.5, limited to 0.99 m/s,
    # reached at the robot's 2 m/s^2 within 0.5 s
    state = stepper.run(0.6, Joy(type="joy", axes=[0, 0, 0, 1.0], buttons=[0.0] * 7 + [1.0]))
    assert state["drive"]["source"] == "gamepad"
    assert state["drive"]["twist"] == [0.99, 0.0, 0.0]
    state = stepper.run(0.5, Joy(type="joy", axes=[0, 0, 0, 1.0], buttons=[0] * 8))  # enable let go
    assert state["drive"]["ended"] == "released"


def test_teach_without_a_teacher_says_it_is_not_enabled(stepper: Stepper) -> None:
    stepper.link.submit(Teach(type="teach", action="record"))
    state = stepper.run(0.1)
    assert state["drive"]["teach"] is False
    assert any("not enabled on this dashboard" in text for text in stepper.logs())


class RecordingTeacher:
    """A stand-in teacher that records how the link calls it."""

    def __init__(self) -> None:
        self.calls: list[str] = []
        self.poses: list[Any] = []
        self.runtime: Any = None

    def attach(self, runtime: Any, pose: Any) -> None:
        self.runtime = runtime
        self.poses.append(pose)

    def command(self, action: str, pose: Any) -> str:
        self.calls.append(action)
        return f"{action} ok"

    @property
    def following(self) -> bool:
        return self.calls[-1:] == ["follow"]


def test_teach_hook_joins_the_runtime_in_the_link_thread() -> None:
    client = RobotClient.open("sim://omni4?world=room", timeout=0.5)
    teacher = RecordingTeacher()
    link = RobotLink(client, load_robot("omni4"), teach=teacher)
    try:
        stepper = Stepper(link)
        assert teacher.runtime is link.runtime  # attached once, at setup
        assert teacher.poses[-1][:2] == pytest.approx((1.0, 1.0), abs=0.01)
        link.submit(Teach(type="teach", action="follow"))
        state = stepper.run(0.2)
        assert state["drive"]["state"] == "following"
        assert teacher.calls == ["follow"]
        assert "follow ok" in stepper.logs()
    finally:
        link.stop()


def test_the_pose_is_labelled_by_what_it_is(stepper: Stepper) -> None:
    state = stepper.run(0.2)
    assert state["pose_source"] == "truth" and state["pose"][:2] == [1.0, 1.0]  # the room's start
    stepper.link._device = None  # as on a real link: no simulator behind it
    state = stepper.run(0.2)
    assert state["pose_source"] == "odometry"
    assert state["pose"] == state["odometry"]


def test_a_link_lost_for_good_ends_the_link_thread(monkeypatch: pytest.MonkeyPatch) -> None:
    """The cable pulled and the port not back: the thread ends and says why (the command then exits
    1); it used to retry every period for ever, the dashboard serving a dead robot and exiting 0."""
    client = RobotClient.open("sim://omni4?world=room&seed=1", timeout=0.5)
    wall = FakeWall()
    link = RobotLink(client, load_robot("omni4"), wall=wall, sleep=wall.sleep)

    def unplugged(*args: object) -> bytes:
        raise LinkError("unplugged by the test")

    monkeypatch.setattr(client.link, "_read", unplugged)
    monkeypatch.setattr(client.link, "_write", unplugged)  # and sim:// cannot be reopened
    link.start()
    try:
        assert link._thread is not None
        link._thread.join(timeout=60)
        assert not link.alive, "the link thread is still retrying a link that is gone"
    finally:
        link.stop()
    assert link.ended == "unplugged by the test"
    texts = []
    while not link.outbox.empty():
        frame = link.outbox.get_nowait()
        texts += [frame["text"]] if frame["type"] == "log" else []
    assert "robot link ended: unplugged by the test" in texts


def test_a_source_that_wakes_is_answered_between_the_pages_cycles() -> None:
    """ROS 2's cmd_vel beside the page (``run --ros2 --dashboard``): a source that wakes the runtime has
    its command sent as it arrives, by the link thread's wait, not at the next cycle."""
    client = RobotClient.open("sim://omni4?world=room&seed=1", timeout=0.5)
    link = RobotLink(client, load_robot("omni4"))
    source = Pushed()
    link.runtime.add_source(source)
    link.start()
    try:
        deadline = time.monotonic() + 20
        while link.runtime.reactions == 0 and time.monotonic() < deadline:
            source.push(Twist(0.1, 0.0, 0.0))
            time.sleep(0.05)
        assert link.runtime.reactions > 0 and link.runtime.wakeup.wakes > 0
    finally:
        link.stop()
    assert client.link.closed
