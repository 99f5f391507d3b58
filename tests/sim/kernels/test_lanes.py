"""The batch kernel in vector lanes: its runs against the exact step."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from omnibot.errors import SimulationError
from omnibot.robot import load_robot
from omnibot.sim.kernels import lanes
from omnibot.sim.physics import Physics
from omnibot.sim.twins import python_twins

RTOL = 1e-12
"""How far a lanes run may part from the exact step's in 2 s, relative to a state's largest value (measured: 5e-15; 7e-13 after 10 s)."""


def _batch(n: int) -> Physics:
    robots = [load_robot("omni4"), load_robot("omni4").model_copy(update={"mass": 2.3})]
    return Physics([robots[i % 2] for i in range(n)], surfaces=("wood", "carpet"))


def _inputs(n: int) -> tuple[Any, ...]:
    rng = np.random.default_rng(4)
    return rng.integers(-255, 256, size=(n, 4)), rng.integers(0, 2, size=(n, 4)), rng.normal(0.0, 2.0, (n, 3))


STATE = ("pose", "twist", "wheel_angle", "wheel_speed", "motor_current", "battery_voltage")


def _assert_close(a: Physics, b: Physics, rtol: float) -> None:
    for name in STATE:
        want, got = getattr(a, name), getattr(b, name)
        assert np.abs(got - want).max() <= rtol * np.abs(want).max(), name


def test_a_lanes_run_keeps_within_its_tolerance_of_the_exact_step() -> None:
    n = 37  # not a whole number of blocks
    pwm, ids, force = _inputs(n)
    fast, exact = _batch(n), _batch(n)
    for _ in range(4):  # 2 s, each part its own call (the blocks reloaded)
        fast.run(pwm, 500, surface_ids=ids, external_force=force, exact=False)
        exact.run(pwm, 500, surface_ids=ids, external_force=force)
    _assert_close(exact, fast, RTOL)
    assert not all(np.array_equal(getattr(exact, s), getattr(fast, s)) for s in STATE)  # not the same kernel
    assert len(np.unique(fast.pose[:, 0])) > n // 2 and fast.time == exact.time


@pytest.mark.parametrize("preset", ["omni3", "mecanum4"])
def test_every_wheel_layout_keeps_within_the_tolerance(preset: str) -> None:
    robot = load_robot(preset)
    pwm = np.random.default_rng(5).integers(-255, 256, size=(5, robot.n_wheels))
    fast, exact = Physics(robot, n=5), Physics(robot, n=5)
    fast.run(pwm, 1000, exact=False)
    exact.run(pwm, 1000)
    _assert_close(exact, fast, RTOL)


def test_angles_past_the_reduction_go_to_the_c_library() -> None:
    fast, exact = _batch(2), _batch(2)
    for ph in (fast, exact):
        ph.reset(pose=(0.0, 0.0, 3e7), wheel_angle=(2e6, -5e6, 0.5, 1e9))
    pwm = np.full((2, 4), 200)
    fast.run(pwm, 100, exact=False)
    exact.run(pwm, 100)
    _assert_close(exact, fast, RTOL)


def test_the_compiled_kernel_is_its_python_twin_bit_for_bit() -> None:
    """IEEE arithmetic in the order written, whatever the vector width: the twin's numbers."""
    n = 3
    pwm, ids, force = _inputs(n)
    compiled, python = _batch(n), _batch(n)
    compiled.run(pwm, 5, surface_ids=ids, external_force=force, exact=False)
    python._inputs(pwm, ids, force)
    python_twins(lanes)["physics_run"](python.buffer, python._ids, n, 4, 2, True, python.dt, 5)
    for name in STATE:
        assert np.array_equal(getattr(compiled, name), getattr(python, name)), name


def test_a_lanes_run_refuses_bad_surfaces() -> None:
    batch = _batch(2)
    with pytest.raises(SimulationError, match="must index the 2 surfaces"):
        batch.run(np.zeros((2, 4)), 3, surface_ids=np.full((2, 4), 2), exact=False)
    assert batch.time == 0.0 and not batch.pose.any()
