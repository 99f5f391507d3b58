"""The batteries' state of charge: run down by each robot's battery current (coulomb counting) along
its chemistry's open-voltage curve (:func:`omnibot.robot.open_voltage`); a battery without a
``charge`` is held at its nominal voltage, unless a charge is set."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.robot import RobotDescription, open_voltage

FloatArray = NDArray[np.float64]


class BatteryCharge:
    """The state of charge of n robots' batteries, and the open voltage it gives them."""

    def __init__(self, robots: Sequence[RobotDescription]) -> None:
        self.robots = tuple(robots)
        self.drains = np.array([r.battery.charge is not None for r in self.robots], dtype=bool)
        """(n,) whether each battery runs down."""
        self.charge = np.array([1.0 if r.battery.charge is None else r.battery.charge for r in self.robots])
        """(n,) state of charge, 0..1."""
        self.draining = bool(self.drains.any())
        """Whether any battery runs down (the physics then steps one step per kernel call)."""
        self._capacity_as = np.array([r.battery.capacity_ah * 3600.0 for r in self.robots], dtype=float)

    def set_open_voltage(self, v_open: FloatArray) -> None:
        """Each draining battery's open voltage at its charge into ``v_open`` (n,)."""
        for i in np.flatnonzero(self.drains):
            b = self.robots[i].battery
            v_open[i] = open_voltage(b.chemistry, b.n_cells, float(self.charge[i]))

    def drain(self, current: FloatArray, dt: float, v_open: FloatArray) -> None:
        """Run the charge down by the battery ``current`` (n,) over dt; the open voltage follows."""
        q = self.charge - np.where(self.drains, current, 0.0) * dt / self._capacity_as
        self.charge[:] = np.clip(q, 0.0, 1.0)
        self.set_open_voltage(v_open)

    def set(self, value: ArrayLike, v_open: FloatArray) -> None:
        """Set every battery's charge (0..1): all run down from now on; the open voltage follows."""
        self.charge[:] = np.clip(np.asarray(value, dtype=float), 0.0, 1.0)
        self.drains[:] = True
        self.draining = True
        self.set_open_voltage(v_open)


__all__ = ["BatteryCharge"]
