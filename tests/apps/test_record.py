"""``omnibot record``: teach by pushing (seed 002) or by driving, then repeat."""

from __future__ import annotations

from pathlib import Path as FsPath
from typing import Any

import pytest

from omnibot.cli import main
from omnibot.control import PathRecorder, read_path, standard_path
from omnibot.navigation import simulated_client, teach
from omnibot.robot import load_robot
from omnibot.runtime import Runtime
from tests.navigation.test_runner import Drivers


def test_record_by_pushing_then_follow_with_seed002(
    tmp_path: FsPath, capsys: pytest.CaptureFixture[str]
) -> None:
    taught = tmp_path / "taught.csv"
    argv = [
        "record",
        "--path",
        str(taught),
        "--robot",
        "omni3",
        "--shape",
        "line",
        "--size",
        "0.5",
        "--store-speed",
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "pushed by hand along line" in out and "from the true end" in out
    path = read_path(taught)
    assert path.v is not None and path.length == pytest.approx(1.0, abs=0.05)
    assert main(["follow", str(taught), "--robot", "omni3", "--follower", "seed002"]) == 0
    assert "seed002" in capsys.readouterr().out


def test_record_by_driving_and_by_time(tmp_path: FsPath) -> None:
    taught = tmp_path / "driven.csv"
    argv = [
        "record",
        "--path",
        str(taught),
        "--teach",
        "drive",
        "--shape",
        "circle",
        "--size",
        "0.4",
        "--sample-time",
        "0.1",
    ]
    assert main(argv) == 0
    path = read_path(taught)
    assert path.t is not None and path.t[1] == pytest.approx(0.1, abs=0.011)
    assert path.length == pytest.approx(1.26, rel=0.1)


def test_teach_drive_is_a_script_on_the_runtime(monkeypatch: pytest.MonkeyPatch) -> None:
    robot = load_robot("omni4")
    drivers = Drivers()
    runtimes: list[Runtime] = []
    start = Runtime.start

    def watched(runtime: Runtime) -> None:  # every runtime the recording makes: who drove it
        if runtime not in runtimes:
            runtimes.append(runtime)
            runtime.add_sink(drivers)
        start(runtime)

    monkeypatch.setattr(Runtime, "start", watched)
    recorder = PathRecorder("distance", 0.02)
    with simulated_client(robot, seed=1) as client:
        result = teach(client, robot, recorder, mode="drive", shape=standard_path("line", size=0.3))
    assert len(runtimes) == 1 and drivers.sources == {"drive"}
    assert runtimes[0].sent.vel > 100 and runtimes[0].sent.errors == 0
    assert result.path is not None and result.path.length == pytest.approx(0.6, rel=0.05)


@pytest.mark.parametrize("world", ["room", "corridor"])
def test_record_and_follow_in_a_world_start_at_its_start(
    world: str, tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A world with walls has its own start pose: the robot stands there, not at the origin (which
    is inside the room's wall), and a path is followed in its own frame from there."""
    from omnibot.sim import device, load_world

    starts: list[tuple[float, float, float]] = []

    class Spy(device.SimDevice):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            p = self.sim.pose
            starts.append((p.x, p.y, p.theta))

    monkeypatch.setattr(device, "SimDevice", Spy)
    taught = tmp_path / "taught.csv"
    argv = ["record", "--world", world, "--path", str(taught), "--shape", "line", "--size", "0.5"]
    assert main(argv) == 0
    assert main(["follow", str(taught), "--world", world]) == 0
    home = load_world(world).start
    assert home is not None
    assert starts == [pytest.approx((home.x, home.y, home.theta))] * 2
