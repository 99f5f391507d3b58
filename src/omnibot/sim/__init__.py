"""The simulator: rigid-body physics with motors, wheels, rollers and floor surfaces, sensors and a world.

Other packages take the names below from this face::

    from omnibot.sim import SimDevice, Simulator, World, load_world

Each loads on first use, with only the module that defines it: ``import omnibot.sim`` loads nothing
(numba, the ``[sim]`` extra, loads with the first module that needs the kernels: the world's ranges
and contacts, the physics, the simulator).
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.sim.device import SimDevice
    from omnibot.sim.emulator import parse_member, run_pty_emulator, run_pty_fleet, spawn_pty_emulator
    from omnibot.sim.fleet import Fleet
    from omnibot.sim.geometry import points_in_polygon
    from omnibot.sim.physics import Physics
    from omnibot.sim.simulator import Simulator
    from omnibot.sim.truth import Snapshot
    from omnibot.sim.world import World, load_world, parse_world

_EXPORTS = {
    "device": ("SimDevice",),
    "emulator": ("parse_member", "run_pty_emulator", "run_pty_fleet", "spawn_pty_emulator"),
    "fleet": ("Fleet",),
    "geometry": ("points_in_polygon",),
    "physics": ("Physics",),
    "simulator": ("Simulator",),
    "truth": ("Snapshot",),
    "world": ("World", "load_world", "parse_world"),
}

__all__ = [
    "Fleet",
    "Physics",
    "SimDevice",
    "Simulator",
    "Snapshot",
    "World",
    "device",
    "emulator",
    "fleet",
    "geometry",
    "kernels",
    "load_world",
    "parse_member",
    "parse_world",
    "physics",
    "points_in_polygon",
    "run_pty_emulator",
    "run_pty_fleet",
    "simulator",
    "spawn_pty_emulator",
    "truth",
    "world",
]

# a name loads the module that defines it (and what that imports), on first use
if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
