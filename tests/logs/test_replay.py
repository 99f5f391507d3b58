"""Replay: the recorded estimator re-run offline on the recorded telemetry reproduces the live
estimate exactly; another estimator runs on the same samples."""

from __future__ import annotations

from omnibot.logs.replay import replay_log, telemetry_of
from omnibot.logs.run import load_run
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
