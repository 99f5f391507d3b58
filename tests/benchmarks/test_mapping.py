"""The mapping benchmarks run on a few scans and poses and print their tables."""

from __future__ import annotations

import pytest

from benchmarks import mapping_localise, mapping_mapper


def test_mapper_benchmark_times_the_three_walks_and_scores_the_rebuild(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert mapping_mapper.main(["--scans", "12", "--repeat", "1"]) == 0
    out = capsys.readouterr().out
    for row in ("| numba | ", "| numpy | ", "| skimage | ", "| the loop | 12 |", "| 10 loops | 120 |"):
        assert row in out


def test_localise_benchmark_compares_the_filter_with_and_without_refinement(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert mapping_localise.main(["--seeds", "1", "--particles", "100", "--poses", "10"]) == 0
    out = capsys.readouterr().out
    assert "| particle filter | 1 |" in out and "| filter + refinement | 1 |" in out and "10 poses" in out
