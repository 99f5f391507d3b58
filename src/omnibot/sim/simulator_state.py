"""The compiled step's own state of one simulator, packed as :func:`~omnibot.sim.kernels.robot_step`
takes it (the ``F_`` and ``I_`` layouts of :mod:`omnibot.sim.kernels.layout`): the contact broad
phase, the surface cache, the contact rows and last touches; and its moving into a fleet's buffers."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from omnibot.robot import RobotDescription
from omnibot.sim import kernels
from omnibot.sim.kernels import layout
from omnibot.sim.physics import Physics
from omnibot.sim.physics_like import PhysicsLike
from omnibot.sim.scanner import SCAN_POSE_PERIOD, pose_log_rows
from omnibot.sim.sensors import Gyro, TrackingWheels
from omnibot.sim.simulator_contacts import CONTACT_DAMPING, CONTACT_OMEGA_DT, CONTACT_RELEASE, WALL_FRICTION
from omnibot.sim.world import World

FloatArray = NDArray[np.float64]


class StepState:
    """:class:`~omnibot.sim.simulator.Simulator`'s arrays for the compiled step: packed once
    (:meth:`_pack_step_state`), moved whole into a fleet's buffers and back (:meth:`_rehome`)."""

    robot: RobotDescription
    world: World
    dt: float
    gyro: Gyro | None
    tracking: TrackingWheels
    _physics: PhysicsLike
    _packed: Physics | None
    _outline: FloatArray
    _surface_map: NDArray[np.int64]
    _floor_ids: NDArray[np.int64]
    _no_gyro: FloatArray
    _pwm: FloatArray
    _pose_row: FloatArray
    _twist_row: FloatArray
    _dt_us: int
    _step_args: list[Any] | None
    """robot_step's arguments, bound by :meth:`_bind_step`."""

    @property
    def _log_stride_us(self) -> int:
        """How often (us) the compiled step records the pose for the laser scanners: every
        SCAN_POSE_PERIOD, or every step if a step is longer."""
        return max(1, round(SCAN_POSE_PERIOD / self.dt)) * self._dt_us

    def pose_log(self) -> tuple[FloatArray, NDArray[np.int64]]:
        """The pose log's rows (capacity, 3), a view of the float state, and the int state whose
        ``I_LOG_`` columns describe it (:func:`~omnibot.sim.kernels.pose_log`)."""
        return self._log_rows, self._si

    def _pose_log_start(self, now_us: int) -> None:
        """Start the pose log at ``now_us`` (the end of a step) with the pose now as its first row."""
        rows, si = self.pose_log()
        rows[0] = self._pose_row
        si[layout.I_LOG_N], si[layout.I_LOG_NEXT] = 1, now_us + self._log_stride_us
        si[layout.I_LOG_STRIDE], si[layout.I_LOG_DT] = self._log_stride_us, self._dt_us
        si[layout.I_LOG_FLUSH], si[layout.I_LOG_ON] = 2**62, 1

    def _pose_log_stop(self) -> None:
        """Stop recording the pose (the compiled step then skips it)."""
        self._si[layout.I_LOG_ON] = 0

    def _pack_step_state(self) -> None:
        """The compiled step's own state (kernels.robot_step): contact broad phase (no contact while
        the origin stays within F_CLEAR of F_CLEAR_X/Y), the surface cache (the same ids while the
        wheels move less than F_SURF_CLEAR from the anchor pose), contact rows, last touches."""
        robot = self.robot
        self._walls = len(self.world.segments) > 0
        self._patchy = len(self.world.surface_names) > 1
        self._ids = self._floor_ids.copy()
        n_rows = len(self.world.contact_buffer())
        si = np.zeros(layout.I_HEADER, dtype=np.int64)
        si[layout.I_V], si[layout.I_C], si[layout.I_M] = len(self._outline), n_rows, robot.n_wheels
        si[layout.I_OWNERS], si[layout.I_SURFACES] = len(self.world.contact_owners), len(self._surface_map)
        si[layout.I_WALLS], si[layout.I_PATCHY] = self._walls, self._patchy
        si[layout.I_RELEASE] = round(CONTACT_RELEASE * 1e6)
        si[layout.I_LOG_CAP] = pose_log_rows(
            robot.scanner.period if robot.scanner else 0.0, self._log_stride_us / 1e6
        )
        of0, of1, of2, of3, of4, of_end, oi0, oi1, oi2, oi3, oi_end = kernels.sim_offsets.py_func(si)
        self._si = np.zeros(oi_end, dtype=np.int64)
        self._si[: layout.I_HEADER] = si
        self._si[oi0:oi1] = layout.NEVER
        self._si[oi2:oi3] = self._surface_map
        self._sf = sf = np.zeros(of_end)
        sf[layout.F_MASS], sf[layout.F_INERTIA] = robot.mass, robot.yaw_inertia
        sf[layout.F_OMEGA] = CONTACT_OMEGA_DT / self.dt
        sf[layout.F_DAMPING], sf[layout.F_WALL_FRICTION] = CONTACT_DAMPING, WALL_FRICTION
        sf[layout.F_CLEAR], sf[layout.F_SURF_CLEAR] = -1.0, -1.0
        sf[layout.F_REACH] = max(math.hypot(*wh.position) for wh in robot.wheels)
        sf[of0:of1] = self._outline.ravel()
        sf[of3:of4] = np.array([wh.position for wh in robot.wheels], dtype=float).ravel()
        self._log_rows = sf[of4:of_end].reshape(-1, 3)
        self._contact_out = sf[of1:of2].reshape(n_rows, 6)
        self._contact_speed = sf[of2:of3]
        self._new_contact = self._si[oi1:oi2]
        self._world_packed = self.world.packed
        self._extra = np.zeros((4, 3))
        self._step_ids = self._ids if self._patchy else self._floor_ids
        self._n_surfaces = len(self._physics.surfaces)
        self._state6 = np.zeros(6)
        self._force = np.zeros((1, 3))

    def _bind_step(self) -> None:
        """Bind the compiled step's arguments (:func:`~omnibot.sim.kernels.robot_step`'s, in its order)
        to the arrays they are now: again whenever one is replaced (a fleet's rehoming, the sensors'
        refill, more extra-force rows). The step sets only the extra-force count and the time (the
        ``A_`` indices of :mod:`~omnibot.sim.kernels.layout`); None with a physics of another kind."""
        physics = self._packed
        self._step_args = None if physics is None else [
            physics.buffer, self._step_ids, physics.m, self._n_surfaces, *self._world_packed, self._sf, self._si,
            self._extra, 0, *self._sensors, 0, self.dt,
        ]  # fmt: skip

    def _sensor_arrays(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """The gyro's and tracking wheels' state and normal draws, as the compiled step takes them."""
        gyro, tracking = self.gyro, self.tracking
        g_state, g_normals = (gyro.state, gyro.normals.values) if gyro is not None else (self._no_gyro,) * 2
        return g_state, g_normals, tracking.state, tracking.normals.values

    def _step_state(self) -> tuple[tuple[FloatArray, ...], tuple[NDArray[np.int64], ...]]:
        """The arrays the compiled step writes: (physics buffer, float state, gyro state, tracking
        state) and (surface ids, int state); a fleet moves them into its own buffers (:meth:`_rehome`)."""
        assert self._packed is not None
        gyro_state = self._sensors[0]
        return (self._packed.buffer, self._sf, gyro_state, self.tracking.state), (self._step_ids, self._si)

    def _rehome(self, floats: Sequence[FloatArray], ints: Sequence[NDArray[np.int64]]) -> None:
        """Move the arrays of :meth:`_step_state` into ``floats`` and ``ints`` (arrays of the same
        shapes, such as views of a fleet's buffers, or fresh ones when the robot leaves it) and keep
        them there: the numbers do not change, only where they live."""
        assert self._packed is not None
        pbuf, sf, gyro_state, tracking_state = floats
        ids, si = ints
        (own_f, own_i) = self._step_state()
        for new, old in zip((*floats, *ints), (*own_f, *own_i), strict=True):
            new[...] = old
        self._packed.rehome(pbuf)
        self._pwm = self._packed.pwm
        self._pose_row = self._physics.pose[0]
        self._twist_row = self._physics.twist[0]
        self._sf, self._si, self._step_ids = sf, si, ids
        if self._patchy:
            self._ids = ids
        _, of1, of2, of3, of4, of_end, _, oi1, oi2, _, _ = kernels.sim_offsets.py_func(si)
        self._log_rows = sf[of4:of_end].reshape(-1, 3)
        self._contact_out = sf[of1:of2].reshape(-1, 6)
        self._contact_speed = sf[of2:of3]
        self._new_contact = si[oi1:oi2]
        if self.gyro is not None:
            self.gyro.state = gyro_state
        self.tracking.state = tracking_state
        self._sensors = self._sensor_arrays()
        self._bind_step()


__all__ = ["StepState"]
