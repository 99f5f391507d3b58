"""``omnibot log recover``: a log whose recorder was killed with SIGKILL (no summary, no rosbag2
metadata) rewritten whole, then read by readers we did not write that need the summary: rosbags'
AnyReader and Foxglove's indexed reader (@mcap/core's McapIndexedReader under Node.js)."""

from __future__ import annotations

import json
import shutil
import subprocess
from collections import Counter
from pathlib import Path

import pytest
import yaml
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader

from omnibot.cli import main
from omnibot.logs import topics
from omnibot.logs.reader import LogFile
from omnibot.logs.recover import recover
from tests.logs.conftest import RecordedRun, node_script


@pytest.fixture(scope="module")
def recovered(killed: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("recovered") / "killed-recovered.mcap"
    result = recover(killed, out)
    assert result.cut_short is not None and result.messages > 500
    return out


def test_rosbags_reads_every_message_of_a_killed_run(killed: Path, recovered: Path) -> None:
    ours = LogFile.open(killed).read_all()  # the cut file, read up to its last chunk
    with AnyReader([recovered]) as reader:
        theirs = [(c.topic, t, bytes(raw)) for c, t, raw in reader.messages()]
        for connection, _, raw in reader.messages():
            reader.deserialize(raw, connection.msgtype)  # every message decodes
        types = {c.topic: c.msgtype for c in reader.connections}
    assert sorted(theirs) == sorted((m.topic, m.ns, m.data) for m in ours)
    assert types[topics.ODOM] == "nav_msgs/msg/Odometry"
    assert types[topics.PROTOCOL] == "omnibot_msgs/msg/ProtocolLine"


def test_the_recovered_file_has_summary_and_rosbag2_metadata(killed: Path, recovered: Path) -> None:
    ours = Counter(m.topic for m in LogFile.open(killed).read_all())
    with recovered.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.message_count == sum(ours.values())
    info = yaml.safe_load(metadata["rosbag2"]["serialized_metadata"])["rosbag2_bagfile_information"]
    assert info["message_count"] == sum(ours.values())
    assert info["relative_file_paths"] == [recovered.name]
    counted = {t["topic_metadata"]["name"]: t["message_count"] for t in info["topics_with_message_count"]}
    assert counted == dict(ours)
    assert metadata["omnibot"]["robot"] == "omni4"  # the recording's own metadata is kept
    assert LogFile.open(recovered).is_whole()


def test_foxglove_indexed_reader_reads_the_recovered_file(
    killed: Path, recovered: Path, tmp_path: Path
) -> None:
    script = node_script("read_indexed.mjs", tmp_path)
    run = subprocess.run(
        ["node", str(script), str(recovered)], check=False, capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    ours = Counter(m.topic for m in LogFile.open(killed).read_all())
    assert out["topics"] == dict(ours)
    assert out["statistics"] == sum(ours.values())
    assert {"omnibot", "rosbag2"} <= set(out["metadata"])
    cut = subprocess.run(
        ["node", str(script), str(killed)], check=False, capture_output=True, text=True, timeout=120
    )
    assert cut.returncode != 0  # what recover is for: the cut file has no summary to index


def test_the_command_writes_beside_the_log_and_never_overwrites(
    killed: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "run.mcap"
    shutil.copyfile(killed, log)
    assert main(["log", "recover", str(log)]) == 0
    target = tmp_path / "run-recovered.mcap"
    assert target.is_file() and "cut short" in capsys.readouterr().out
    before = target.read_bytes()
    assert main(["log", "recover", str(log)]) == 2  # the target exists
    assert "exists" in capsys.readouterr().err
    assert target.read_bytes() == before and log.read_bytes() == killed.read_bytes()
    assert main(["log", "recover", str(target)]) == 0  # a whole file: nothing to do
    assert "nothing to recover" in capsys.readouterr().out
    assert not (tmp_path / "run-recovered-recovered.mcap").exists()


def test_a_whole_log_rewritten_keeps_every_message(recorded: RecordedRun, tmp_path: Path) -> None:
    out = tmp_path / "again.mcap"
    result = recover(recorded.path, out, force=True)
    assert result.cut_short is None and result.messages == sum(recorded.counts.values())
    again = [(m.topic, m.ns, m.data) for m in LogFile.open(out).read_all()]
    assert again == [(m.topic, m.ns, m.data) for m in LogFile.open(recorded.path).read_all()]


def test_a_file_torn_inside_a_chunk_is_recovered_up_to_it(recorded: RecordedRun, tmp_path: Path) -> None:
    torn = tmp_path / "torn.mcap"
    data = recorded.path.read_bytes()
    torn.write_bytes(data[: len(data) * 3 // 5])  # a disk that filled up in the middle of a chunk
    ours = LogFile.open(torn).read_all()
    assert 0 < len(ours) < sum(recorded.counts.values())
    out = recover(torn, tmp_path / "whole.mcap")
    assert out.cut_short is not None and out.messages == len(ours)
    with AnyReader([out.target]) as reader:
        theirs = [(c.topic, t, bytes(raw)) for c, t, raw in reader.messages()]
    assert sorted(theirs) == sorted((m.topic, m.ns, m.data) for m in ours)


def test_a_log_cut_before_its_first_message_is_not_recovered_as_an_empty_one(
    recorded: RecordedRun, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Nothing to recover is not a recovery: no file written, status 1 and one line saying why."""
    torn = tmp_path / "torn.mcap"
    torn.write_bytes(recorded.path.read_bytes()[:5000])  # killed before its first chunk was written
    assert LogFile.open(torn).read_all() == []
    capsys.readouterr()
    assert main(["log", "recover", str(torn)]) == 1
    said = capsys.readouterr()
    assert said.out == ""
    assert said.err.startswith(f"omnibot: error: {torn}: no message before the cut (the log was cut short: ")
    assert said.err.endswith("): nothing to recover, nothing written\n") and said.err.count("\n") == 1
    assert not (tmp_path / "torn-recovered.mcap").exists()
