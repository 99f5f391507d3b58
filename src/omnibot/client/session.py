"""Leave the controller as you found it: one context manager around a command's use of a robot.

::

    with robot_session(url, "omni3") as s:     # open, HELLO: the robot on the link is the one asked
        s.client.move(...)                     # for; STATUS: the MODE bits it was found in
    # on every way out - the end, an error, Ctrl-C, SIGTERM (see :func:`omnibot.signals.terminate_cleanly`), the link
    # dropping: STOP, telemetry off, MODE back to what it was (text protocol), the link closed

:func:`robot_on_link` decides which robot a command drives: the one the controller names in its
``HELLO`` (``sim://PRESET`` names its preset the same way). ``--robot`` may only name that same
robot (a preset name, or a description file whose ``name`` is the controller's); a mismatch is a
:class:`~omnibot.errors.ConfigError` of one line. :func:`guarded` gives the same exit to a client a
command built itself (the lockstep simulator of ``follow``/``record``/``calibrate``).

Cleanup never raises and never hangs: each command gets :data:`CLEANUP_TIMEOUT` s, and a link that
is gone is just closed.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Literal, Protocol

from omnibot.client.client import DEFAULT_TIMEOUT, RobotClient
from omnibot.client.commands import telem
from omnibot.client.events import Telemetry
from omnibot.client.greet import wait_for_controller
from omnibot.client.limits import Limits
from omnibot.client.views import Hello
from omnibot.errors import ConfigError, LinkError, OmnibotError
from omnibot.progress import notice
from omnibot.protocol import codes
from omnibot.protocol.messages import Mode, Stop
from omnibot.protocol.messages import Telem as TelemCommand
from omnibot.robot import RobotDescription, load_robot, preset_names

CLEANUP_TIMEOUT = 0.5
"""Seconds (link clock) each cleanup command may wait for its reply."""

StopPolicy = Literal["always", "on_error"]
"""``always``: STOP on every way out; ``on_error``: only when the command did not end normally
(``omnibot send`` leaves a MOVE it was asked to send running)."""
RestorePolicy = Literal["mode", "protocol"]
"""``mode``: the MODE bits found at the start come back; ``protocol``: only the text protocol
(``omnibot send 'MODE,2'`` sets a mode on purpose)."""


def _simulated_robot(client: RobotClient, name: str) -> RobotDescription | None:
    """The description a simulated controller on the link runs (``sim://PRESET|FILE``), when it is
    the robot ``name`` its HELLO gave; None on a real link."""
    from omnibot.transport import find_device

    device = find_device(client.link)
    robot = getattr(device, "robot", None)
    return robot if isinstance(robot, RobotDescription) and robot.name == name else None


def robot_on_link(name: str, requested: str | None, where: str) -> RobotDescription:
    """The description of the robot the controller at ``where`` names ``name``; ``requested``
    (``--robot``: a preset or a file) must describe that same robot."""
    if requested is None:
        if name in preset_names():
            return load_robot(name)
        raise ConfigError(
            f"the controller on {where} is '{name}', which is not a preset: give its description file",
            key="--robot",
        )
    robot = load_robot(requested)
    if robot.name != name:
        raise ConfigError(
            f"{requested} is the robot '{robot.name}' but the controller on {where} is '{name}'",
            key="--robot",
        )
    return robot


def leave(client: RobotClient, mode: int | None, *, stop: bool = True, telemetry: bool = True) -> None:
    """Put the controller back: STOP (if ``stop``), telemetry off (if ``telemetry``), MODE ``mode``
    (None: only back to the text protocol and without the checked-text bit the client set), then
    close the link. Never raises."""
    try:
        if client.link.closed:
            return
        with contextlib.suppress(OmnibotError, OSError):
            # replies still owed to the interrupted command would be taken for ours (text matching)
            client.drain(CLEANUP_TIMEOUT)
        commands: list[Stop | TelemCommand | Mode] = []
        if stop:
            commands.append(Stop())
        if telemetry:
            commands.append(telem(client.limits, 0.0))
        if mode is not None:
            # the mode found, without the checked- and sequenced-text bits this client set (found clear)
            commands.append(Mode(mode & ~(codes.MODE_BINARY | client.added_text_bits)))
        elif client.binary or client.added_text_bits:
            # back to text and without the text bits this client set, the other bits kept
            known = client.mode_bits if client.mode_bits is not None else codes.MODE_BINARY
            commands.append(Mode(known & ~(codes.MODE_BINARY | client.added_text_bits)))
        for command in commands:
            if client.link.closed:
                break
            with contextlib.suppress(OmnibotError, OSError):
                client.execute(command, CLEANUP_TIMEOUT)
    finally:
        client.close()


class ClientRecording(Protocol):
    """Where a command records the clients its sessions open (its ``--log`` / ``--foxglove``
    recording, :class:`omnibot.logs.recording.Recording`): handed in, so the client knows nothing of logs."""

    def attach(self, client: RobotClient, robot: RobotDescription | None, guess: bool) -> None:
        """Record ``client`` (its ``robot``; ``guess``: the robot its HELLO names rather than one given)."""


@contextlib.contextmanager
def guarded(
    client: RobotClient,
    *,
    stop: StopPolicy = "always",
    restore: RestorePolicy = "mode",
    robot: RobotDescription | None = None,
    recording: ClientRecording | None = None,
) -> Iterator[RobotClient]:
    """Run the body with ``client``; on every way out :func:`leave` the controller as it was found.
    With a ``recording`` (``--log``) the client (the robot ``robot``) is recorded in it."""
    try:
        if recording is not None:
            recording.attach(client, robot, True)
        mode = client.status().mode if restore == "mode" else None  # leave() drops the bit 4 it set
    except BaseException:
        client.close()
        raise
    seen = {"tel": False}

    def saw(event: Telemetry) -> None:
        seen["tel"] = True

    client.on_telemetry(saw)
    ended = False
    try:
        yield client
        ended = True
    finally:
        client.remove_listener(saw)
        leave(client, mode, stop=stop == "always" or not ended, telemetry=seen["tel"])


@dataclass(frozen=True)
class RobotSession:
    """A command's robot: the client, the robot's description and the controller's HELLO."""

    client: RobotClient
    robot: RobotDescription
    hello: Hello


def open_robot(
    url: str,
    robot: str | RobotDescription | None = None,
    *,
    timeout: float | None = None,
    reconnect: float | None = 0.0,
    recording: ClientRecording | None = None,
) -> RobotSession:
    """Open ``url`` and check that the robot on it is ``robot`` (None: take it from the link). A
    link that cannot be opened, or no HELLO reply, is a ConfigError naming ``--port`` (the command
    could not start: exit status 2). The caller closes the client (or :func:`guarded` does). With a
    ``recording`` (``--log``) the client is recorded from its first byte, with its robot once known."""
    try:
        client = RobotClient.open(
            url, None, timeout=DEFAULT_TIMEOUT if timeout is None else timeout, reconnect=reconnect
        )
    except LinkError as exc:
        raise ConfigError(f"cannot open {url}: {exc}", key="--port") from exc
    try:
        if recording is not None:
            recording.attach(client, None, False)
        try:
            # the versions listed: the reply says whether VEL may carry the planned acceleration
            hello = wait_for_controller(client, codes.VERSIONS, notice=notice)
        except LinkError as exc:
            raise ConfigError(f"no controller answers on {url}: {exc}", key="--port") from exc
        if isinstance(robot, RobotDescription):
            if robot.name != hello.name:
                raise ConfigError(
                    f"the robot is '{robot.name}' but the controller on {url} is '{hello.name}'",
                    key="--robot",
                )
            description = robot
        elif robot is None and (simulated := _simulated_robot(client, hello.name)) is not None:
            description = simulated  # sim://FILE: the file in the URL describes the robot
        else:
            description = robot_on_link(hello.name, robot, url)
        if hello.motors != description.n_wheels:
            raise ConfigError(
                f"the controller on {url} drives {hello.motors} motors, {description.name} has "
                f"{description.n_wheels} wheels",
                key="--robot",
            )
        client.limits = Limits.from_robot(description)
        if recording is not None:
            recording.attach(client, description, False)
    except BaseException:
        client.close()
        raise
    return RobotSession(client, description, hello)


@contextlib.contextmanager
def robot_session(
    url: str,
    robot: str | RobotDescription | None = None,
    *,
    stop: StopPolicy = "always",
    restore: RestorePolicy = "mode",
    timeout: float | None = None,
    reconnect: float | None = 0.0,
    recording: ClientRecording | None = None,
) -> Iterator[RobotSession]:
    """:func:`open_robot`, then :func:`guarded`: the controller is left as it was found (the client
    recorded in ``recording``, if given)."""
    session = open_robot(url, robot, timeout=timeout, reconnect=reconnect, recording=recording)
    with guarded(session.client, stop=stop, restore=restore, recording=recording):
        yield session
