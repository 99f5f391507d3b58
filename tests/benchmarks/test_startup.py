"""The start-up benchmark's measures run (the figures are BENCHMARKS.md's business, not a test's)."""

from __future__ import annotations

from benchmarks.startup import ROOT, best, command_cpu


def test_command_cpu_measures_a_finished_command() -> None:
    cpu, wall = command_cpu(ROOT / "src", ["--help"])
    assert cpu > 0 and wall > 0
    assert best([(0.5, 2.0), (0.3, 3.0)]).split() == ["0.30", "s", "CPU", "(", "2.00", "s", "wall)"]
