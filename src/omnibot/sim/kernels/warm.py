"""Which kernels there are, and compiling (or loading) them all at once with the argument types the
simulator passes: what ``make setup`` and the compiling process of a cold start run
(:mod:`omnibot.sim.jit`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from omnibot.sim.kernels.contacts import cone_distance, outline_contacts, surface_probe
from omnibot.sim.kernels.layout import (
    F_HEADER,
    G_COLUMNS,
    G_DUE,
    G_PERIOD,
    I_HEADER,
    L_COLUMNS,
    R_COLUMNS,
    S_COLUMNS,
    T_HEADER,
    W_COLUMNS,
    WORLD_HEADER,
    FloatArray,
    IntArray,
    physics_offsets,
    sim_offsets,
)
from omnibot.sim.kernels.scan import (
    SCAN_BINS,
    SCAN_PARAMS,
    pose_log,
    scan_index,
    scan_index_around,
    scan_rays,
    scan_revolution,
)
from omnibot.sim.kernels.scan_noise import scan_measure
from omnibot.sim.kernels.scan_ray import RAY_COLUMNS, ray_table
from omnibot.sim.kernels.sensors import gyro_measure, gyro_update, tracking_update
from omnibot.sim.kernels.step import fleet_step, robot_after, robot_before, robot_step
from omnibot.sim.kernels.wheels import contact_speeds, physics_step, physics_step_parallel

SIMULATOR_KERNELS = (
    outline_contacts,
    robot_step,
    fleet_step,
    cone_distance,
    scan_measure,
    scan_revolution,
    scan_index_around,
    pose_log,
)
"""The kernels a simulator of one robot calls (the helpers they call compile with them; Python
calls :func:`physics_offsets` and :func:`sim_offsets` as plain Python, their ``py_func``)."""
KERNELS = (
    *SIMULATOR_KERNELS, physics_step, contact_speeds, surface_probe, robot_before, robot_after, gyro_update,
    gyro_measure, tracking_update, scan_index, scan_rays, ray_table,
)  # fmt: skip
"""Every serial kernel (:func:`physics_step_parallel`, for batches, compiles on its first call)."""


def _f(*shape: int) -> FloatArray:
    """Zeros of ``shape``, float64."""
    return np.zeros(shape)


def _i(*shape: int) -> IntArray:
    """Zeros of ``shape``, int64."""
    return np.zeros(shape, dtype=np.int64)


def _physics_call() -> object:
    """:func:`physics_step` on one robot of one wheel, no surface."""
    f, i = _f, _i
    return physics_step(
        f(1, 3), f(1, 4), f(1, 1), f(1, 1), f(1, 1), f(1, 2), f(1), f(1, 1), i(1, 1), f(1, 3), False,
        f(1, 1, W_COLUMNS), f(1, R_COLUMNS), f(0, S_COLUMNS), 0.001,
    )  # fmt: skip


def warm_up_calls() -> list[tuple[Any, Callable[[], object]]]:
    """(kernel, call) for every kernel in :data:`KERNELS` order: the call compiles (or loads) it with
    the argument types the simulator passes (empty or trivial arrays: nothing is computed)."""
    f, i = _f, _i
    triangle = np.array([[0.1, 0.0], [-0.1, 0.1], [-0.1, -0.1]])
    si = i(I_HEADER)
    si_full = i(int(sim_offsets.py_func(si)[-1]))
    no_world = i(WORLD_HEADER + 2)
    index = (i(SCAN_BINS + 1), i(0), f(0))
    gyro = f(G_COLUMNS)
    gyro[G_DUE] = gyro[G_PERIOD] = 1.0
    # robot_step with no surface returns STEP_BAD_SURFACE before it moves anything; fleet_step has no robot
    one_robot = (
        f(int(physics_offsets.py_func(1, 1, 0)[-1])), i(1, 1), 1, 0, f(0), no_world, f(F_HEADER), si_full,
        f(1, 3), 0, f(0), f(0), f(2), f(0), 0, 0.001,
    )  # fmt: skip
    revolution = (
        0.0, 0, 0, f(0, RAY_COLUMNS), f(1, 3), 0, f(SCAN_PARAMS), f(0, 4), *index, f(0, 2), i(2), f(0), f(0), f(0), f(0),
    )  # fmt: skip
    calls: dict[Any, Callable[[], object]] = {
        outline_contacts: lambda: outline_contacts(
            triangle, 0.0, 0.0, 0.0, f(0, 2), i(1), f(0, 2), f(0), i(0), f(0, 2), i(0), f(0, 6)
        ),
        robot_step: lambda: robot_step(*one_robot),
        fleet_step: lambda: fleet_step(
            f(0), i(0), i(0, L_COLUMNS), f(0), no_world, f(0), f(0, 3), i(0), 0, 0.001
        ),
        cone_distance: lambda: cone_distance(f(0, 4), 0.0, 0.0, 0.0, 0.5, 1.0),
        scan_index: lambda: scan_index(f(0, 4), 0.0, 0.0, 1.0, 1.0),
        scan_rays: lambda: scan_rays(
            f(0), f(0), 0.0, 0.001, f(1, 3), 0, 0.0, 0.0, f(0, 4), *index, f(0, 2), i(2), 1.0, f(0)
        ),
        ray_table: lambda: ray_table(f(0), f(0)),
        scan_measure: lambda: scan_measure(f(0), f(0), f(0), 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, f(0)),
        scan_revolution: lambda: scan_revolution(*revolution),
        scan_index_around: lambda: scan_index_around(f(0, 4), f(1, 3), 0, 0.0, 1.0, 1.0, f(SCAN_PARAMS)),
        pose_log: lambda: pose_log(f(F_HEADER), si_full, 0.0, 0.0, 0.0, -(2**40)),
        physics_step: _physics_call,
        contact_speeds: lambda: contact_speeds(f(0, 3), f(0, 0, W_COLUMNS), f(0, 0, 2)),
        surface_probe: lambda: surface_probe(f(0, 2), f(0, 2), i(1), i(0), i(0)),
        robot_before: lambda: robot_before(
            f(6), i(1, 1), f(0), no_world, f(F_HEADER), si_full, f(1, 3), 0, f(1, 3), 0
        ),
        robot_after: lambda: robot_after(f(6), 0.001, f(0), f(0), f(2), f(0)),
        gyro_update: lambda: gyro_update(gyro, f(0), 0.0, 0.0),
        gyro_measure: lambda: gyro_measure(f(G_COLUMNS), f(0), 0.0),
        tracking_update: lambda: tracking_update(f(T_HEADER), f(0), 0.0, 0.0, 0.0, 0.001),
    }
    return [(kernel, calls[kernel]) for kernel in KERNELS]


def warm_up(every: bool = True) -> None:
    """Compile every kernel of :data:`KERNELS` and :func:`physics_step_parallel` now (only the
    :data:`SIMULATOR_KERNELS` with ``every`` False), or load it from the disk cache, with the
    argument types the simulator passes. About a second per kernel on the first run of a fresh
    install (:func:`robot_step`, which compiles the physics, contacts and sensors with it, takes
    most), milliseconds once the cache is filled."""
    for kernel, call in warm_up_calls():
        if every or kernel in SIMULATOR_KERNELS:
            call()
    if every:  # the batch's kernel too (no surface: it returns before it moves anything)
        buf = np.zeros(physics_offsets.py_func(1, 1, 0)[-1])
        physics_step_parallel(buf, np.zeros((1, 1), dtype=np.int64), 1, 1, 0, False, 0.001, 0)
