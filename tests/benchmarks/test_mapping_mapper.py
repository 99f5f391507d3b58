"""The mapper benchmark runs on a few scans and prints its tables."""

from __future__ import annotations

import pytest

from benchmarks import mapping_mapper


def test_times_the_three_walks_and_scores_the_rebuild(capsys: pytest.CaptureFixture[str]) -> None:
    assert mapping_mapper.main(["--scans", "12", "--repeat", "1"]) == 0
    out = capsys.readouterr().out
    for row in ("| numba | ", "| numpy | ", "| skimage | ", "| the loop | 12 |", "| 10 loops | 120 |"):
        assert row in out
