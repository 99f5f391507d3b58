"""The compiled kernels: warm_up() compiles each with the very argument types the simulator passes."""

from __future__ import annotations

import numpy as np

from omnibot.robot import load_robot
from omnibot.scan import Scan
from omnibot.sim import kernels
from omnibot.sim.physics import Physics
from omnibot.sim.simulator import Simulator
from omnibot.sim.world import load_world


def test_warm_up_compiles_what_the_simulator_calls() -> None:
    """After warm_up, real calls of every kernel find their compiled version (no second signature)."""
    kernels.warm_up()
    assert all(len(k.signatures) == 1 for k in kernels.KERNELS), [
        k.signatures for k in kernels.KERNELS if len(k.signatures) > 1
    ]
    physics = Physics(load_robot("omni4"), surfaces=("wood", "carpet"))
    physics.step([100, 100, 100, 100])
    assert physics.slip.shape == (1, 4)  # contact_speeds
    room = load_world("room")
    assert room.surface_ids([[0.0, 0.0], [1.0, 1.0]]).shape == (2,)  # surface_probe
    (x0, y0, _x1, _y1) = room.segments[0]
    square = np.array([[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]]) + np.array([x0, y0])
    assert room.contacts(square)  # outline_contacts, touching a wall
    sim = Simulator(load_robot("omni4"), world="room", seed=1)
    scans: list[Scan] = []
    sim.add_scan_listener(scans.append)
    sim.advance(0.25)
    assert scans  # scan_revolution, scan_index_around, pose_log
    assert [len(k.signatures) for k in kernels.KERNELS] == [1] * len(kernels.KERNELS)
