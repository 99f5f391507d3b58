"""The drift benchmark's tables (no simulation: the drives are the benchmark's)."""

from __future__ import annotations

from typing import Any

import pytest

from benchmarks import odometry_drift


def result(seed: int, surface: str, position_m: float, heading_deg: float) -> dict[str, Any]:
    return {
        "robot": "omni4",
        "surface": surface,
        "seed": seed,
        "distance_m": 100.0,
        "errors": {"fused": [0.05, position_m]},
        "heading_errors": {"fused": [0.1, heading_deg]},
        "completed": True,
    }


def test_every_seed_gets_its_final_position_and_heading_and_the_worst_is_the_largest_heading() -> None:
    results = [
        result(1, "wood", 0.13, -1.02),
        result(1, "carpet", 0.28, 0.50),
        result(2, "wood", 0.10, -0.57),
        result(2, "carpet", 0.31, -0.60),
    ]
    lines = odometry_drift.format_seeds(results).splitlines()
    assert lines[0] == "| robot | floor | seed 1 | seed 2 | worst |"
    assert (
        lines[2] == "| omni4 | wood | 0.13 % / -1.02 degree | 0.10 % / -0.57 degree | 0.13 % / -1.02 degree |"
    )
    assert (
        lines[3]
        == "| omni4 | carpet | 0.28 % / +0.50 degree | 0.31 % / -0.60 degree | 0.31 % / -0.60 degree |"
    )


def test_seeds_must_be_integers() -> None:
    with pytest.raises(SystemExit):
        odometry_drift.main(["--seeds", "1,x"])
