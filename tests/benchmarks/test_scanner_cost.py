"""The scanner-cost benchmark runs (0.5 s runs) and its compiled cast agrees with numpy's."""

from __future__ import annotations

import pytest

from benchmarks import scanner_cost


def test_quick_run_measures_every_case(capsys: pytest.CaptureFixture[str]) -> None:
    assert scanner_cost.main(["--quick"]) == 0
    out = capsys.readouterr().out
    for case in (
        "| 1 robot | room |",
        "| 1 robot | house |",
        "| fleet of 4 | room |",
        "| fleet of 4 | house |",
    ):
        assert case in out
    assert "| 10 |" in out and "| 40 |" in out  # scans per simulated second: one robot, four


def test_the_compiled_cast_gives_numpys_ranges() -> None:
    _, _, _, diff = scanner_cost.ray_casting("house", repeats=2)
    assert diff < 1e-9
