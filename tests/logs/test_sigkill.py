"""A recording killed with SIGKILL mid-run: the file is readable up to its last chunk, by our reader
and by Foxglove's stream reader."""

from __future__ import annotations

import itertools
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from omnibot.logs import topics
from omnibot.logs.reader import LogFile
from omnibot.protocol import text
from tests.logs.conftest import REPO, node_reader


def kill_mid_run(path: Path) -> None:
    """``omnibot send --log`` a motion that never ends (MOVE INF: until the next command)
    with telemetry at 100 Hz; SIGKILL it once its log holds several chunks."""
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
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and proc.poll() is None:
            if path.exists() and path.stat().st_size > 60_000:
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the run ended by itself"
        assert path.stat().st_size > 60_000, "the log did not grow"
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
    assert proc.returncode == -signal.SIGKILL


@pytest.fixture(scope="module")
def killed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("killed") / "killed.mcap"
    kill_mid_run(path)
    return path


def test_a_killed_run_is_readable_up_to_its_last_chunk(killed: Path) -> None:
    log = LogFile.open(killed)
    messages = log.read_all()
    assert log.cut_short is not None
    lines = [m.decode() for m in messages if m.topic == topics.PROTOCOL]
    tels = [text.parse_line(line.text.encode()) for line in lines if line.keyword == "TEL"]
    assert len(tels) > 100
    times = [t.t_ms for t in tels]  # type: ignore[union-attr]
    assert times == sorted(times) and all(b - a == 10 for a, b in itertools.pairwise(times))
    assert sum(1 for m in messages if m.topic == topics.ODOM) == len(tels)


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
