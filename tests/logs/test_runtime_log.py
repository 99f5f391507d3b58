"""The recorder as a runtime sink: ``follow --log`` records the arbitration and the follower's own
estimate (from the path's start, not a second estimator's), and ``log replay`` reproduces it."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from omnibot.cli import main
from omnibot.client import Telemetry
from omnibot.control import standard_path, write_path
from omnibot.logs import schemas, sink, topics
from omnibot.logs.reader import LogFile
from omnibot.logs.recorder import Recorder
from omnibot.logs.run import load_run
from omnibot.runtime import Runtime

START = (1.0, 0.5)
"""The path starts here: the recorder's own estimator would start at (0, 0)."""


def test_follow_log_has_the_arbitration_and_the_followers_estimate(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    write_path(standard_path("line", size=0.4), tmp_path / "line0.csv")
    with (tmp_path / "line0.csv").open() as f:
        rows = list(csv.DictReader(f))
    with (tmp_path / "line.csv").open("w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["t", "x", "y", "theta"])
        for r in rows:
            out.writerow([r["t"], float(r["x"]) + START[0], float(r["y"]) + START[1], r["theta"]])

    followers: list[tuple[float, float, float]] = []
    runtimes: list[Runtime] = []
    adopt = sink.RuntimeRecorder.__init__

    def spy(self: sink.RuntimeRecorder, recorder: Recorder, runtime: Runtime) -> None:
        adopt(self, recorder, runtime)
        runtimes.append(runtime)

        def after(tel: Telemetry) -> None:  # what the follower steers by, after each sample
            if tel.encoders is not None and runtime.estimator is not None:
                e = runtime.estimator.estimate
                followers.append((e.x, e.y, e.theta))

        runtime.telemetry_hooks.append(after)

    monkeypatch.setattr(sink.RuntimeRecorder, "__init__", spy)
    log = tmp_path / "follow.mcap"
    assert main(["follow", str(tmp_path / "line.csv"), "--log", str(log), "--out", str(tmp_path / "o")]) == 0
    assert len(runtimes) == 1

    run = load_run(log)
    assert run.metadata[topics.ADOPTED]["start"] == f"{START[0]!r} {START[1]!r} 0.0"
    recorded = [(x, y, theta) for _, x, y, theta in run.estimate_exact]
    assert len(recorded) > 100 and recorded == followers  # the follower's estimate, to the bit
    assert abs(recorded[-1][0] - (START[0] + 0.8)) < 0.02  # in the path's frame

    controls = [m.decode() for m in LogFile.open(log).messages() if m.topic == topics.CONTROL]
    assert controls and controls[0].source == "follower"
    assert controls[0].reason == "follower (priority 10)" and controls[0].lock == ""
    assert controls[0].twist.linear.x > 0

    capsys.readouterr()
    assert main(["log", "replay", str(log)]) == 0
    assert "the live estimate is reproduced exactly" in capsys.readouterr().out
    assert main(["log", "info", str(log)]) == 0
    assert "follower   follower (priority 10)" in capsys.readouterr().out
    assert main(["log", "export", str(log), "--csv", str(tmp_path / "csv")]) == 0
    with (tmp_path / "csv" / "control.csv").open() as f:
        assert [r["source"] for r in csv.DictReader(f)] == [c.source for c in controls]


def test_the_control_schema_is_declared() -> None:
    text = schemas.schema_text(schemas.CONTROL)
    assert text.startswith("builtin_interfaces/Time stamp\nstring source\nstring reason\nstring lock\n")
    assert "\nMSG: geometry_msgs/Twist\n" in text  # its dependencies follow, as rosbag2 writes them


def test_an_estimator_installed_mid_run_is_adopted_and_replayed_exactly(tmp_path: Path) -> None:
    """The dashboard's teach installs its estimator after the runtime started, telemetry flowing."""
    from omnibot.client import RobotClient
    from omnibot.estimation import make_estimator
    from omnibot.logs.replay import replay_log
    from omnibot.motion import Pose2D, Twist
    from omnibot.robot import load_robot
    from omnibot.runtime import ScriptSource

    robot = load_robot("omni4")
    path = tmp_path / "mid.mcap"
    with Recorder(path) as rec, RobotClient.open("sim://omni4?seed=4", robot, timeout=0.5) as client:
        rec.attach(client, robot)
        runtime = Runtime(client, period=0.01, sources=[ScriptSource(lambda t: Twist(0.2, 0.1, 0.3))])
        recording = sink.RuntimeRecorder(rec, runtime)
        runtime.add_sink(recording)
        client.telemetry(0.01)
        runtime.run(duration=0.3)
        assert rec.counts[topics.ESTIMATE] > 10  # the recorder's own estimator, so far
        runtime.estimator = make_estimator("encoders", robot, Pose2D(0.3, 0.2, 0.1))
        runtime.run(duration=0.5)
        runtime.close()
        recording.close()
        client.stop()
    run = load_run(path)
    adopted = run.metadata[topics.ADOPTED]
    assert adopted["name"] == "encoders" and adopted["start"] == "0.3 0.2 0.1"
    replay = replay_log(run)
    assert len(replay.estimates) > 40 and replay.max_difference == 0.0
    assert replay.estimates[0][1].x == pytest.approx(0.3, abs=0.01)


def test_an_unregistered_pose_estimator_is_replayed_by_its_recipe() -> None:
    from omnibot.estimation import PoseEstimator
    from omnibot.robot import load_robot

    robot = load_robot("omni4")
    teach = PoseEstimator(robot, translation="encoders", name="teach")  # as the dashboard's teach makes it
    assert sink.registered_name(teach) == "encoders+gyro"
    raw = PoseEstimator(robot, translation="encoders", heading="gyro", name="mine")
    assert sink.registered_name(raw) == "encoders+raw-gyro"


def test_a_flat_battery_is_in_the_log(tmp_path: Path) -> None:
    """The battery's WARN events (19, 20, 43) and the refused motion (ERROR 44) are in the MCAP log as
    protocol lines, beside the TEL lines that carry the voltage."""
    from omnibot.client import RobotClient
    from omnibot.motion import Twist
    from omnibot.protocol import codes
    from omnibot.robot import load_robot
    from omnibot.runtime import ScriptSource

    robot = load_robot("omni4")
    path = tmp_path / "flat.mcap"
    with Recorder(path) as rec, RobotClient.open("sim://omni4?seed=4", robot, timeout=0.5) as client:
        rec.attach(client, robot)
        runtime = Runtime(client, period=0.01, sources=[ScriptSource(lambda t: Twist(0.2, 0.0, 0.0))])
        client.telemetry(0.05, codes.TEL_BATTERY | codes.TEL_QUEUE)
        client.link.device.sim.physics.battery_charge = [0.0]  # type: ignore[attr-defined]
        runtime.run(duration=5.0)
        assert runtime.latched and runtime.latch_reason == "battery"
        runtime.close()
        client.telemetry(0)
    lines = [m.decode().text for m in LogFile.open(path).messages({topics.PROTOCOL})]
    for code in (codes.W_BATTERY_LOW, codes.W_BATTERY_LIMIT, codes.W_BATTERY_STOP):
        assert f"WARN,{code},{codes.TEXTS[code]}" in lines
    assert any(line.startswith(f"ERROR,{codes.E_BATTERY},") for line in lines)
    assert any(line.startswith("TEL,") and line.endswith(",4,0") for line in lines)  # state 4
