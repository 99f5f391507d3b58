"""Replay: the recorded estimator re-run offline on the recorded telemetry reproduces the live
estimate exactly; another estimator runs on the same samples; the truth is compared in the
estimate's frame."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from omnibot.cli import main
from omnibot.control import standard_path, write_path
from omnibot.logs.replay import Replay, replay_log, telemetry_of, truth_in_frame
from omnibot.logs.run import Run, load_run
from omnibot.motion import Estimate, Pose2D
from tests.logs.conftest import RecordedRun


def test_replay_reproduces_the_live_estimate_exactly(recorded: RecordedRun) -> None:
    run = load_run(recorded.path)
    result = replay_log(run)
    assert result.estimator == "fused" and len(result.estimates) == len(run.estimate) > 100
    assert result.max_difference == 0.0
    for row, (_, e) in zip(run.estimate_exact, result.estimates, strict=True):
        assert row[1:] == (e.x, e.y, e.theta)


def test_replayed_telemetry_is_the_live_telemetry(recorded: RecordedRun) -> None:
    offline = telemetry_of(load_run(recorded.path))
    assert [t.message for t in offline] == [t.message for t in recorded.telemetry]


def test_another_estimator_is_not_compared(recorded: RecordedRun) -> None:
    result = replay_log(load_run(recorded.path), "encoders")
    assert result.estimator == "encoders" and result.max_difference is None
    assert len(result.estimates) > 100


def test_truth_is_moved_into_the_estimates_frame() -> None:
    # the estimator started at (1, 0, 90 deg) at t=0.1, where the simulator had the robot at (2, 3, 0)
    run = Run(Path("x.mcap"))
    run.truth = [(0.0, 2.0, 3.0, 0.0, 0, 0, 0), (0.1, 2.0, 3.0, 0.0, 0, 0, 0), (0.2, 2.5, 3.0, 0.1, 0, 0, 0)]
    start = Pose2D(1.0, 0.0, math.pi / 2)
    replay = Replay("fused", "fused", [(0.1, Estimate(0.1, 1.0, 0.0, math.pi / 2))], None, start=start)
    moved = truth_in_frame(run, replay)
    assert [r[0] for r in moved] == [0.1, 0.2]
    assert moved[0][1:] == pytest.approx((1.0, 0.0, math.pi / 2))
    assert moved[1][1:] == pytest.approx((1.0, 0.5, math.pi / 2 + 0.1))  # 0.5 m ahead: +y here
    assert truth_in_frame(Run(Path("x.mcap")), replay) == []


def test_replay_of_run_follow_compares_truth_in_the_paths_frame(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the room puts the simulated robot at its start pose; the path starts at the origin
    write_path(standard_path("line", size=0.3), tmp_path / "line.csv")
    log = tmp_path / "run.mcap"
    assert main(["run", "--follow", str(tmp_path / "line.csv"), "--world", "room", "--log", str(log)]) == 0
    run = load_run(log)
    assert math.hypot(run.truth[-1][1], run.truth[-1][2]) > 0.5  # world coordinates: far from the path
    capsys.readouterr()
    assert main(["log", "replay", str(log)]) == 0
    out = capsys.readouterr().out
    error = float(re.search(r"truth at the end \(in the estimate's frame\): .*; error ([0-9.]+) m", out)[1])  # type: ignore[index]
    assert error < 0.02 and "reproduced exactly" in out
