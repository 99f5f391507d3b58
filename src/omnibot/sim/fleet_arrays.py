"""A fleet's robots stepped in one compiled call: their step state moved into fleet-wide arrays.

::

    FleetArrays(sims)   every robot's physics buffer, float and int state, gyro and tracking state
                        copied into two buffers (fbuf, ibuf) and kept there (Simulator._rehome): the
                        robots' arrays are views of them, so everything else reads and writes them
                        as before; where each lies is one row of ``layout`` (kernel_layout.L_ columns)
    step(now_us)        the extra forces due (the fleet's contacts, hand pushes) into one array
                        -> kernels.fleet_step: kernels.robot_step for every robot, in order
                        -> each robot's own after-step (Simulator._finish_step: its clock, events,
                           normal draws, listeners)
    release()           each robot's arrays back into arrays of its own (it leaves the fleet)

One call a step instead of one a robot saves numba's dispatch of eleven array arguments per robot
(about 1 us each): the numbers are the robots' own steps', bit for bit, as
``kernels.fleet_step`` calls the same ``kernels.robot_step``. The sensors' normal draws, which the
step only reads and :class:`~omnibot.sim.sensors.NormalDraws` replaces when it refills, are copied
into one array again after a refill. Robots whose physics is not a
:class:`~omnibot.sim.physics.Physics`, or that do not share one world's packed geometry and step,
cannot be stepped together (:func:`batchable`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from omnibot.sim import jit
from omnibot.sim.kernels import layout as kernel_layout
from omnibot.sim.simulator import NO_FORCE, Simulator

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
ScalarT = TypeVar("ScalarT", bound=np.generic)


def batchable(sims: Sequence[Simulator]) -> bool:
    """Whether ``sims`` can be stepped by one :func:`~omnibot.sim.kernels.fleet_step`: each with a
    packed :class:`~omnibot.sim.physics.Physics`, all on the same packed world and step."""
    if not sims:
        return False
    first = sims[0]
    return all(
        s._packed is not None and s._world_packed is first._world_packed and s._dt_us == first._dt_us
        for s in sims
    )


def _spans(sizes: Sequence[int]) -> tuple[list[int], int]:
    """Where each of consecutive arrays of ``sizes`` starts, and their total size."""
    starts = np.concatenate(([0], np.cumsum(sizes, dtype=np.int64))).tolist()
    return starts[:-1], starts[-1]


class FleetArrays:
    """The step state of ``sims`` (:func:`batchable`) in fleet-wide arrays, stepped in one call."""

    def __init__(self, sims: Sequence[Simulator]) -> None:
        if not batchable(sims):
            raise ValueError("these simulators cannot be stepped together (see fleet_arrays.batchable)")
        self.sims = list(sims)
        first = sims[0]
        self._wf, self._wi = first._world_packed
        self._dt = first.dt
        n = len(self.sims)
        self.layout = np.zeros((n, kernel_layout.L_COLUMNS), dtype=np.int64)
        self.status = np.zeros(n, dtype=np.int64)
        self.extra = np.zeros((4 * n, 3))
        self._with_extra: list[int] = []
        floats = [s._step_state()[0] for s in self.sims]
        ints = [s._step_state()[1] for s in self.sims]
        fstarts, fsize = _spans([a.size for arrays in floats for a in arrays])
        istarts, isize = _spans([a.size for arrays in ints for a in arrays])
        self.fbuf = np.zeros(fsize)
        self.ibuf = np.zeros(isize, dtype=np.int64)
        f_cols = (kernel_layout.L_PBUF, kernel_layout.L_SF, kernel_layout.L_GYRO, kernel_layout.L_TRACKING)
        for k, (sim, own_f, own_i) in enumerate(zip(self.sims, floats, ints, strict=True)):
            row = self.layout[k]
            new_f = [self._slot(self.fbuf, fstarts[4 * k + a], own_f[a]) for a in range(4)]
            new_i = [self._slot(self.ibuf, istarts[2 * k + a], own_i[a]) for a in range(2)]
            for col, start, arr in zip(f_cols, fstarts[4 * k : 4 * k + 4], own_f, strict=True):
                row[col], row[col + 1] = start, start + arr.size
            row[kernel_layout.L_IDS], row[kernel_layout.L_SI] = istarts[2 * k], istarts[2 * k + 1]
            row[kernel_layout.L_SI_END] = istarts[2 * k + 1] + own_i[1].size
            assert sim._packed is not None
            row[kernel_layout.L_M], row[kernel_layout.L_N_SURF] = sim._packed.m, sim._n_surfaces
            sim._rehome(new_f, new_i)
        self.normals = np.zeros(0)
        self._gather_normals()

    @staticmethod
    def _slot(buffer: NDArray[ScalarT], start: int, like: NDArray[ScalarT]) -> NDArray[ScalarT]:
        """The view of ``buffer`` from ``start`` shaped as ``like``."""
        return buffer[start : start + like.size].reshape(like.shape)

    def _gather_normals(self) -> None:
        """Every robot's gyro and tracking normal draws into :attr:`normals` (again after a refill)."""
        arrays = [a for s in self.sims for a in (s._sensors[1], s._sensors[3])]
        starts, _ = _spans([a.size for a in arrays])
        self.normals = np.concatenate(arrays) if arrays else np.zeros(0)
        for j, (array, start) in enumerate(zip(arrays, starts, strict=True)):
            col = kernel_layout.L_GYRO_NORMALS if j % 2 == 0 else kernel_layout.L_TRACKING_NORMALS
            self.layout[j // 2, col], self.layout[j // 2, col + 1] = start, start + array.size

    def _gather_extra(self, now_us: int) -> None:
        """The extra-force rows acting on each robot this step (``Simulator._extra_forces``: its
        applied forces and hand pushes) into :attr:`extra`, each robot's first row and count into its
        layout row."""
        layout = self.layout
        for k in self._with_extra:
            layout[k, kernel_layout.L_N_EXTRA] = 0
        self._with_extra = []
        rows = 0
        for k, sim in enumerate(self.sims):
            count = sim._extra_forces(now_us)
            if count:
                if rows + count > len(self.extra):
                    self.extra = np.concatenate((self.extra, np.zeros((rows + count, 3))))
                self.extra[rows : rows + count] = sim._extra[:count]
                layout[k, kernel_layout.L_EXTRA], layout[k, kernel_layout.L_N_EXTRA] = rows, count
                self._with_extra.append(k)
                rows += count

    def step(self, now_us: int) -> None:
        """One step of every robot, the step beginning at ``now_us`` (every robot's clock reads it)."""
        sims = self.sims
        if self._with_extra or any([s._pushes or s._applied != NO_FORCE for s in sims]):
            self._gather_extra(now_us)
        every = jit.active.fleet_step(
            self.fbuf, self.ibuf, self.layout, self._wf, self._wi, self.normals, self.extra, self.status, now_us,
            self._dt,
        )  # fmt: skip
        if every:
            for sim, status in zip(sims, self.status.tolist(), strict=True):
                sim._finish_step(status, now_us)
            if every & kernel_layout.STEP_REFILL:
                self._gather_normals()
        else:
            for sim in sims:
                sim._finish_step(0, now_us)

    def release(self) -> None:
        """Give every robot its step state back in arrays of its own (they leave the fleet's)."""
        for sim in self.sims:
            floats, ints = sim._step_state()
            sim._rehome([a.copy() for a in floats], [a.copy() for a in ints])
        self.sims = []


__all__ = ["FleetArrays", "batchable"]
