"""A recorded run for the log tests: the simulated omni4 in lockstep, driven with VEL at 100 Hz with
telemetry at 100 Hz, recorded by :class:`omnibot.logs.recorder.Recorder` fed by the client."""

from __future__ import annotations

import fcntl
import math
import os
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from omnibot.client import EventRecorder, RobotClient, Telemetry, guarded
from omnibot.logs.recorder import Recorder
from omnibot.protocol.messages import Vel
from omnibot.robot import load_robot
from omnibot.transport import find_simulator

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
    """The Foxglove reader script, next to the npm packages ``make mcap-readers`` installed (again
    when tests/logs/node/package.json changed since, as ``make mcap-readers`` does)."""
    if shutil.which("node") is None or shutil.which("npm") is None:
        pytest.skip("node/npm are not installed: Foxglove's MCAP libraries cannot run")
    wanted = (REPO / "tests" / "logs" / "node" / "package.json").read_bytes()
    installed = READERS / "package.json"
    READERS.mkdir(parents=True, exist_ok=True)
    # one test worker at a time installs the packages or writes the script (pytest -n: the others
    # wait, then find them in place); the script is replaced whole, never seen half written
    with (READERS / ".lock").open("a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if (
            not (READERS / "node_modules" / "@mcap" / "core").is_dir()
            or not installed.is_file()
            or installed.read_bytes() != wanted
        ):
            subprocess.run(["make", "-s", "mcap-readers"], cwd=REPO, check=True, timeout=600)
        script = READERS / "read_mcap.mjs"
        source = (REPO / "tests" / "logs" / "node" / "read_mcap.mjs").read_bytes()
        if not script.is_file() or script.read_bytes() != source:
            staged = script.with_name(f".{script.name}.{os.getpid()}")
            staged.write_bytes(source)
            os.replace(staged, script)
    return script


KILL_AFTER = 200
"""TEL samples the killed run's log must hold (readable) before it is killed: its tests count more
than 100 of them, and more than 500 messages in all."""


def readable_tels(path: Path) -> int:
    """TEL lines in the chunks of a log being written (what a SIGKILL now would leave readable)."""
    from omnibot.logs import topics
    from omnibot.logs.reader import LogFile

    if not path.exists():
        return 0
    messages = LogFile.open(path).read_all()
    return sum(1 for m in messages if m.topic == topics.PROTOCOL and m.decode().keyword == "TEL")


def kill_mid_run(path: Path) -> None:
    """``omnibot send --log`` a motion that never ends (MOVE INF: until the next command)
    with telemetry at 100 Hz; SIGKILL it once its log holds several chunks, with KILL_AFTER TEL
    samples in them (not after a file size: a chunk is written every wall-clock second, and on a
    loaded machine the simulation gets less of it, so as many bytes held fewer samples)."""
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "omnibot",
            "send",
            "--log",
            str(path),
            "TELEM,10,255",
            "MOVE,30000,40,0,0",
            "--wait-idle",
            "--idle-timeout",
            "100000",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
    )
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            if path.exists() and path.stat().st_size > 60_000 and readable_tels(path) >= KILL_AFTER:
                break
            time.sleep(0.2)
        assert proc.poll() is None, "the run ended by itself"
        assert path.stat().st_size > 60_000, "the log did not grow"
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
    assert proc.returncode == -signal.SIGKILL


@pytest.fixture(scope="session")
def killed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A log whose recorder (``omnibot send --log`` in a subprocess) was killed with SIGKILL."""
    path = tmp_path_factory.mktemp("killed") / "killed.mcap"
    kill_mid_run(path)
    return path


def node_script(name: str, where: Path) -> Path:
    """Foxglove reader script ``name`` (tests/logs/node/) copied into ``where``, beside a link to the
    npm packages ``make mcap-readers`` installed (nothing is written where they are)."""
    node_reader()  # node/npm present and the packages installed, else skip
    script = where / name
    shutil.copyfile(REPO / "tests" / "logs" / "node" / name, script)
    modules = where / "node_modules"
    if not modules.exists():
        modules.symlink_to(READERS / "node_modules", target_is_directory=True)
    return script
