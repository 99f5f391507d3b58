"""Several simulated robots in one world on one clock: each its own firmware, seed and preset.

::

    Fleet.step():  every robot's firmware polls (sonar pings see the others where they stand now)
                   -> robot-robot contacts (the pairs whose bounding circles meet, from a sweep and
                      prune along x made again only when a robot has moved 25 mm since the last:
                      omnibot.sim.broadphase; then separating axes, the same kernel as the walls)
                      -> equal and opposite penalty forces
                   -> every robot's physics steps (its walls, its pushes, those forces), all in one
                      compiled call on the fleet's arrays (omnibot.sim.fleet_arrays) -> clock += dt
                   -> while a scanner is on, every 5 ms: every robot's step logs its pose; the
                      scanners due cast their rays (each ray sees the others where they were then)

A robot is a :class:`~omnibot.sim.device.SimDevice` (firmware + :class:`Simulator`) with a name;
an omni3 and an omni4 may share a room. Each robot's footprint (its convex hull) is a body the
others collide with and an obstacle their sonar cones and laser scanners see
(``Simulator.neighbours``). Contacts
between robots are the walls' contact law with the two bodies' effective mass: a critically damped
penalty spring along the normal (natural frequency 0.25/dt) plus the walls' friction, and a
:class:`~omnibot.sim.truth.CollisionEvent` whose owner is ``robot NAME`` when two robots start
touching. Robots are stepped in the order of their names, so a run does not depend on the order
they joined in.

A :class:`Fleet` is stepped by one owner; :mod:`omnibot.sim.fleet_link` serves it to several
links (``sim://omni4?fleet=NAME&name=r1``) and threads, and ``omnibot sim --pty`` with several
``--robot`` options serves it on one pty per robot.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import ConfigError, SimulationError
from omnibot.motion import Pose2D
from omnibot.robot import RobotDescription
from omnibot.sim import jit
from omnibot.sim.broadphase import Footprints, NearPairs
from omnibot.sim.clock import SimClock
from omnibot.sim.device import SimDevice
from omnibot.sim.fleet_arrays import FleetArrays, batchable
from omnibot.sim.geometry import placed
from omnibot.sim.scanner import PoseLog
from omnibot.sim.simulator import Simulator
from omnibot.sim.simulator_contacts import CONTACT_DAMPING, CONTACT_OMEGA_DT, WALL_FRICTION
from omnibot.sim.simulator_scan import SCAN_POSE_PERIOD
from omnibot.sim.world import Contact, World

FloatArray = NDArray[np.float64]

_NO_EDGES = np.zeros((0, 2))
_NO_OWNERS = np.zeros(0, dtype=np.int64)
_ONE_SOLID = np.array([0], dtype=np.int64)


@dataclass
class _Body:
    """What the fleet keeps of one robot: its device and the footprint geometry of its contacts."""

    name: str
    device: SimDevice
    outline: FloatArray
    """Convex footprint in the robot's frame (V, 2)."""
    reach: float
    """Largest distance from the robot's origin to its footprint, m (the bounding circle)."""
    offsets: NDArray[np.int64]

    @property
    def sim(self) -> Simulator:
        return self.device.sim

    @property
    def pose_row(self) -> FloatArray:
        """The live true pose (x, y, theta), a read-only view (of the fleet's arrays once it joined)."""
        return self.sim.pose_array

    def hull(self) -> FloatArray:
        """The footprint in the world frame now."""
        p = self.sim.pose
        return np.ascontiguousarray(placed(self.outline, p.x, p.y, p.theta))


