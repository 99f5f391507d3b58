"""Where a wheel meets the floor: gravity, the static normal loads and the friction laws'
regularisation speeds, shared by the simulator's physics (:mod:`omnibot.sim.physics` and its
kernels) and the planner's reach (:mod:`omnibot.control.reach`).

The friction laws are regularised Coulomb laws ``F = -F_max tanh(speed / eps)`` (docs/simulator.md):
the floor's traction along each roller's direction with the surface's own ``slip_velocity``
(:class:`~omnibot.floor.surfaces.Surface`), the axle's static friction with
:data:`WHEEL_SPEED_EPS` and the rollers' rolling resistance with :data:`ROLL_SPEED_EPS`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

GRAVITY = 9.81
"""m/s^2."""
WHEEL_SPEED_EPS = 0.01
"""rad/s: regularisation speed of the Coulomb friction at the wheel axle."""
ROLL_SPEED_EPS = 0.005
"""m/s: regularisation speed of the roller rolling resistance."""


def static_loads(x: FloatArray, y: FloatArray, mass: FloatArray, lifted: BoolArray) -> FloatArray:
    """Static normal loads (n,m) in N: least-norm loads on the wheels in contact, none on lifted ones.

    Solves sum N = m g, sum N x = 0, sum N y = 0 over the wheels in contact (least norm when more
    than three touch), clips negative loads (the robot would tip) and rescales the rest to m g.
    """
    support = (~lifted).astype(float)
    A = np.stack([support, x * support, y * support], axis=1)
    b = np.zeros((x.shape[0], 3, 1))
    b[:, 0, 0] = mass * GRAVITY
    loads = (np.linalg.pinv(A) @ b)[:, :, 0]
    loads = np.clip(loads, 0.0, None) * support
    total = loads.sum(axis=1)
    scale = np.divide(mass * GRAVITY, total, out=np.zeros_like(total), where=total > 1e-12)
    return np.asarray(loads * scale[:, None], dtype=float)


__all__ = ["GRAVITY", "ROLL_SPEED_EPS", "WHEEL_SPEED_EPS", "static_loads"]
