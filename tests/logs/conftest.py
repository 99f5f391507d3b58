"""A recorded run for the log tests: the simulated omni4 in lockstep, driven with VEL at 100 Hz with
telemetry at 100 Hz, recorded by :class:`omnibot.logs.recorder.Recorder` fed by the client."""

from __future__ import annotations

import math
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from omnibot.client import EventRecorder, RobotClient
from omnibot.client.events import Telemetry
from omnibot.client.session import guarded
from omnibot.logs.recorder import Recorder
from omnibot.protocol.messages import Vel
from omnibot.robot.description import load_robot
from omnibot.transport.device import find_simulator

REPO = Path(__file__).resolve().parents[2]
READERS = REPO / ".cache" / "mcap-readers"


@dataclass
class RecordedRun:
    path: Path
    vels: list[Vel] = field(default_factory=list)
    telemetry: list[Telemetry] = field(default_factory=list)
    tx: bytes = b""
    truth: list[tuple[float, float, float]] = field(default_factory=list)
    """The simulator's pose when each telemetry sample was read."""
    counts: dict[str, int] = field(default_factory=dict)


def drive(path: Path, seconds: float = 2.0, *, binary: bool = False) -> RecordedRun:
    """Drive a curve with VEL every 10 ms for ``seconds`` (simulated) and record it into ``path``."""
    robot = load_robot("omni4")
    client = RobotClient.open("sim://omni4?seed=3", robot)
    rec = Recorder(path)
    events = EventRecorder()
    run = RecordedRun(path)
    sent: list[bytes] = []

    class TxSpy:
        def link_bytes(self, t: float, kind: str, data: bytes = b"", note: str = "") -> None:
            if kind == "TX":
                sent.append(data)

        def message(self, t: float, direction: str, message: object) -> None:
            pass

    with guarded(client, robot=robot):
        rec.attach(client, robot)
        client.add_tracer(TxSpy())
        client.add_listener(events, Telemetry)
        sim = find_simulator(client.link)
        assert sim is not None
        client.on_telemetry(lambda _: run.truth.append((sim.pose.x, sim.pose.y, sim.pose.theta)))
        if binary:
            client.use_binary()
        client.telemetry(0.01)
        steps = round(seconds / 0.01)
        for i in range(steps):
            vx = 0.3 * math.sin(math.pi * i / steps)
            cmd = client.vel(vx, 0.1, 0.5, 0.2)
            run.vels.append(cmd)
            client.sleep(0.01)
    rec.close()
    run.telemetry = events.of(Telemetry)
    run.tx = b"".join(sent)
    run.counts = dict(rec.counts)
    return run


@pytest.fixture(scope="session")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> RecordedRun:
    return drive(tmp_path_factory.mktemp("log") / "run.mcap")


def node_reader() -> Path:
    """The Foxglove reader script, next to the npm packages ``make mcap-readers`` installed."""
    if shutil.which("node") is None or shutil.which("npm") is None:
        pytest.skip("node/npm are not installed: Foxglove's MCAP libraries cannot run")
    if not (READERS / "node_modules" / "@mcap" / "core").is_dir():
        subprocess.run(["make", "-s", "mcap-readers"], cwd=REPO, check=True, timeout=600)
    script = READERS / "read_mcap.mjs"
    shutil.copyfile(REPO / "tests" / "logs" / "node" / "read_mcap.mjs", script)
    return script
