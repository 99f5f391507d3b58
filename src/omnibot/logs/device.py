"""``omnibot sim --pty --log``: the simulated controller's side of a run, recorded.

:class:`RecordedDevice` stands in for the device the pty bridge serves and hands the recorder the
bytes both ways (``TX`` what the host wrote, ``RX`` what it will read, as on the host's side) and,
every 10 ms of simulated time, the ground truth (``/omnibot/truth``); the robot description goes in
first. Times are the simulator's clock.
"""

from __future__ import annotations

from typing import Any

from omnibot.logs.recorder import Recorder
from omnibot.logs.topics import TRUTH
from omnibot.motion import Pose2D
from omnibot.robot import RobotDescription
from omnibot.sim import Snapshot

TRUTH_PERIOD = 0.01
"""s of simulated time between two ground-truth records."""


class RecordedDevice:
    """``device`` (a :class:`~omnibot.sim.device.SimDevice`) with its link bytes and truth recorded."""

    def __init__(
        self, device: Any, recorder: Recorder, robot: RobotDescription, url: str = "sim --pty"
    ) -> None:
        self._device = device
        self._recorder = recorder
        recorder.start(robot, url=url, t=device.time)
        device.sim.add_listener(self._truth, period=TRUTH_PERIOD)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._device, name)

    def receive(self, data: bytes) -> None:
        """Record the host's bytes (TX), then hand them to the device."""
        self._recorder.link_bytes(self._device.time, "TX", data)
        self._device.receive(data)

    def transmit(self) -> bytes:
        """Take the device's bytes, recorded as RX."""
        out: bytes = self._device.transmit()
        if out:
            self._recorder.link_bytes(self._device.time, "RX", out)
        return out

    def _truth(self, snap: Snapshot) -> None:
        rec = self._recorder
        rec.write_pose(TRUTH, rec.ns(snap.t), Pose2D(snap.x, snap.y, snap.theta), (snap.vx, snap.vy, snap.w))
