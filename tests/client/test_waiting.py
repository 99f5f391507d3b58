"""The client's waits (client/waiting.py): on a lockstep link a wait or a sleep reads the bytes a
line at a time, gathered, and does what reading them as they came did, at the same times."""

from __future__ import annotations

import math

from omnibot.client import RobotClient, Telemetry
from omnibot.protocol.messages import Malformed, Message
from omnibot.sim import SimDevice
from omnibot.transport import LockstepLink


class Quiet:
    """A tracer that hears everything and keeps nothing (its presence alone: every read as it came)."""

    def link_bytes(self, t: float, kind: str, data: bytes = b"", note: str = "") -> None:
        pass

    def message(self, t: float, direction: str, message: Message | Malformed) -> None:
        pass


class CountedLink(LockstepLink):
    """A lockstep link that counts its reads, gathered or not."""

    reads = 0
    gathered = 0

    def _read(self, max_bytes: int, timeout: float | None, ends: bytes = b"", most: int = 0) -> bytes:
        self.reads += 1
        self.gathered += bool(ends)
        return super()._read(max_bytes, timeout, ends, most)


def session(traced: bool) -> tuple[list[tuple[float, Telemetry]], object, CountedLink]:
    """TEL every 20 ms through a MOVE, a ROTATE, a VEL and sleeps: each sample with its time."""
    device = SimDevice("omni4", surface="carpet", seed=4)
    link = CountedLink(device)
    samples: list[tuple[float, Telemetry]] = []
    with RobotClient(link, "omni4") as client:
        if traced:
            client.add_tracer(Quiet())
        client.on_telemetry(lambda tel: samples.append((client.clock.now(), tel)))
        client.telemetry(0.02, 0xFF)
        client.move(0.3, 0.5, math.radians(30.0))
        client.rotate(math.pi / 2, math.pi / 2)
        client.wait_idle(10.0)
        client.vel(0.2, 0.1, 0.0, 0.5)
        client.sleep(0.4)
        client.stop()
        client.drain()
        client.sleep(0.3)
    return samples, device.sim.pose, link


def test_waits_gather_lines_and_see_what_reads_as_they_came_saw() -> None:
    samples, pose, link = session(traced=False)
    traced_samples, traced_pose, traced_link = session(traced=True)
    assert samples == traced_samples and pose == traced_pose and len(samples) > 100
    assert link.steps == traced_link.steps
    assert traced_link.gathered == 0 and link.gathered > 100  # a recorder is told every read as it came
    assert link.reads < traced_link.reads / 2
