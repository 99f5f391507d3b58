"""Robots stepped in one compiled call (omnibot.sim.fleet_arrays): each robot's numbers are those of
its own step, bit for bit, while its state lives in the fleet's arrays, and after it leaves them."""

from __future__ import annotations

import numpy as np

from omnibot.motion import Pose2D
from omnibot.robot import load_robot
from omnibot.sim.fleet import Fleet
from omnibot.sim.fleet_arrays import FleetArrays, batchable
from omnibot.sim.simulator import Simulator
from omnibot.sim.world import World, load_world

from .fakes import FakePhysics

# preset, seed, start pose, PWM: omni4 driven into the room's wall (contacts, collision events),
# omni3 (gyro and tracking wheels), mecanum4 pushed by hand and by an applied force
ROBOTS = (
    ("omni4", 7, (1.5, 3.4, 0.3), [150, -40, -150, 40]),
    ("omni3", 3, (1.0, 1.0, 0.0), [120, -60, -60]),
    ("mecanum4", 5, (2.6, 2.0, -1.0), [90, 90, 90, 90]),
)


def robots(world: World) -> list[Simulator]:
    sims = []
    for preset, seed, pose, pwm in ROBOTS:
        sim = Simulator(load_robot(preset), world=world, seed=seed, start_pose=pose)
        sim.set_pwm(pwm)
        sims.append(sim)
    return sims


def state(sim: Simulator) -> list[bytes]:
    """Every number the step writes, and what it told the simulator."""
    floats, ints = sim._step_state()
    events = [(e.time, e.x, e.y, e.owner) for e in sim.collisions]
    return [a.tobytes() for a in (*floats, *ints)] + [repr((sim.clock.ticks_us(), events)).encode()]


def forces(sims: list[Simulator], k: int) -> None:
    """The same hand push and applied force on the last robot at step ``k`` of either run."""
    if k == 300:
        sims[-1].push((4.0, -2.0), 0.2, duration=0.05, motors_off=False)
    if 600 <= k < 700:
        sims[-1].apply_force(1.5, 0.5, -0.05)


def test_robots_stepped_in_one_call_give_their_own_steps_numbers_bit_for_bit() -> None:
    world = load_world("room")
    alone, together = robots(world), robots(world)
    arrays = FleetArrays(together)
    normals = arrays.normals
    for k in range(1500):
        forces(alone, k)
        forces(together, k)
        for sim in alone:
            sim.step()
        arrays.step(together[0].clock.ticks_us())
    assert arrays.normals is not normals  # the gyros' draws were refilled on the way
    assert alone[0].collisions  # the wall was met
    for a, b in zip(alone, together, strict=True):
        assert state(a) == state(b)
        assert np.shares_memory(b.physics.pose, arrays.fbuf)


def test_a_robot_released_from_the_fleets_arrays_steps_on_in_arrays_of_its_own() -> None:
    world = load_world("room")
    alone, together = robots(world), robots(world)
    arrays = FleetArrays(together)
    for _ in range(200):
        for sim in alone:
            sim.step()
        arrays.step(together[0].clock.ticks_us())
    arrays.release()
    for a, b in zip(alone, together, strict=True):
        assert not any(np.shares_memory(x, arrays.fbuf) for x in b._step_state()[0])
        assert not any(np.shares_memory(x, arrays.ibuf) for x in b._step_state()[1])
        a.step(300)
        b.step(300)
        assert state(a) == state(b)


def test_only_packed_physics_on_one_world_and_step_are_stepped_together() -> None:
    room = load_world("room")
    omni4 = load_robot("omni4")
    assert batchable(robots(room))
    assert not batchable([])
    assert not batchable([Simulator(omni4, world=room), Simulator(omni4, world=load_world("room"))])
    assert not batchable([Simulator(omni4, world=room), Simulator(omni4, world=room, dt=0.002)])
    assert not batchable([Simulator(omni4, world=room, physics_factory=FakePhysics)])


def test_a_fleet_steps_its_robots_in_its_arrays_and_gives_a_leaving_robot_its_own() -> None:
    fleet = Fleet(load_world("room"))
    a = fleet.add("a", "omni4", seed=1, pose=Pose2D(1.0, 1.0, 0.0))
    b = fleet.add("b", "omni3", seed=2, pose=Pose2D(2.5, 2.0, 0.0))
    arrays = fleet._arrays
    assert arrays is not None and arrays.sims == [a.sim, b.sim]
    fleet.step()
    fleet.remove("b")
    assert not np.shares_memory(b.sim.physics.pose, arrays.fbuf)
    assert fleet._arrays is not None and fleet._arrays.sims == [a.sim]
    assert np.shares_memory(a.sim.physics.pose, fleet._arrays.fbuf)
    assert a.sim.clock.ticks_us() == b.sim.clock.ticks_us() == fleet.ticks_us == 1000
