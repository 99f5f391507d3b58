"""One simulated robot: physics, sensors and a world behind a small facade, on a simulated clock.

::

    set_pwm(...) -> step()/advance() ------------------------------------------------> clock += dt
                      |  one compiled call (kernels.robot_step) per step:
                      |    surface ids under each wheel   (when a wheel may have crossed a patch edge)
                      |    wall/obstacle push-back force  (when the robot may touch something)
                      |    + hand pushes (push()) and applied forces (a fleet's contacts), in order
                      |    physics step
                      |    pose log for the laser scanner (every 5 ms while someone wants scans)
                      |    tracking wheels, gyro (every step)
                      v
      encoders (when read) ; sonars (on ping, one compiled pass over the edges) ; listeners ;
      collision events ; laser scanner (when the step says a revolution is due: one compiled
      call casts and measures it; scan listeners)

A step costs a few microseconds: everything above the line is one compiled kernel call on arrays
(the physics' packed buffer, the world's packed geometry, the simulator's and the sensors' state
arrays), with Python only at the edges (commands in; readings, events and listeners out). A
physics of another kind (``physics_factory``) gets the same compiled parts before and after its
own step. Two exact broad phases skip the world geometry. Each probe of the world returns a
clearance: the contact test tells how far the robot's origin may move (any rotation) before its
outline could touch a wall or obstacle, the surface lookup how far the wheel contact points may
move before one could cross a patch edge (a contact point moves at most |dx, dy| + |d theta| r).
Until the robot has moved that far the previous answer (no contact; the same surfaces) stands, so
the result is the same as testing every step. Near a wall or a patch edge the test runs every step.
The numbers are those of the step it replaced, bit for bit (``tests/sim/test_step_trace.py``).

The simulator's concerns, each in a module of its own that :class:`Simulator` mixes in:
:mod:`~omnibot.sim.simulator_contacts` (the contact test, collision events: a penalty force, one
event when the robot starts touching a wall, obstacle or robot), :mod:`~omnibot.sim.simulator_sensors`
(encoders, tracking wheels, gyro, sonars), :mod:`~omnibot.sim.simulator_scan` (the laser scanner,
measuring only while someone wants scans), :mod:`~omnibot.sim.simulator_listeners` (a
:class:`~omnibot.sim.truth.Snapshot` once when added, then after every step or every ``period``
seconds; :class:`~omnibot.sim.truth.TruthRecorder` is such a listener writing ``t,x,y,theta`` CSV)
and :mod:`~omnibot.sim.simulator_state` (the compiled step's packed state). The physics it steps is
anything :class:`~omnibot.sim.physics_like.PhysicsLike`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import SimulationError, SimulationSetupError
from omnibot.motion import Pose2D, Twist
from omnibot.robot import RobotDescription
from omnibot.sim import jit
from omnibot.sim.clock import SimClock
from omnibot.sim.geometry import convex_hull
from omnibot.sim.kernels import layout
from omnibot.sim.kernels.layout import (
    A_N_EXTRA,
    A_NOW_US,
    STEP_BAD_SURFACE,
    STEP_COLLISION,
    STEP_REFILL,
    STEP_SCAN,
)
from omnibot.sim.physics import Physics
from omnibot.sim.physics_like import PhysicsFactory, PhysicsLike, default_physics
from omnibot.sim.simulator_contacts import Contacts
from omnibot.sim.simulator_listeners import Listeners
from omnibot.sim.simulator_scan import ScanFeed
from omnibot.sim.simulator_sensors import SensorReadings
from omnibot.sim.simulator_state import StepState
from omnibot.sim.truth import CollisionEvent, CollisionListener, TruthRecorder
from omnibot.sim.world import World, load_world

FloatArray = NDArray[np.float64]
NO_FORCE = [0.0, 0.0, 0.0]
"""No applied force: ``Simulator._applied`` equal to it (-0.0 too; a NaN is not) adds no extra-force row
(the robot stepped alone and in a fleet, :mod:`omnibot.sim.fleet_arrays`)."""


class PwmRangeError(SimulationError, ValueError):
    """A PWM command outside +-pwm_max or not one per wheel (the firmware must clamp)."""


class Simulator(Contacts, SensorReadings, ScanFeed, Listeners, StepState):
    """One robot in a world, stepped by hand; its clock moves only in :meth:`step` / :meth:`advance`.

    ``surface`` overrides the world's default floor (None keeps it; the default world is ``empty``,
    a wood floor). ``start_pose`` (x, y, theta) overrides the world's start (else the origin).
    ``physics_factory`` replaces :class:`~omnibot.sim.physics.Physics` (tests use a stand-in); the
    simulator keeps views of its ``pose`` and ``twist`` arrays, so it must update them in place.
    ``clock`` is the simulator's own clock (default a new one at 0; a fleet starts a robot that
    joins late at the fleet's time); the simulator advances it on every step.
    """

    def __init__(
        self,
        robot: RobotDescription,
        *,
        surface: str | None = None,
        world: World | str | Path | None = None,
        seed: int = 0,
        dt: float = 0.001,
        start_pose: Pose2D | Sequence[float] | None = None,
        truth_recorder: TruthRecorder | None = None,
        physics_factory: PhysicsFactory | None = None,
        clock: SimClock | None = None,
    ) -> None:
        self.robot = robot
        self.seed = seed
        dt_us = round(dt * 1e6)
        if dt_us <= 0 or abs(dt_us - dt * 1e6) > 1e-6:
            raise SimulationSetupError(f"dt must be a positive whole number of microseconds, got {dt} s")
        self._dt_us = dt_us
        self.dt = dt_us / 1e6
        self.clock = clock or SimClock()

        w = load_world("empty") if world is None else world if isinstance(world, World) else load_world(world)
        self.world = w.with_floor(surface) if surface is not None and surface != w.floor else w
        self._physics = self._make_physics(physics_factory or default_physics)
        self._place(start_pose)

        n_wheels = robot.n_wheels
        # a Physics: one compiled call per step, on its own input arrays; another kind: compiled
        # parts before and after its step
        self._packed = self._physics if isinstance(self._physics, Physics) else None
        self._pwm = self._packed.pwm if self._packed is not None else np.zeros((1, n_wheels))
        self._pwm_max = [wh.motor.pwm_max for wh in robot.wheels]
        self._wheel_names = [wh.name for wh in robot.wheels]
        self._outline = np.ascontiguousarray(convex_hull(robot.footprint.outline()), dtype=float)
        self._pushes: list[tuple[int, float, float, float]] = []
        self._applied = [0.0, 0.0, 0.0]
        self.neighbours: Callable[[], FloatArray] | None = None
        """Edges ``(K, 4)`` of other bodies in the world frame now (a fleet's other robots), which the
        sonars see as they see walls; None: nothing but the world."""
        self.collisions: list[CollisionEvent] = []
        self._collision_listeners: list[CollisionListener] = []
        self._listeners = []
        self._next_notify_us = 0
        self._pack_step_state()
        self._touching: dict[str, int] = {}
        """Last touch (us) of each body outside the world (a fleet's other robots) by name."""

        self._init_scan(self._make_sensors())
        self._sensors = self._sensor_arrays()
        self._bind_step()

        self._check_clear()
        if truth_recorder is not None:
            self.add_listener(truth_recorder, period=truth_recorder.period)

    def _make_physics(self, factory: PhysicsFactory) -> PhysicsLike:
        """The physics of one robot on the world's surfaces, and the map from the world's surface
        indices to the physics' (every surface the world uses must be one the physics knows)."""
        physics = factory(self.robot, n=1, surfaces=self.world.surface_names, dt=self.dt, seed=self.seed)
        known = [s.name for s in physics.surfaces]
        missing = [s for s in self.world.surface_names if s not in known]
        if missing:
            raise SimulationSetupError(
                f"world '{self.world.name}' uses surfaces the physics lacks: {missing}"
            )
        self._surface_map = np.array([known.index(s) for s in self.world.surface_names], dtype=np.int64)
        self._floor_ids = np.full((1, self.robot.n_wheels), self._surface_map[0], dtype=np.int64)
        return physics

    def _place(self, start_pose: Pose2D | Sequence[float] | None) -> None:
        """Put the robot at ``start_pose`` (else the world's start, else the origin) and keep views of
        its state rows."""
        given = start_pose if start_pose is not None else self.world.start or Pose2D(0.0, 0.0, 0.0)
        start = (given.x, given.y, given.theta) if isinstance(given, Pose2D) else tuple(given)
        if len(start) != 3:
            raise SimulationSetupError(f"start_pose is (x, y, theta), got {start}")
        self._physics.reset(pose=np.array([start], dtype=float))
        # views of robot 0's state: the physics updates its arrays in place
        self._pose_row = self._physics.pose[0]
        self._twist_row = self._physics.twist[0]

    # ------------------------------------------------------------------ state

    @property
    def outline(self) -> FloatArray:
        """The robot's footprint as a convex outline in its own frame (V, 2), counter-clockwise."""
        return self._outline

    @property
    def physics(self) -> PhysicsLike:
        """The physics engine the simulator steps."""
        return self._physics

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self.clock.now()

    @property
    def pose(self) -> Pose2D:
        """True world pose (x, y in m, theta in rad, continuous: not wrapped)."""
        x, y, th = self._pose_row.tolist()
        return Pose2D(x, y, th)

    @property
    def twist(self) -> Twist:
        """True body-frame velocity (vx, vy in m/s, w in rad/s)."""
        vx, vy, w = self._twist_row.tolist()
        return Twist(vx, vy, w)

    @property
    def wheel_speeds(self) -> list[float]:
        """True wheel speeds, rad/s, in robot.wheels order."""
        return [float(v) for v in self._physics.wheel_speed[0]]

    @property
    def wheel_surfaces(self) -> list[str]:
        """The floor surface under each wheel at the last step, in robot.wheels order."""
        return [self._physics.surfaces[int(i)].name for i in self._step_ids[0]]

    @property
    def pwm(self) -> list[int]:
        """The PWM values applied to the motors now."""
        return [int(v) for v in self._pwm[0]]

    @property
    def battery_charge(self) -> float:
        """The battery's state of charge, 0..1 (1 for an ideal battery: the description gave no ``charge``)."""
        own = getattr(self._physics, "battery_charge", None)
        return 1.0 if own is None else float(np.asarray(own, dtype=float).reshape(-1)[0])

    @property
    def battery_voltage(self) -> float:
        """Battery terminal voltage: nominal minus the internal-resistance drop of the drive current."""
        own = getattr(self._physics, "battery_voltage", None)
        if own is not None:
            return float(np.asarray(own, dtype=float).reshape(-1)[0])
        duty = np.abs(self._pwm[0]) / np.array(self._pwm_max, dtype=float)
        current = float(np.sum(np.abs(self._physics.motor_current[0]) * duty))
        bat = self.robot.battery
        return max(0.0, bat.voltage - bat.internal_resistance * current)

    # ------------------------------------------------------------------ commands

    def set_pwm(self, values: Sequence[int]) -> None:
        """Signed PWM counts, one per wheel (robot.wheels order). Out of range raises, never clamps."""
        vals = list(values)
        names = self._wheel_names
        if len(vals) != len(names):
            raise PwmRangeError(f"set_pwm needs {len(names)} values ({', '.join(names)}), got {len(vals)}")
        out = []
        for i, v in enumerate(vals):
            if isinstance(v, bool) or not isinstance(v, int | np.integer | float) or int(v) != v:
                raise PwmRangeError(f"PWM for wheel '{names[i]}' must be a whole number of counts, got {v!r}")
            if abs(int(v)) > self._pwm_max[i]:
                raise PwmRangeError(
                    f"PWM {int(v)} for wheel '{names[i]}' is outside +-{self._pwm_max[i]} "
                    "(the firmware must clamp)"
                )
            out.append(int(v))
        self._pwm[0] = out

    def lift_wheel(self, name: str, lifted: bool = True) -> None:
        """Fault injection: lift a wheel off the floor (it spins freely and drives nothing)."""
        index = self._wheel_names.index(self.robot.wheel(name).name)
        mask = np.array(self._physics.lifted, dtype=bool)
        mask[0, index] = lifted
        self._physics.lifted = mask

    def push(
        self,
        force_xy: Sequence[float],
        torque: float = 0.0,
        duration: float = 0.1,
        *,
        motors_off: bool = True,
    ) -> None:
        """Push the robot by hand: a world-frame force (N) and torque (N m) for ``duration`` s.

        Does not advance time: the push acts during the next steps (pushes add up). With
        ``motors_off`` (default) the PWM is set to zero first, as when seed 002 teaches a path by
        moving the robot by hand.
        """
        if duration < 0:
            raise ValueError(f"duration must be >= 0, got {duration}")
        if motors_off:
            self._pwm[:] = 0.0
        end = self.clock.ticks_us() + round(duration * 1e6)
        self._pushes.append((end, float(force_xy[0]), float(force_xy[1]), float(torque)))

    def apply_force(self, fx: float, fy: float, torque: float = 0.0) -> None:
        """A world-frame force (N) and torque (N m) acting during the next step only (forces of one
        step add up): how a fleet applies the contacts between its robots."""
        self._applied[0] += fx
        self._applied[1] += fy
        self._applied[2] += torque

    # ------------------------------------------------------------------ sensors

    # ------------------------------------------------------------------ listeners

    # ------------------------------------------------------------------ stepping

    def advance(self, seconds: float) -> None:
        """Step for ``seconds`` of simulated time (rounded to whole steps)."""
        if seconds < 0:
            raise ValueError(f"cannot advance by a negative time ({seconds} s)")
        self.step(round(seconds / self.dt))

    def step(self, n: int = 1) -> None:
        """Advance ``n`` steps of ``dt``."""
        for _ in range(n):
            now_us = self.clock.ticks_us()
            n_extra = self._extra_forces(now_us) if self._pushes or self._applied != NO_FORCE else 0
            args = self._step_args  # bound once (_bind_step): only the count and the time change
            if args is not None:
                args[A_N_EXTRA], args[A_NOW_US] = n_extra, now_us
                status = jit.active.robot_step(*args)
            else:
                status = self._step_other(now_us, n_extra)
            self._finish_step(status, now_us)

    def _finish_step(self, status: int, now_us: int) -> None:
        """What follows the compiled step of the step that began at ``now_us`` (its ``status`` bits;
        a fleet's :func:`~omnibot.sim.kernels.fleet_step` too): the collision events, the clock, the
        sensors' normal draws, the scanner and the listeners."""
        if status & STEP_BAD_SURFACE:
            raise SimulationError(f"surface_ids must index the {self._n_surfaces} surfaces of this Physics")
        if self._packed is not None:
            self._packed.count_step()
        if status & STEP_COLLISION:
            self._collisions_found()
        self.clock.advance_us(self._dt_us)
        if status & (STEP_REFILL | STEP_SCAN):
            self._refill_and_scan(status, now_us + self._dt_us)
        if self._listeners and now_us + self._dt_us >= self._next_notify_us:
            self._notify()

    def _refill_and_scan(self, status: int, end_us: int) -> None:
        """The sensors' new normal draws and the scanner's revolution a step ending at ``end_us`` asks
        for (its ``status`` bits)."""
        if status & STEP_REFILL:
            self.tracking.refill()
            if self.gyro is not None:
                self.gyro.refill(self.dt)
            self._sensors = self._sensor_arrays()
            self._bind_step()
        if status & STEP_SCAN:
            self._scan_tick(end_us)

    def _step_other(self, now_us: int, n_extra: int) -> int:
        """A step with a physics of another kind: the compiled step's parts before and after its step."""
        state = self._state6
        state[:3], state[3:] = self._pose_row, self._twist_row
        status = jit.active.robot_before(
            state,
            self._step_ids,
            *self._world_packed,
            self._sf,
            self._si,
            self._extra,
            n_extra,
            self._force,
            now_us,
        )
        force = self._force if status & layout.STEP_FORCE else None
        self._physics.step(self._pwm, self._step_ids, force)
        state[:3], state[3:] = state[3:], self._twist_row
        if self._si[layout.I_LOG_ON]:
            pose = self._pose_row
            status |= jit.active.pose_log(
                self._sf, self._si, float(pose[0]), float(pose[1]), float(pose[2]), now_us
            )
        return status | jit.active.robot_after(state, self.dt, *self._sensors)

    def _extra_forces(self, now_us: int) -> int:
        """Put the applied force and the hand pushes still acting into the extra-force rows; their count."""
        rows: list[Sequence[float]] = []
        if self._applied != NO_FORCE:
            rows.append(self._applied)
            self._applied = [0.0, 0.0, 0.0]
        if self._pushes:
            self._pushes = [p for p in self._pushes if p[0] > now_us]
            rows += [p[1:] for p in self._pushes]
        if len(rows) > len(self._extra):
            self._extra = np.zeros((2 * len(rows), 3))
            self._bind_step()
        if rows:
            self._extra[: len(rows)] = rows
        return len(rows)
