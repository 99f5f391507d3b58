"""The localisation benchmark runs on a few poses and prints its table."""

from __future__ import annotations

import pytest

from benchmarks import mapping_localise


def test_compares_the_filter_with_and_without_refinement(capsys: pytest.CaptureFixture[str]) -> None:
    assert mapping_localise.main(["--seeds", "1", "--particles", "100", "--poses", "10"]) == 0
    out = capsys.readouterr().out
    assert "| particle filter | 1 |" in out and "| filter + refinement | 1 |" in out and "10 poses" in out
