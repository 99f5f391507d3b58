"""The compiled step's bound arguments (omnibot.sim.simulator_state.StepState._bind_step): in
robot_step's order, and the arrays the simulator holds now after each array is replaced."""

from __future__ import annotations

import inspect

from omnibot.robot import load_robot
from omnibot.sim import kernels
from omnibot.sim.fleet_arrays import FleetArrays
from omnibot.sim.kernels import layout
from omnibot.sim.simulator import Simulator
from omnibot.sim.world import load_world

from .fakes import FakePhysics


def assert_bound(sim: Simulator) -> None:
    """Each bound argument but the count and the time is the very object a fresh binding takes."""
    bound = sim._step_args
    assert bound is not None
    sim._bind_step()
    fresh = sim._step_args
    assert fresh is not None and len(bound) == len(fresh)
    for k, (old, new) in enumerate(zip(bound, fresh, strict=True)):
        if k not in (layout.A_N_EXTRA, layout.A_NOW_US):
            assert old is new or (not hasattr(old, "shape") and old == new), k


def test_changing_arguments_are_robot_steps_count_and_time() -> None:
    names = list(inspect.signature(kernels.robot_step.py_func).parameters)
    assert names[layout.A_N_EXTRA] == "n_extra"
    assert names[layout.A_NOW_US] == "now_us"


def test_binding_follows_more_extra_rows_a_refill_and_a_fleet() -> None:
    world = load_world("empty")
    sim = Simulator(
        load_robot("omni3"), world=world, seed=3
    )  # a gyro and tracking wheels: their draws refill
    sim.set_pwm([120, -60, -60])
    for k in range(6):  # more pushes than the extra-force rows hold
        sim.push((0.5, 0.0), 0.01 * k, duration=0.01, motors_off=False)
    extra = sim._extra
    sim.step()
    assert sim._extra is not extra
    assert_bound(sim)
    normals = sim._sensors[3]
    for _ in range(100):
        sim.step(200)
        if sim._sensors[3] is not normals:
            break
    assert sim._sensors[3] is not normals, "no refill in 20,000 steps"
    assert_bound(sim)
    buffer = sim._packed.buffer if sim._packed is not None else None
    arrays = FleetArrays(
        [sim, Simulator(load_robot("omni4"), world=world, seed=1, start_pose=(1.0, 0.0, 0.0))]
    )
    assert sim._packed is not None and sim._packed.buffer is not buffer
    assert_bound(sim)
    arrays.release()
    assert_bound(sim)


def test_another_physics_binds_nothing() -> None:
    sim = Simulator(load_robot("omni4"), physics_factory=FakePhysics)
    assert sim._step_args is None
