"""The fleet speed benchmark measures every fleet size on a source tree in a fresh interpreter."""

from __future__ import annotations

import json

import pytest
from benchmarks.fleet_speed import ROOT, SIZES, main


def test_every_fleet_size_is_measured_in_each_round(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--src", str(ROOT / "src"), "--rounds", "1", "--steps", "10", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    (runs,) = result["rounds"].values()
    assert len(runs) == 1 and sorted(runs[0]) == [str(k) for k in SIZES]
    assert all(0 < t < 1.0 for t in runs[0].values())
    (summary,) = result["summary"].values()
    assert summary["ratio_8_over_1"] == [round(runs[0]["8"] / runs[0]["1"], 2)]
