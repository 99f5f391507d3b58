"""The robots ``omnibot calibrate`` drives: a fresh simulated robot per surface (:func:`sim_opener`), or
the one on ``--port`` with a person asked to place it on each surface (:func:`port_opener`) and to
lift it onto a stand (:func:`asked_stand`), at a terminal (:func:`terminal_ask`, :func:`check_operator`).
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from typing import TYPE_CHECKING

from omnibot.errors import ConfigError

if TYPE_CHECKING:
    from omnibot.client import ClientRecording, RobotClient
    from omnibot.robot import RobotDescription


def sim_opener(
    robot: RobotDescription,
    name: str,
    seed: int,
    true_robot: RobotDescription | None,
    world: str | None = None,
    recording: ClientRecording | None = None,
) -> Callable[[str], AbstractContextManager[RobotClient]]:
    """surface -> a lockstep client on a fresh simulated robot standing on it (in ``world``, default
    empty), left stopped and in its MODE on the way out, recorded in ``recording`` (``--log``)."""

    @contextmanager
    def open_client(surface: str) -> Iterator[RobotClient]:
        from omnibot.client import RobotClient, guarded
        from omnibot.sim import SimDevice
        from omnibot.transport import LockstepLink

        url = f"sim://{name}?surface={surface}&seed={seed}" + (f"&world={world}" if world else "")
        if true_robot is None:
            client = RobotClient.open(url, robot)
        else:
            device = SimDevice(robot, true_robot=true_robot, surface=surface, seed=seed, world=world)
            client = RobotClient(LockstepLink(device, url=url), robot)
        with guarded(client, recording=recording):
            yield client

    return open_client


OPERATOR_TRUTHS = ("tape",)
"""Truth strategies that ask a person to measure every run."""


def terminal_ask(prompt: str) -> str:
    """``input(prompt)``; ConfigError (not EOFError) when standard input ends."""
    try:
        return input(prompt)
    except EOFError:
        raise ConfigError(f"standard input ended while asking: {prompt.strip()!r}", key="calibrate") from None


def check_operator(reasons: list[str]) -> None:
    """ConfigError when the run needs someone at a terminal (``reasons``) and stdin is not one."""
    if reasons and not sys.stdin.isatty():
        raise ConfigError(
            f"needs a terminal to ask you to {' and to '.join(reasons)} (standard input is not one); "
            "run it on a terminal, or unattended with --yes and a truth that needs no operator",
            key="calibrate",
        )


def port_opener(
    client: RobotClient, ask: Callable[[str], str], placed: bool = False
) -> Callable[[str], AbstractContextManager[RobotClient]]:
    """surface -> the one real controller, after asking the person to put the robot there (except on
    the first surface when the robot is ``placed`` there already)."""
    where: dict[str, str | None] = {"surface": None}  # where the robot stands

    @contextmanager
    def open_client(surface: str) -> Iterator[RobotClient]:
        if where["surface"] is None and placed:
            where["surface"] = surface
        if where["surface"] != surface:
            ask(f"Put the robot on {surface} with about 2 m of free floor around it, then press Enter: ")
            where["surface"] = surface
        yield client

    return open_client


def asked_stand(ask: Callable[[str], str]) -> Callable[[RobotClient, bool], None]:
    """The motor map's stand test on a real robot: ask the person to lift it and to put it back."""

    def lift(client: RobotClient, up: bool) -> None:
        if up:
            ask(
                "Lift the robot onto a stand so that no wheel touches anything (they will spin), then press Enter: "
            )
        else:
            ask("Put the robot back on the floor where it stood, then press Enter: ")

    return lift
