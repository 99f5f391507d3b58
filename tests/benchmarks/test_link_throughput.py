"""The throughput benchmark's load: busy processes that end with the block, and bounded arguments."""

from __future__ import annotations

import os

import pytest

from benchmarks import link_throughput
from omnibot.protocol import binary, codes


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def test_busy_processes_end_with_the_block() -> None:
    with link_throughput.busy_processes(2) as pids:
        assert len(pids) == 2 and all(_alive(pid) for pid in pids)
    assert not any(_alive(pid) for pid in pids)


def test_load_is_bounded(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        link_throughput.main(["--load", "9"])
    assert "--load must be 0..8" in capsys.readouterr().err


def test_binary_stream_fills_the_line_with_the_announced_window() -> None:
    """Lockstep (simulated time): the controller announces its window and 300 VEL frames streamed
    within it keep the line full (BENCHMARKS.md: 99.9 %); the window of 32 is what a loaded host needs."""
    with link_throughput.open_line(pty=False) as link:
        link_throughput.switch_to_binary(link)
        window = link_throughput.start_session(link)
        seconds = link_throughput.stream_binary(link, 300, window)
    frame_bytes = len(binary.encode(link_throughput.VEL, seq=1))
    assert window == codes.WINDOW
    assert 300 / seconds / (link_throughput.LINE_BYTES_PER_S / frame_bytes) > 0.99


def test_window_is_bounded(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        link_throughput.main(["--window", str(codes.WINDOW + 1)])
    assert f"--window must be {codes.WINDOW_MIN}..{codes.WINDOW}" in capsys.readouterr().err
