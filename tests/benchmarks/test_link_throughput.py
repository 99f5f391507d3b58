"""The throughput benchmark's load: busy processes that end with the block, and bounded arguments."""

from __future__ import annotations

import os

import pytest

from benchmarks import link_throughput


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
