"""The physics' state arrays as properties: views of its packed buffer, writable in place, and
assigning to one writes into it (so references handed out stay valid)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


class StateArrays:
    """:class:`~omnibot.sim.physics.Physics`'s pose, twist, wheel, motor and battery arrays (the
    class binds the views, ``Physics._bind``)."""

    _pose: FloatArray
    _q: FloatArray
    _wheel_angle: FloatArray
    _current: FloatArray
    _traction: FloatArray
    _v_open: FloatArray

    @property
    def pose(self) -> FloatArray:
        """(n,3) world x, y (m), theta (rad, continuous); writable in place."""
        return self._pose

    @pose.setter
    def pose(self, value: ArrayLike) -> None:
        self._pose[:] = value

    @property
    def twist(self) -> FloatArray:
        """(n,3) body-frame vx, vy (m/s), w (rad/s); writable in place."""
        return self._q[:, :3]

    @twist.setter
    def twist(self, value: ArrayLike) -> None:
        self._q[:, :3] = value

    @property
    def wheel_speed(self) -> FloatArray:
        """(n,m) wheel angular speeds, rad/s; writable in place."""
        return self._q[:, 3:]

    @wheel_speed.setter
    def wheel_speed(self, value: ArrayLike) -> None:
        self._q[:, 3:] = value

    @property
    def wheel_angle(self) -> FloatArray:
        """(n,m) wheel angles, rad (continuous); writable in place."""
        return self._wheel_angle

    @wheel_angle.setter
    def wheel_angle(self, value: ArrayLike) -> None:
        self._wheel_angle[:] = value

    @property
    def motor_current(self) -> FloatArray:
        """(n,m) motor current at the last step, A."""
        return self._current

    @motor_current.setter
    def motor_current(self, value: ArrayLike) -> None:
        self._current[:] = value

    @property
    def traction_force(self) -> FloatArray:
        """(n,m) floor force on the robot along each wheel's traction direction at the last step, N."""
        return self._traction

    @traction_force.setter
    def traction_force(self, value: ArrayLike) -> None:
        self._traction[:] = value

    @property
    def battery_open_voltage(self) -> FloatArray:
        """(n,) open-circuit battery voltage, V (lower it to simulate a discharged battery)."""
        return self._v_open

    @battery_open_voltage.setter
    def battery_open_voltage(self, value: ArrayLike) -> None:
        self._v_open[:] = value


__all__ = ["StateArrays"]
