"""wait_for_controller: HELLO again until a slow-starting controller answers, and say so once."""

from __future__ import annotations

import pytest

from omnibot.client.client import RobotClient
from omnibot.client.greet import wait_for_controller
from omnibot.client.tagging import UNTAGGED_VERDICT
from omnibot.errors import ControllerError, LinkTimeout
from omnibot.transport import LockstepLink


class BootingController:
    """A lockstep controller deaf until ``boot`` s (what arrives before is lost, as in a bootloader),
    greeting with its power-up HELLO at ``boot`` if ``greets``, then answering each HELLO line."""

    tick = 0.001

    def __init__(self, boot: float, greets: bool = False) -> None:
        self.boot, self.greets = boot, greets
        self.time = 0.0
        self.hellos_heard = 0
        self._steps = 0
        self._line = bytearray()
        self._out = bytearray()
        self._greeted = False

    def receive(self, data: bytes) -> None:
        if self.time < self.boot:
            return
        for byte in data:
            self._line.append(byte)
            if byte == 0x0A:
                if b"#" in self._line or b"*" in self._line:  # a tagged question: unknown to it
                    self._out += b"ERROR,23,unknown command\r\n"
                elif self._line.startswith(b"HELLO"):
                    self.hellos_heard += 1
                    self._out += b"HELLO,2,fake,4\r\n"
                self._line.clear()

    def step(self) -> None:
        self._steps += 1
        self.time = self._steps * self.tick
        if self.greets and not self._greeted and self.time >= self.boot:
            self._greeted = True
            self._out += b"HELLO,2,fake,4\r\n"

    def transmit(self) -> bytes:
        out, self._out = bytes(self._out), bytearray()
        return out


def client_of(device: BootingController) -> RobotClient:
    return RobotClient(LockstepLink(device, url="lockstep://booting"))


def test_a_ready_controller_answers_the_first_hello_without_a_notice() -> None:
    notices: list[str] = []
    device = BootingController(boot=0.0)
    with client_of(device) as client:
        hello = wait_for_controller(client, notice=notices.append)
    assert (hello.name, hello.motors) == ("fake", 4)
    # its own, and the plain HELLOs of the tag question (a fake without tags: each round asks one)
    assert device.hellos_heard == 1 + UNTAGGED_VERDICT and notices == []


@pytest.mark.parametrize("greets", [False, True])
def test_a_late_controller_is_asked_again_and_the_wait_is_announced_once(greets: bool) -> None:
    notices: list[str] = []
    device = BootingController(boot=3.5, greets=greets)
    with client_of(device) as client:
        hello = wait_for_controller(client, window=10.0, retry=1.0, notice=notices.append)
        assert hello.name == "fake"
        assert 3.5 <= client.clock.now() < 5.0
        assert all(p.timed_out for p in client.outstanding)  # nobody waits for the unanswered HELLOs
    assert notices == ["waiting for the controller on lockstep://booting (HELLO, up to 10 s)..."]


def test_no_controller_is_a_timeout_that_names_the_link() -> None:
    with client_of(BootingController(boot=1e9)) as client, pytest.raises(LinkTimeout) as caught:
        wait_for_controller(client, window=3.0, retry=1.0)
    assert "no reply to HELLO on lockstep://booting within 3 s" in str(caught.value)


class RefusingController(BootingController):
    """Answers every HELLO with an ERROR (a controller that does not speak this protocol version)."""

    def receive(self, data: bytes) -> None:
        if b"\n" in data:
            self._out += b"ERROR,2,unknown command\r\n"


def test_a_refused_hello_is_the_controllers_error_not_a_wait() -> None:
    notices: list[str] = []
    with client_of(RefusingController(boot=0.0)) as client, pytest.raises(ControllerError):
        wait_for_controller(client, notice=notices.append)
    assert notices == []
