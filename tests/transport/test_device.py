"""find_device: the simulator behind any link wrapper (spy+, faults+, both), none behind a real link."""

from __future__ import annotations

import pytest

from omnibot.calibration.truth import simulator_of
from omnibot.client import RobotClient
from omnibot.transport.device import find_device, find_simulator
from omnibot.transport.url import open_link


@pytest.mark.parametrize(
    "url",
    [
        "sim://omni4",
        "spy+sim://omni4",
        "faults+sim://omni4?drop=0",
        "spy+faults+sim://omni4",
        "faults+spy+sim://omni3",
    ],
)
def test_the_simulator_is_found_behind_every_wrapper(url: str) -> None:
    link = open_link(url)
    try:
        device = find_device(link)
        assert device is not None
        assert find_simulator(link) is device.sim
        assert device.sim.robot.name == url.rsplit("//", 1)[1].split("?", maxsplit=1)[0]
        # calibrate --truth sim looks through the same function (it used to miss wrapped links)
        assert simulator_of(RobotClient(link)) is device.sim
    finally:
        link.close()


def test_a_real_link_has_no_device() -> None:
    class Bare:
        inner = None

    assert find_device(Bare()) is None  # type: ignore[arg-type]


def test_a_cycle_of_wrappers_ends() -> None:
    class Loop:
        def __init__(self) -> None:
            self.inner = self

    assert find_device(Loop()) is None  # type: ignore[arg-type]
