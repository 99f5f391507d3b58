"""What the simulator needs of a physics engine (:class:`PhysicsLike`), and the engine it makes when
given no other: :class:`~omnibot.sim.physics.Physics`."""

from __future__ import annotations

import inspect
from collections.abc import Callable, Sequence
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.robot import RobotDescription

FloatArray = NDArray[np.float64]


class PhysicsLike(Protocol):
    """What the simulator uses of :class:`omnibot.sim.physics.Physics` (batched over N robots)."""

    @property
    def pose(self) -> FloatArray:
        """(N, 3) world x, y, theta."""

    @property
    def twist(self) -> FloatArray:
        """(N, 3) body vx, vy, w."""

    @property
    def wheel_angle(self) -> FloatArray:
        """(N, M) rad."""

    @property
    def wheel_speed(self) -> FloatArray:
        """(N, M) rad/s."""

    @property
    def motor_current(self) -> FloatArray:
        """(N, M) A."""

    @property
    def surfaces(self) -> Sequence[Any]:
        """Floor surfaces (objects with ``.name``) that surface ids index."""

    @property
    def lifted(self) -> NDArray[np.bool_]:
        """(N, M) wheels off the floor; assigned whole (Physics.lifted is a read-only view)."""

    @lifted.setter
    def lifted(self, mask: NDArray[np.bool_]) -> None: ...

    def reset(self, pose: ArrayLike | None = None) -> None:
        """Put every robot at rest at ``pose`` ((3,) or (n, 3); the origin when None), time 0."""

    def step(
        self, pwm: ArrayLike, surface_ids: ArrayLike | None = None, external_force: ArrayLike | None = None
    ) -> None:
        """Advance one step with these PWM values, floor surfaces under the wheels and external forces."""

    def contact_points_world(self) -> FloatArray:
        """(N, M, 2) wheel contact points in the world frame, m."""


PhysicsFactory = Callable[..., PhysicsLike]
"""Called as ``factory(robot, n=1, surfaces=names, dt=dt, seed=seed)``."""


def default_physics(robot: RobotDescription, **kwargs: Any) -> PhysicsLike:
    """A :class:`~omnibot.sim.physics.Physics` of ``robot`` (``seed`` dropped unless it takes one)."""
    from omnibot.sim.physics import Physics

    accepted = inspect.signature(Physics).parameters
    if "seed" not in accepted:
        kwargs.pop("seed", None)
    return Physics(robot, **kwargs)


__all__ = ["PhysicsFactory", "PhysicsLike", "default_physics"]
