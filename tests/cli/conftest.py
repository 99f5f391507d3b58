"""The harness of the command-line suite: the simulated controllers a command made, ways to end it.

In-process (``main(argv)`` on ``sim://``): :class:`Harness` records every :class:`SimDevice` the
command builds (so the test can look at the controller afterwards, as a second connection would) and
ends the command the way a test asks, the first time the client waits while the robot is moving
(or after :data:`FALLBACK_PUMPS` waits, for commands that do not move it):

* ``sigint`` / ``sigterm``: a real signal to this process (``signal.raise_signal``), handled by the
  command's own handlers (``main`` turns SIGTERM into a clean exit);
* ``error``: the controller fails a command (ControllerError);
* ``link``: the link is closed under the client;
* ``unplug``: the cable pulled: every read and write of the link fails from then on, and ``sim://``
  cannot be reopened (the error must still say why the link broke, not only that it cannot be opened).

Over the pty emulator (``omnibot sim --pty`` and the command as subprocesses): :class:`PtyRobot`
starts the emulator (this test owns its PID), and :func:`controller_state` asks it for STATUS
through a second connection.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from omnibot.client import RobotClient
from omnibot.errors import ControllerError, LinkError
from omnibot.protocol import codes
from omnibot.sim import SimDevice
from omnibot.transport import find_device

ENDINGS = ("normal", "error", "sigint", "sigterm", "link", "unplug")
FALLBACK_PUMPS = 400
"""Waits after which a command that never moves the robot is ended anyway."""
EXIT = {"normal": 0, "error": 1, "sigint": 130, "sigterm": 143, "link": 1, "unplug": 1}
"""The exit status each way of ending must give (docs/cli.md's command table)."""
ROOT = Path(__file__).resolve().parents[2]


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "slow: subprocess cases over the pty emulator (run in CI too)")


@dataclass
class Harness:
    """Records the simulated controllers and ends the command as :attr:`ending` says."""

    ending: str = "normal"
    devices: list[SimDevice] = field(default_factory=list)
    fired: bool = False
    pumps: int = 0

    def moving(self, client: RobotClient) -> bool:
        device = find_device(client.link)
        if device is None:
            return False
        tw = device.sim.twist
        return math.hypot(tw.vx, tw.vy) > 0.02 or abs(tw.w) > 0.05

    def pump(self, client: RobotClient) -> None:
        """Called before each wait of a client: ends the command once, at the chosen moment."""
        if self.ending == "normal" or self.fired:
            return
        self.pumps += 1
        if not (self.moving(client) or self.pumps > FALLBACK_PUMPS):
            return
        self.fired = True
        if self.ending == "sigint":
            signal.raise_signal(signal.SIGINT)
        elif self.ending == "sigterm":
            signal.raise_signal(signal.SIGTERM)
        elif self.ending == "error":
            raise ControllerError(36, "internal fault (injected by the test)")
        elif self.ending == "link":
            client.link.close()
        elif self.ending == "unplug":

            def unplugged(*args: object) -> bytes:
                raise LinkError("unplugged by the test")

            link: Any = client.link
            link._read = link._write = unplugged

    def controller(self) -> Any:
        """The firmware of the last simulated controller the command made."""
        assert self.devices, "the command made no simulated controller"
        return self.devices[-1].controller

    def assert_left_as_found(self) -> None:
        """Stopped, telemetry off, MODE 0 and the text protocol: what every sim:// starts with."""
        ctl = self.controller()
        assert ctl.state != codes.STATE_MOVING, "the robot was left moving"
        assert ctl.mode == 0, f"the controller was left in MODE {ctl.mode}"
        assert not ctl.binary
        assert ctl.telemetry.period == 0, "telemetry was left on"


