"""Compiled (numba) kernels of the simulator, a family per module:

* :mod:`~omnibot.sim.kernels.wheels`: the physics step (:func:`physics_step` advances n robots,
  :func:`physics_step_parallel` many steps of a batch on numba's threads);
* :mod:`~omnibot.sim.kernels.contacts`: the world's contact geometry (:func:`outline_contacts`,
  :func:`surface_probe` the floor lookup, :func:`cone_distance` a sonar's range);
* :mod:`~omnibot.sim.kernels.sensors`: the gyro and the tracking wheels;
* :mod:`~omnibot.sim.kernels.step`: one robot's whole step (:func:`robot_step`, its parts
  :func:`robot_before` and :func:`robot_after`) and a fleet's (:func:`fleet_step`);
* :mod:`~omnibot.sim.kernels.scan`: the laser scanner (``scan_*``, and :func:`pose_log` its poses),
  with :mod:`~omnibot.sim.kernels.scan_ray` where its rays start and point (:func:`ray_table`) and
  :mod:`~omnibot.sim.kernels.scan_noise` its measurement;
* :mod:`~omnibot.sim.kernels.lanes`: the batch physics in vector lanes (``Physics.run(exact=False)``),
  with its own vectorisable ``tanh``, ``sin`` and ``cos`` (:mod:`~omnibot.sim.kernels.libm`);
* :mod:`~omnibot.sim.kernels.layout`: the column indices and packed-buffer offsets they share;
* :mod:`~omnibot.sim.kernels.warm`: the list of kernels, compiled all at once (:func:`warm_up`);
* :mod:`~omnibot.sim.kernels.cache`: numba's disk cache stamped with every file of the family.

The equations live here once; :mod:`omnibot.sim.physics`, :mod:`omnibot.sim.world`,
:mod:`omnibot.sim.sensors` and :mod:`omnibot.sim.simulator` hold the parameters and state as numpy
arrays and call these kernels with them. Every kernel loops over plain scalars and writes into
arrays its caller preallocated, so one call costs about a microsecond for one robot and scales
linearly with the number of robots. A kernel calls another by the name it imported it under
(``from omnibot.sim.kernels.wheels import robot_physics``), which is what their Python twins
follow (:mod:`omnibot.sim.twins`).

Kernels compile lazily on their first call and are cached on disk (``cache=True``, next to their
files or in ``NUMBA_CACHE_DIR``), so a new process loads them instead of compiling. Callers always
pass the same argument types (C-contiguous float64 arrays, int64 id arrays, Python floats and
bools), so each kernel compiles exactly once. :func:`warm_up` compiles (or loads) every kernel with
those types at once; ``make setup`` runs it (``python -m omnibot.sim.jit``) to fill the cache at
install time. The simulator calls the kernels through :data:`omnibot.sim.jit.active`, which runs
their plain-Python twins while a first start compiles them in another process.
"""

import omnibot.sim.kernels.cache  # noqa: F401 - before any kernel: each cached with the whole family' stamp
from omnibot.sim.kernels.contacts import cone_distance, outline_contacts, surface_probe
from omnibot.sim.kernels.layout import physics_offsets, physics_views, sim_offsets, world_offsets
from omnibot.sim.kernels.scan import (
    pose_log,
    scan_index,
    scan_index_around,
    scan_rays,
    scan_revolution,
)
from omnibot.sim.kernels.scan_noise import scan_measure
from omnibot.sim.kernels.scan_ray import ray_table
from omnibot.sim.kernels.sensors import gyro_measure, gyro_update, tracking_update
from omnibot.sim.kernels.step import fleet_step, robot_after, robot_before, robot_step
from omnibot.sim.kernels.warm import KERNELS, SIMULATOR_KERNELS, warm_up, warm_up_calls
from omnibot.sim.kernels.wheels import contact_speeds, physics_step, physics_step_parallel, solve_body

__all__ = [
    "KERNELS",
    "SIMULATOR_KERNELS",
    "cache",
    "cone_distance",
    "contact_speeds",
    "contacts",
    "fleet_step",
    "gyro_measure",
    "gyro_update",
    "lanes",
    "layout",
    "libm",
    "outline_contacts",
    "physics_offsets",
    "physics_step",
    "physics_step_parallel",
    "physics_views",
    "pose_log",
    "ray_table",
    "robot_after",
    "robot_before",
    "robot_step",
    "scan",
    "scan_index",
    "scan_index_around",
    "scan_measure",
    "scan_noise",
    "scan_ray",
    "scan_rays",
    "scan_revolution",
    "sensors",
    "sim_offsets",
    "solve_body",
    "step",
    "surface_probe",
    "tracking_update",
    "warm",
    "warm_up",
    "warm_up_calls",
    "wheels",
    "world_offsets",
]
