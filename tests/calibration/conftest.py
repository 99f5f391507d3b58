"""Fixtures of the calibration tests: lockstep clients on simulated robots (fixed seeds)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager

import pytest

from omnibot.calibration.runner import Runner
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.truth import SimTruth
from omnibot.client import RobotClient
from omnibot.robot import RobotDescription, load_robot
from omnibot.sim import SimDevice
from omnibot.transport import LockstepLink

Opener = Callable[..., AbstractContextManager[RobotClient]]


@pytest.fixture(scope="session")
def omni4() -> RobotDescription:
    return load_robot("omni4")


@contextmanager
def sim_client(
    robot: RobotDescription,
    surface: str = "wood",
    *,
    true_robot: RobotDescription | None = None,
    seed: int = 3,
    **device: object,
) -> Iterator[RobotClient]:
    """A RobotClient in lockstep with a SimDevice (firmware for ``robot``, physics of ``true_robot``)."""
    dev = SimDevice(robot, true_robot=true_robot, surface=surface, seed=seed, **device)  # type: ignore[arg-type]
    with RobotClient(LockstepLink(dev), robot) as client:
        yield client


@pytest.fixture
def runner(omni4: RobotDescription) -> Iterator[Runner]:
    with sim_client(omni4, "wood") as client:
        tap = TelemetryTap(client, omni4)
        tap.start()
        r = Runner(client, omni4, SimTruth(client.link.device.sim), tap, settle=0.3)  # type: ignore[attr-defined]
        yield r
        r.close()
        tap.stop()
