"""The at-rest benchmark: a robot standing in the room, the localiser beside the truth every cycle."""

from __future__ import annotations

import numpy as np
import pytest
from benchmarks.planner import rasterise

from benchmarks import localise_rest
from omnibot.motion import Pose2D
from omnibot.sim import load_world


def test_a_robot_at_rest_is_traced_every_cycle_after_the_first_second() -> None:
    grid = rasterise(load_world("room"), 0.05)
    rest = localise_rest.at_rest("omni3", "room", Pose2D(1.0, 1.0, 0.0), seed=1, seconds=2.5, grid=grid)
    steps = np.diff(rest.rows[:, 0])
    assert len(steps) > 100 and np.allclose(steps, 0.01)  # every cycle (binary telemetry: 10 ms)
    assert rest.drift == 0.0  # nothing drives: the estimate stays put, whatever moves is the localiser
    assert rest.off.max() < 0.01 and rest.wander < 0.005  # tests/mapping/test_localise_rest.py's bound


def test_prints_one_row_per_world_and_robot(capsys: pytest.CaptureFixture[str]) -> None:
    args = [
        "--robots",
        "omni3",
        "--worlds",
        "room",
        "--poses",
        "1",
        "--seconds",
        "1.5",
        "--resolution",
        "0.05",
    ]
    assert localise_rest.main(args) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| room | omni3 | 1 |")]
    assert len(rows) == 1 and rows[0].endswith("| 0.000 cm |")
