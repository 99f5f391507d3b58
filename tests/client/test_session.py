"""The session guard: the robot on the link, and the controller left as it was found."""

from __future__ import annotations

import os
import signal
import time

import pytest

from omnibot.client.client import RobotClient
from omnibot.client.session import guarded, leave, robot_on_link, robot_session
from omnibot.errors import ConfigError, ControllerError
from omnibot.protocol import codes
from omnibot.robot.description import PRESET_DIR
from omnibot.signals import Terminated, terminate_cleanly
from omnibot.transport import find_device


def test_the_robot_is_the_one_on_the_link(tmp_path: object) -> None:
    assert robot_on_link("omni3", None, "sim://omni3").name == "omni3"
    assert robot_on_link("omni3", str(PRESET_DIR / "omni3.yaml"), "x").name == "omni3"
    with pytest.raises(ConfigError, match="omni4 is the robot 'omni4' but the controller on x is 'omni3'"):
        robot_on_link("omni3", "omni4", "x")
    with pytest.raises(ConfigError, match="'bespoke', which is not a preset: give its description file"):
        robot_on_link("bespoke", None, "x")


def test_robot_session_takes_the_robot_from_hello_and_leaves_mode_and_protocol() -> None:
    with robot_session("sim://mecanum4") as session:
        client = session.client
        device = find_device(client.link)
        assert device is not None
        assert session.robot.name == "mecanum4" and session.hello.motors == 4
        client.mode(closed_loop=True)
        client.use_binary()
        client.telemetry(0.02)
        client.move(1.0, 0.3)
    ctl = device.controller
    assert client.link.closed
    assert ctl.state == codes.STATE_IDLE and ctl.mode == 0 and not ctl.binary and ctl.telemetry.period == 0


class Seen:
    """A recording that notes what it is handed."""

    def __init__(self) -> None:
        self.seen: list[tuple[RobotClient, str | None, bool]] = []

    def attach(self, client: RobotClient, robot: object, guess: bool) -> None:
        self.seen.append((client, getattr(robot, "name", None), guess))


def test_every_client_a_session_opens_goes_to_its_recording() -> None:
    """What the command's --log recorder is handed (omnibot.apps.recording)."""
    rec = Seen()
    seen = rec.seen
    with robot_session("sim://omni3", "omni3", recording=rec) as session:
        assert seen and all(client is session.client for client, _, _ in seen)
        assert (session.client, "omni3", False) in seen  # with its description once the HELLO named it
    with robot_session("sim://omni3", "omni3"):  # a session given no recording is recorded nowhere
        pass
    assert all(client is session.client for client, _, _ in seen)


def test_a_guarded_client_goes_to_its_recording_with_its_robot_guessed() -> None:
    rec = Seen()
    client = RobotClient.open("sim://omni4")
    with guarded(client, recording=rec):
        pass
    assert rec.seen == [(client, None, True)]


def test_guarded_stops_on_error_only_when_asked() -> None:
    client = RobotClient.open("sim://omni4")
    device = find_device(client.link)
    assert device is not None
    with guarded(client, stop="on_error", restore="protocol"):
        client.move(1.0, 0.3)
    assert device.controller.state == codes.STATE_MOVING  # send's policy: a normal end keeps it moving
    client = RobotClient.open("sim://omni4")
    device = find_device(client.link)
    assert device is not None
    with pytest.raises(ControllerError), guarded(client, stop="on_error", restore="protocol"):
        client.move(1.0, 0.3)
        raise ControllerError(36, "boom")
    assert device.controller.state == codes.STATE_IDLE


def test_leave_on_a_closed_link_does_nothing_and_never_raises() -> None:
    client = RobotClient.open("sim://omni4")
    client.close()
    leave(client, 0)  # no exception


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_become_terminated(signum: signal.Signals) -> None:
    """SIGHUP too: an SSH session that drops must not leave the robot driving."""
    before = signal.signal(signal.SIGHUP, signal.SIG_DFL)
    try:
        with pytest.raises(Terminated) as ended, terminate_cleanly():
            os.kill(os.getpid(), signum)
            time.sleep(5)  # pragma: no cover - the handler raises before this ends
        assert ended.value.signum == signum
        assert signal.getsignal(signal.SIGHUP) == signal.SIG_DFL
    finally:
        signal.signal(signal.SIGHUP, before)


def test_a_sighup_ignored_by_nohup_stays_ignored() -> None:
    before = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        with terminate_cleanly():
            assert signal.getsignal(signal.SIGHUP) == signal.SIG_IGN
            os.kill(os.getpid(), signal.SIGHUP)  # ignored: nothing happens
        assert signal.getsignal(signal.SIGHUP) == signal.SIG_IGN
    finally:
        signal.signal(signal.SIGHUP, before)
