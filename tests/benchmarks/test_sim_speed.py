"""The simulator speed benchmark's measures run (the figures are BENCHMARKS.md's business, not a test's)."""

from __future__ import annotations

import numba
from benchmarks.sim_speed import fleet_step_seconds, omnibot_batch_robot_steps_per_second


def test_the_batch_measures_step_run_and_lanes_and_restores_the_threads() -> None:
    threads = numba.get_num_threads()
    for how in (0, 1, None):
        assert omnibot_batch_robot_steps_per_second(n=20, steps=5, repeats=1, threads=how) > 0
    for how in (1, None):  # the lanes, per second of the wall clock and of the CPU
        assert omnibot_batch_robot_steps_per_second(n=20, steps=5, repeats=1, threads=how, exact=False) > 0
    assert omnibot_batch_robot_steps_per_second(n=20, steps=5, repeats=1, threads=1, cpu=True) > 0
    assert numba.get_num_threads() == threads


def test_a_fleet_step_is_measured_for_a_fleet_of_two() -> None:
    assert 0 < fleet_step_seconds(2, steps=20, repeats=2) < 1.0