class Fleet:
    """Robots sharing ``world`` (already with its floor) and one clock of step ``dt`` s."""

    def __init__(self, world: World, *, dt: float = 0.001) -> None:
        self.world = world
        self.dt = dt
        self._dt_us = round(dt * 1e6)
        self._us = 0
        self._bodies: dict[str, _Body] = {}
        self._order: list[_Body] = []
        self._out = np.zeros((2, 6))
        self._controls: list[Callable[[], None]] = []
        self._steps: list[Callable[[], None]] = []
        self._pose_rows: list[FloatArray] = []
        """Every robot's firmware poll, physics step and live pose row, in step order."""
        self._arrays: FleetArrays | None = None
        """Every robot's step state in fleet-wide arrays, stepped in one call (None: robot by robot,
        when their physics or worlds differ: :func:`~omnibot.sim.fleet_arrays.batchable`)."""
        self._near = NearPairs([])
        self._footprints = Footprints([])
        self._edges = np.zeros((0, 4))
        self._edges_rows: dict[str, tuple[int, int]] = {}
        self._edges_tick = -1
        self._scan_stride_us = max(1, round(SCAN_POSE_PERIOD / dt)) * self._dt_us
        self._scan_flush_us = 0
        self._scan_log = PoseLog([], self._scan_stride_us / 1e6)
        self._scanning: list[tuple[int, Simulator]] = []
        """(index in the step order, simulator) of every robot whose scanner is on."""
        self._scan_due: list[int] = []
        self._outlines: tuple[FloatArray, NDArray[np.int64]] = (np.zeros((0, 2)), np.zeros(1, dtype=np.int64))

    def __repr__(self) -> str:
        return f"Fleet({self.world.name!r}, robots {self.names}, t={self.time:.3f} s)"

    @property
    def time(self) -> float:
        """Simulated time, s (every robot's clock reads the same)."""
        return self._us / 1e6

    @property
    def ticks_us(self) -> int:
        """Simulated time in whole microseconds."""
        return self._us

    @property
    def names(self) -> list[str]:
        """The robots' names, in the order they are stepped."""
        return [b.name for b in self._order]

    def __len__(self) -> int:
        return len(self._order)

    def device(self, name: str) -> SimDevice:
        """The robot called ``name``."""
        return self._bodies[name].device

    # ------------------------------------------------------------------ membership

    def add(
        self,
        name: str,
        robot: RobotDescription | str,
        *,
        seed: int = 0,
        pose: Pose2D | None = None,
        **device_options: Any,
    ) -> SimDevice:
        """Put a new robot called ``name`` at ``pose`` (default: the world's start, else the origin).

        ConfigError for a name already taken or a pose whose footprint overlaps a wall, an obstacle
        or another robot. ``device_options`` go to :class:`SimDevice` (``true_robot``,
        ``firmware_overrides``, ``truth_recorder``). Whenever a robot joins or leaves, every robot's
        step state moves into new fleet-wide arrays (:mod:`omnibot.sim.fleet_arrays`; a robot leaving
        gets arrays of its own): read it through the simulator (``sim.pose``, ``sim.physics.pose``),
        not through arrays taken from it before.
        """
        if not name:
            raise ConfigError("a robot of a fleet needs a name", key="name")
        if name in self._bodies:
            raise ConfigError(
                f"fleet already has a robot named {name!r} (robots: {', '.join(self.names)})", key="name"
            )
        try:
            device = SimDevice(
                robot,
                world=self.world,
                seed=seed,
                dt=self.dt,
                start_pose=pose if pose is None else (pose.x, pose.y, pose.theta),
                clock=SimClock(self._us),
                **device_options,
            )
        except SimulationError as exc:
            raise ConfigError(f"robot {name!r}: {exc}", key="pose") from None
        outline = device.sim.outline
        body = _Body(
            name,
            device,
            outline,
            float(np.max(np.hypot(outline[:, 0], outline[:, 1]))),
            np.array([0, len(outline)]),
        )
        for other in self._order:
            if self._pair_contact(body, other) is not None:
                raise ConfigError(
                    f"robot {name!r} at {device.sim.pose.text()} overlaps robot "
                    f"{other.name!r}; give each robot its own pose=X,Y,THETA",
                    key="pose",
                )
        device.sim.neighbours = partial(self._edges_except, name)
        self._bodies[name] = body
        self._order = sorted(self._bodies.values(), key=lambda b: b.name)
        self._members_changed()
        device.sim.set_scan_driver(self._scan_switched)
        return device

    def remove(self, name: str) -> None:
        """Take the robot ``name`` out of the world (no error if it is not there)."""
        body = self._bodies.pop(name, None)
        if body is not None:
            body.sim.neighbours = None
            self._order = [b for b in self._order if b is not body]
            body.sim._pose_log_stop()
            body.sim.set_scan_driver(None)
            self._members_changed()

    def _members_changed(self) -> None:
        """A robot joined or left: the fleet's arrays, the broad phase, the footprints and the
        scanners' log start again."""
        if self._arrays is not None:
            self._arrays.release()
        sims = [b.sim for b in self._order]
        self._arrays = FleetArrays(sims) if batchable(sims) else None
        self._controls = [b.device.control for b in self._order]
        self._steps = [b.sim.step for b in self._order]
        self._pose_rows = [b.pose_row for b in self._order]
        self._near = NearPairs([b.reach for b in self._order])
        self._footprints = Footprints([b.outline for b in self._order])
        bounds = self._footprints.bounds
        self._edges_rows = {b.name: (int(bounds[i]), int(bounds[i + 1])) for i, b in enumerate(self._order)}
        self._edges_tick = -1
        self._rescan()

    # ------------------------------------------------------------------ stepping

    def step(self) -> None:
        """One step of every robot: firmware polls, contacts between robots, physics."""
        for control in self._controls:
            control()
        bodies = self._order
        for i, j in self._near_pairs():
            self._push_apart(bodies[i], bodies[j])
        if self._arrays is not None:
            self._arrays.step(self._us)
        else:
            for step in self._steps:
                step()
        self._us += self._dt_us
        if self._scanning and self._us >= self._scan_flush_us:
            self._scan_step()

    def _near_pairs(self) -> list[tuple[int, int]]:
        """The pairs (i < j, in step order) of robots whose bounding circles may meet, sorted
        (:class:`~omnibot.sim.broadphase.NearPairs`); :meth:`_pair_contact` makes the exact test."""
        return self._near.pairs([row.tolist() for row in self._pose_rows])

    # ------------------------------------------------------------------ laser scanners

    def _scan_switched(self, sim: Simulator) -> None:
        """A robot's scanner started or stopped (its simulator's scan_driver)."""
        self._rescan()

    def _rescan(self) -> None:
        """Start the pose log again for the robots now in the fleet (every scanner that is on drops
        its revolution under way and starts with the next: the log's layout changed)."""
        sims = [b.sim for b in self._order]
        self._scanning = [(i, s) for i, s in enumerate(sims) if s.scanner is not None and s.scanner.active]
        if not self._scanning:
            for s in sims:
                s._pose_log_stop()
            self._scan_log = PoseLog([], self._scan_stride_us / 1e6)
            return
        now = self._us / 1e6
        for s in sims:  # every robot's step records its pose: the scanners see the others
            s._pose_log_start(self._us)
        self._scan_log = PoseLog(sims, self._scan_stride_us / 1e6, self._us)
        outlines = [b.outline for b in self._order]
        offsets = np.cumsum([0] + [len(o) for o in outlines]).astype(np.int64)
        self._outlines = (np.ascontiguousarray(np.vstack(outlines), dtype=np.float64), offsets)
        for _, s in self._scanning:
            assert s.scanner is not None
            s.scanner.start(now)
        self._scan_due = [
            Simulator._due_us(s.scanner.due) for _, s in self._scanning if s.scanner is not None
        ]
        self._scan_flush_us = self._scan_log.flush_at(min(self._scan_due))

    def _scan_step(self) -> None:
        """Flush the scanners that are due (the robots' steps have just recorded their poses; all of
        them when the pose logs are full) and trim the logs."""
        log, now = self._scan_log, self._us
        full = now >= log.start_us + (log.capacity - 1) * log.stride_us
        for k, (index, sim) in enumerate(self._scanning):
            if full or now >= self._scan_due[k]:
                self._scan_due[k] = sim.scan_flush(now, log, index, self._outlines)
        log.trim(min(s.scanner.needs_from for _, s in self._scanning if s.scanner is not None))
        self._scan_flush_us = log.flush_at(min(self._scan_due))

    def _edges_except(self, name: str) -> FloatArray:
        """The footprint edges (K, 4) of every robot but ``name``, world frame, as they stood when
        first asked for during this step (the sonars ask before the robots move, the scanners after
        their own robot moved: at most one step apart); placed once per step for all the askers."""
        if self._edges_tick != self._us:
            self._edges = self._footprints.place([row.tolist() for row in self._pose_rows])
            self._edges_tick = self._us
        lo, hi = self._edges_rows[name]
        return np.concatenate((self._edges[:lo], self._edges[hi:]))

    def _pair_contact(self, a: _Body, b: _Body) -> Contact | None:
        """Where ``a``'s footprint overlaps ``b``'s (normal pushing ``a`` out), None if apart."""
        pa, pb = a.sim.pose, b.sim.pose
        if math.hypot(pa.x - pb.x, pa.y - pb.y) >= a.reach + b.reach:
            return None
        hull = b.hull()
        centre = hull.mean(axis=0)
        count, _ = jit.active.outline_contacts(
            a.outline,
            pa.x,
            pa.y,
            pa.theta,
            hull,
            b.offsets,
            centre.reshape(1, 2),
            np.array([float(np.max(np.hypot(*(hull - centre).T)))]),
            _ONE_SOLID,
            _NO_EDGES,
            _NO_OWNERS,
            self._out,
        )
        if not count:
            return None
        px, py, nx, ny, depth, _ = self._out[0].tolist()
        return Contact((px, py), (nx, ny), depth, f"robot {b.name}")

    def _push_apart(self, a: _Body, b: _Body) -> None:
        """The contact force between two robots, applied to both (equal and opposite)."""
        contact = self._pair_contact(a, b)
        if contact is None:
            return
        (px, py), (nx, ny), depth = contact.point, contact.normal, contact.depth
        sa, sb = a.sim, b.sim
        va, vb = _point_velocity(sa, px, py), _point_velocity(sb, px, py)
        rel_x, rel_y = va[0] - vb[0], va[1] - vb[1]
        vn, vt = rel_x * nx + rel_y * ny, -rel_x * ny + rel_y * nx
        pa, pb = sa.pose, sb.pose
        ran = (px - pa.x) * ny - (py - pa.y) * nx
        rbn = (px - pb.x) * ny - (py - pb.y) * nx
        inv_mass = (
            1.0 / sa.robot.mass
            + ran * ran / sa.robot.yaw_inertia
            + 1.0 / sb.robot.mass
            + rbn * rbn / sb.robot.yaw_inertia
        )
        m_eff = 1.0 / inv_mass
        omega = CONTACT_OMEGA_DT / self.dt
        fn = max(0.0, m_eff * omega * omega * depth - 2 * CONTACT_DAMPING * m_eff * omega * vn)
        ft = -WALL_FRICTION * fn * math.tanh(vt / 0.05)
        fx, fy = fn * nx - ft * ny, fn * ny + ft * nx
        sa.apply_force(fx, fy, (px - pa.x) * fy - (py - pa.y) * fx)
        sb.apply_force(-fx, -fy, -((px - pb.x) * fy - (py - pb.y) * fx))
        sa.touch(contact, -vn)
        sb.touch(Contact(contact.point, (-nx, -ny), depth, f"robot {a.name}"), -vn)


def _point_velocity(sim: Simulator, px: float, py: float) -> tuple[float, float]:
    """World-frame velocity of the robot's body at point (px, py)."""
    p, t = sim.pose, sim.twist
    c, s = math.cos(p.theta), math.sin(p.theta)
    vx, vy = c * t.vx - s * t.vy, s * t.vx + c * t.vy
    return vx - t.w * (py - p.y), vy + t.w * (px - p.x)
