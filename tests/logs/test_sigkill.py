"""A recording killed with SIGKILL mid-run (the ``killed`` fixture: ``omnibot send --log`` killed once
its log holds several chunks): the file is readable up to its last chunk, by our reader and by
Foxglove's stream reader."""

from __future__ import annotations

import itertools
import json
import subprocess
from pathlib import Path

from omnibot.logs import topics
from omnibot.logs.reader import LogFile
from omnibot.protocol import text
from tests.logs.conftest import node_reader


def test_a_killed_run_is_readable_up_to_its_last_chunk(killed: Path) -> None:
    log = LogFile.open(killed)
    messages = log.read_all()
    assert log.cut_short is not None
    lines = [m.decode() for m in messages if m.topic == topics.PROTOCOL]
    tels = [text.parse_line(line.text.encode()) for line in lines if line.keyword == "TEL"]
    assert len(tels) > 100
    times = [t.t_ms for t in tels]  # type: ignore[union-attr]
    assert times == sorted(times) and all(b - a == 10 for a, b in itertools.pairwise(times))
    # each TEL's odometry is written right after it: the chunk the kill cut short may end between
    # the last TEL and its odometry, never earlier
    assert len(tels) - 1 <= sum(1 for m in messages if m.topic == topics.ODOM) <= len(tels)


def test_foxglove_reads_a_killed_run(killed: Path) -> None:
    script = node_reader()
    out = subprocess.run(
        ["node", str(script), str(killed)], capture_output=True, text=True, timeout=120, check=True
    ).stdout.splitlines()
    end = json.loads(out[-1])
    assert end["done"] is False
    ours = LogFile.open(killed).read_all()
    theirs = [json.loads(line) for line in out[:-1] if '"topic"' in line]
    assert len(theirs) == len(ours) > 500
