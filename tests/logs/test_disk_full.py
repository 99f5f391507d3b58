"""A ``--log`` whose file cannot grow (a full disk, ``ulimit -f``) stops the recording, never the robot
(issue 27): the follow completes as it does without ``--log``, one warning, no traceback, exit 1, and
what was written before is recovered."""

from __future__ import annotations

import errno
import json
import logging
import os
import resource
import subprocess
import sys
from pathlib import Path as FsPath
from typing import Any

import pytest

import omnibot
from omnibot.cli import main
from omnibot.control import standard_path, write_path
from omnibot.logs.writer import _Direct

KEYS = ("rms_cross_track_m", "max_cross_track_m", "final_error_m", "duration_s")
LIMIT = 64 * 1024
"""Bytes the log's file may grow to: a few chunks, well before the path's end."""


def _path(tmp_path: FsPath) -> FsPath:
    path_file = tmp_path / "c.csv"
    write_path(standard_path("circle", size=0.5), path_file)
    return path_file


def _follow(tmp_path: FsPath, capsys: pytest.CaptureFixture[str], *extra: str) -> tuple[int, Any, str]:
    report = tmp_path / f"r{len(extra)}.json"
    status = main(["follow", str(_path(tmp_path)), "--speed", "0.4", "--report", str(report), *extra])
    return status, json.loads(report.read_text()), capsys.readouterr().err


def _warnings(err: str) -> list[str]:
    return [line for line in err.splitlines() if "warning" in line]


def test_a_full_disk_stops_the_log_not_the_follow(
    tmp_path: FsPath,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
) -> None:
    status, plain, _ = _follow(tmp_path, capsys)
    assert status == 0 and plain["completed"]

    write = _Direct.write

    def full(self: _Direct, data: bytes | memoryview) -> int:
        if self.tell() + len(data) > LIMIT:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return write(self, data)

    monkeypatch.setattr(_Direct, "write", full)
    log = tmp_path / "run.mcap"
    status, logged, err = _follow(tmp_path, capsys, "--log", str(log))
    assert status == 1  # the robot did its job, the log it was asked for is incomplete
    assert logged["completed"]
    for key in KEYS:
        assert logged[key] == pytest.approx(plain[key], abs=0.002), key
    (warning,) = _warnings(err)
    assert "No space left on device" in warning and str(log) in warning
    assert "Traceback" not in err
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING and r.exc_info]
    assert any("recording stopped" in w for w in logged["warnings"])  # the runtime's notice
    assert 0 < log.stat().st_size <= LIMIT
    recovered = tmp_path / "recovered.mcap"
    assert main(["log", "recover", str(log), "-o", str(recovered)]) == 0
    assert recovered.stat().st_size > 0


def test_a_file_size_limit_stops_the_log_not_the_follow(tmp_path: FsPath) -> None:
    """A real process under ``ulimit -f``: the write fails with EFBIG (Python ignores SIGXFSZ)."""
    log, report = tmp_path / "run.mcap", tmp_path / "r.json"

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT, LIMIT))

    src = str(FsPath(omnibot.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": src + os.pathsep + os.environ.get("PYTHONPATH", "")}
    argv = ["follow", str(_path(tmp_path)), "--speed", "0.4", "--report", str(report), "--log", str(log)]
    proc = subprocess.run(
        [sys.executable, "-m", "omnibot", *argv],
        capture_output=True,
        text=True,
        env=env,
        preexec_fn=limit,  # only sets the child's file size limit before exec
        timeout=300,
        check=False,
    )
    assert proc.returncode == 1, proc.stderr[-2000:]
    (warning,) = _warnings(proc.stderr)
    assert "File too large" in warning
    assert "Traceback" not in proc.stderr
    data = json.loads(report.read_text())
    assert data["completed"] and data["rms_cross_track_m"] < 0.015 and data["max_cross_track_m"] < 0.03
    assert log.stat().st_size <= LIMIT
    assert main(["log", "recover", str(log), "-o", str(tmp_path / "recovered.mcap")]) == 0
