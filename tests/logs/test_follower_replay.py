"""Follower replay: on a log of a live ``omnibot follow`` (and ``run --follow``), the recorded
follower re-run offline on the recorded cycles gives the live follower's commands exactly; another
follower or other options run on the same cycles (open loop) and show what they would have
commanded."""

from __future__ import annotations

import csv
import json
import math
import subprocess
from pathlib import Path
from typing import Any

import pytest
from rosbags.highlevel import AnyReader

from omnibot.cli import main
from omnibot.control import standard_path, write_path
from omnibot.logs import topics
from omnibot.logs.follower_replay import parse_options, recorded_followers, replay_follower
from omnibot.logs.run import load_run
from tests.logs.conftest import RecordedRun, node_reader


@pytest.fixture(scope="module")
def circle(tmp_path_factory: pytest.TempPathFactory) -> Path:
    target = tmp_path_factory.mktemp("path") / "circle.csv"
    write_path(standard_path("circle", size=0.5), target)
    return target


@pytest.fixture(scope="module")
def follow_log(circle: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("follow") / "follow.mcap"
    assert main(["follow", str(circle), "--log", str(path)]) == 0
    return path


def test_the_live_follower_is_reproduced_exactly(follow_log: Path) -> None:
    run = load_run(follow_log)
    (recorded,) = recorded_followers(run)
    assert recorded.follower == "tracker" and recorded.options["rate"] == 100.0
    assert len(recorded.cycles) == len(run.cycles) > 200
    result = replay_follower(recorded)
    assert result.is_live and result.reproduced
    assert result.compared > 200 and result.max_difference == 0.0
    drove = [r for r in result.rows if r.live is not None]
    assert all(r.replayed == r.live for r in drove)
    # what was compared is what went out: each twist the follower asked for was sent as a VEL
    assert len(run.cmd_vel) >= len(drove)


def test_other_options_change_the_commands(follow_log: Path) -> None:
    (recorded,) = recorded_followers(load_run(follow_log))
    softer = replay_follower(recorded, options={"cross": 20.0})
    assert not softer.is_live and not softer.reproduced
    assert 0.0 < softer.max_difference < math.inf
    assert softer.compared == replay_follower(recorded).compared
    assert all(not math.isnan(v) and v > 0 for v in softer.rms[:2])


def test_another_follower_runs_on_the_same_cycles(follow_log: Path) -> None:
    (recorded,) = recorded_followers(load_run(follow_log))
    other = replay_follower(recorded, "pure_pursuit")
    assert other.follower == "pure_pursuit" and other.options == {"rate": 100.0}
    assert len(other.rows) == len(recorded.cycles)
    assert sum(1 for r in other.rows if r.replayed is not None) > 200
    assert other.finished_at is not None  # it reached the path's end on the recorded states


def test_the_command_line(follow_log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["log", "replay", str(follow_log)]) == 0
    out = capsys.readouterr().out
    assert "the live estimate is reproduced exactly" in out
    assert "the live follower's commands are reproduced exactly" in out
    table = tmp_path / "commands.csv"
    argv = ["log", "replay", str(follow_log), "--follower", "seed002", "--commands-csv", str(table)]
    assert main([*argv, "--follower-option", "heading_gains=[3, 0.5, 0.1]"]) == 0
    out = capsys.readouterr().out
    assert "replayed follower seed002 (heading_gains=[3, 0.5, 0.1], rate=100.0)" in out
    assert "open loop" in out
    with table.open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(load_run(follow_log).cycles)
    assert any(r["live_vx"] and r["replay_vx"] and r["live_vx"] != r["replay_vx"] for r in rows)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--follower", "magic"], "--follower: unknown follower 'magic'"),
        (["--follower-option", "nope=1"], "--follower-option: follower 'tracker' has no option nope"),
        (["--follower-option", "cross=abc"], "--follower-option: expected KEY=NUMBER"),
        (["--follower-option", "cross"], "--follower-option: expected KEY=VALUE"),
        (["--follower", "seed002", "--follower-option", "heading_gains=[3]"], "--follower-option: seed002: "),
        (["--run", "2"], "--run: "),
    ],
)
def test_bad_replay_options_are_refused_before_anything_runs(
    follow_log: Path, extra: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["log", "replay", str(follow_log), *extra]) == 2
    captured = capsys.readouterr()
    assert message in captured.err and "Traceback" not in captured.err
    assert captured.out == ""  # refused before the estimator's replay printed anything


def test_a_log_without_a_follower(recorded: RecordedRun, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["log", "replay", str(recorded.path), "--follower", "tracker"]) == 2
    assert "has no follower run" in capsys.readouterr().err
    assert main(["log", "replay", str(recorded.path)]) == 0  # the estimator alone, as before
    assert "follower" not in capsys.readouterr().out


def test_run_follow_is_reproduced_too(
    circle: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "run.mcap"
    assert main(["run", "--follow", str(circle), "--port", "sim://omni4", "--log", str(log)]) == 0
    capsys.readouterr()
    (recorded,) = recorded_followers(load_run(log))
    result = replay_follower(recorded)
    assert result.reproduced and result.compared > 100


def test_the_cycles_decode_with_rosbags_and_foxglove(follow_log: Path) -> None:
    with AnyReader([follow_log]) as reader:
        connections = [c for c in reader.connections if c.topic == topics.CYCLE]
        cycles: list[Any] = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections)]
    ours = load_run(follow_log).cycles
    assert [(c.index, c.now, c.x, c.twist.linear.x) for c in cycles] == [
        (c.index, c.now, c.x, c.twist.linear.x) for _, c in ours
    ]
    script = node_reader()
    out = subprocess.run(
        ["node", str(script), str(follow_log)], capture_output=True, text=True, timeout=120, check=True
    ).stdout.splitlines()
    theirs = [json.loads(line) for line in out if '"topic":"/omnibot/cycle"' in line]
    assert len(theirs) == len(ours)
    assert [m["message"]["x"] for m in theirs] == [c.x for _, c in ours]


def test_option_values_are_numbers_bools_or_lists() -> None:
    assert parse_options(["cross=30", "adapt=false", "heading_gains=[4, 0.5, 0.1]"]) == {
        "cross": 30,
        "adapt": False,
        "heading_gains": [4, 0.5, 0.1],
    }
    for bad in ("x=", "x=.inf", "x=[]", "x=[[1]]", "=3"):
        with pytest.raises(ValueError):
            parse_options([bad])