@pytest.fixture
def harness(monkeypatch: pytest.MonkeyPatch) -> Iterator[Harness]:
    h = Harness()
    init = SimDevice.__init__

    def recording_init(self: SimDevice, *args: Any, **kwargs: Any) -> None:
        init(self, *args, **kwargs)
        h.devices.append(self)

    pump_once = RobotClient._pump_once

    def pump(self: RobotClient, timeout: float, gather: bool = False) -> int:
        h.pump(self)
        return pump_once(self, timeout, gather)

    monkeypatch.setattr(SimDevice, "__init__", recording_init)
    monkeypatch.setattr(RobotClient, "_pump_once", pump)
    previous = signal.getsignal(signal.SIGINT)
    yield h
    signal.signal(signal.SIGINT, previous)


def assert_one_line_error(err: str, debug: bool = False) -> None:
    """No traceback (unless --debug), and the error itself in one line."""
    if debug:
        assert "Traceback" in err
        return
    assert "Traceback" not in err, err
    errors = [line for line in err.splitlines() if line.startswith("omnibot: ")]
    assert len([e for e in errors if not e.startswith("omnibot: warning")]) <= 1, err


# ------------------------------------------------------------------ the pty emulator


def environment() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT / "src") + os.pathsep + env.get("PYTHONPATH", "")
    env.setdefault("MPLBACKEND", "Agg")
    env.setdefault("SDL_VIDEODRIVER", "dummy")
    return env


class PtyRobot:
    """``omnibot sim --pty`` as a child of this test; ``path`` is its device."""

    def __init__(self, robot: str = "omni4") -> None:
        argv = [sys.executable, "-m", "omnibot", "sim", "--pty", "--robot", robot]
        self.proc = subprocess.Popen(
            argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=environment()
        )
        assert self.proc.stdout is not None
        self.path = self.proc.stdout.readline().strip()
        if not self.path:
            self.close()
            pytest.fail("the pty emulator did not start")

    def kill(self) -> None:
        """The cable pulled: the emulator dies (SIGKILL, the PID this test started)."""
        if self.proc.poll() is None:
            os.kill(self.proc.pid, signal.SIGKILL)
        self.proc.wait(10)

    def close(self) -> None:
        if self.proc.poll() is None:
            os.kill(self.proc.pid, signal.SIGINT)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                os.kill(self.proc.pid, signal.SIGKILL)
                self.proc.wait(10)
        for stream in (self.proc.stdout, self.proc.stderr):
            if stream is not None:
                stream.close()


@pytest.fixture
def pty_robot() -> Iterator[PtyRobot]:
    robot = PtyRobot()
    try:
        yield robot
    finally:
        robot.close()


def controller_state(path: str) -> tuple[int, int]:
    """(state, MODE) of the controller on ``path``, asked through a second connection, in text
    (a controller left in binary mode does not answer: LinkTimeout). Untagged, so that asking sets no
    MODE bit 4 (and a controller left with it refuses the question: ControllerError)."""
    with RobotClient.open(path, timeout=10.0, tags=False) as client:  # the emulator answers late when loaded
        status = client.status()
        client.sleep(0.3)  # still moving after this long means nobody stopped it
        again = client.status()
        return again.state, status.mode


class Command:
    """An ``omnibot`` command as a subprocess (this test owns its PID)."""

    def __init__(self, *argv: str, stdin: bool = False) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "omnibot", *argv],
            stdin=subprocess.PIPE if stdin else subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=environment(),
        )

    def wait_for(self, text: str, timeout: float = 60.0) -> str:
        """Read stdout until a line contains ``text``; the lines read."""
        assert self.proc.stdout is not None
        seen = []
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            line = self.proc.stdout.readline()
            if not line:
                break
            seen.append(line)
            if text in line:
                return "".join(seen)
        pytest.fail(f"{text!r} never came; stdout: {''.join(seen)!r}")

    def signal(self, signum: int) -> None:
        os.kill(self.proc.pid, signum)

    def finish(self, timeout: float = 60.0, stdin: str | None = None) -> tuple[int, str, str]:
        try:
            out, err = self.proc.communicate(stdin, timeout=timeout)
        except subprocess.TimeoutExpired:
            os.kill(self.proc.pid, signal.SIGKILL)
            out, err = self.proc.communicate()
            pytest.fail(f"the command hung; stderr: {err!r}")
        return self.proc.returncode, out, err
