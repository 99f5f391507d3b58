"""One simulated robot: physics, sensors and a world behind a small facade, on a simulated clock.

::

    set_pwm(...) -> step()/advance() ------------------------------------------------> clock += dt
                      |  one compiled call (kernels.robot_step) per step:
                      |    surface ids under each wheel   (when a wheel may have crossed a patch edge)
                      |    wall/obstacle push-back force  (when the robot may touch something)
                      |    + hand pushes (push()) and applied forces (a fleet's contacts), in order
                      |    physics step
                      |    tracking wheels, gyro (every step)
                      v
      encoders (when read) ; sonars (on ping, one compiled pass over the edges) ; listeners ;
      collision events ; laser scanner (pose recorded every 5 ms while someone wants scans, rays
      cast once per revolution; scan listeners)

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

Collisions use a penalty force: each contact pushes along its normal with a spring-damper whose
stiffness is set from the simulation step (natural frequency 0.25/dt for the effective mass at the
contact point, critically damped), so the response is stiff yet stable for any robot mass, plus a
little wall friction. The robot sinks at most millimetres into a wall. A collision event is
reported when the robot starts touching a wall or obstacle (after 0.25 s without touching it,
so one bump that bounces is one event).

Listeners get a :class:`~omnibot.sim.truth.Snapshot` once when added and then after every step, or
every ``period`` seconds; :class:`~omnibot.sim.truth.TruthRecorder` is such a listener writing
``t,x,y,theta`` CSV.

A robot with a ``scanner`` has a :class:`~omnibot.sim.scanner.LaserScanner` (:attr:`Simulator.scanner`).
It measures only while someone wants scans: a scan listener is registered
(:meth:`Simulator.add_scan_listener`) or :attr:`Simulator.last_scan` has been read once; otherwise it
costs one comparison per step. Scan listeners are called from :meth:`Simulator.step` (the stepping
thread, in simulated time) with every revolution completed, as an :class:`omnibot.scan.Scan`. The
scanner sees the world's walls and obstacles, never its own robot. In a fleet it sees the other
robots where they were at each ray's time: the fleet records every robot's pose and flushes the
scanners (:attr:`Simulator.scan_driver`). Bodies given by a :attr:`Simulator.neighbours` of another
kind are seen as they stand when the rays are cast (every 20 ms then).
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.errors import SimulationError, SimulationSetupError
from omnibot.motion import Pose2D, Twist
from omnibot.robot import RobotDescription
from omnibot.scan import Scan
from omnibot.sim import jit, kernels
from omnibot.sim.clock import SimClock
from omnibot.sim.geometry import convex_hull
from omnibot.sim.kernels import layout
from omnibot.sim.physics import Physics
from omnibot.sim.scanner import LaserScanner, PoseLog
from omnibot.sim.sensors import Gyro, MotorEncoders, Sonar, TrackingWheels
from omnibot.sim.truth import (
    CollisionEvent,
    CollisionListener,
    Listener,
    ScanListener,
    Snapshot,
    TruthRecorder,
)
from omnibot.sim.world import Contact, World, load_world

FloatArray = NDArray[np.float64]

CONTACT_OMEGA_DT = 0.25
"""Contact spring natural frequency times dt (well inside the explicit-integration limit of 2)."""
CONTACT_DAMPING = 1.0
WALL_FRICTION = 0.2
CONTACT_RELEASE = 0.25
"""Seconds without touching after which touching the same wall again is a new collision event."""

# fixed RNG stream keys, so that adding one sensor does not change another's noise
_RNG_ENCODERS, _RNG_TRACKING, _RNG_GYRO, _RNG_SONAR, _RNG_SCANNER = 0, 1, 2, 100, 200
SCAN_POSE_PERIOD = 0.005
"""s: how often the pose is recorded for the scanner while it is on (every step if dt is longer).
The rays' poses are linear between records: off by at most v w T^2 / 8 on a curve (31 um at 1 m/s
and 10 rad/s), far below any scanner's noise (10 mm at 1 m), at a fifth of the cost of recording every step."""
SCAN_OTHERS_EVERY = 0.02
"""s: how often a scanner with :attr:`Simulator.neighbours` but no :attr:`Simulator.scan_driver` casts
the rays due, so that it sees those bodies at most this long after the rays' times (a fleet's
scanners see the others at the rays' times; alone, a scanner casts once per revolution)."""


class PwmRangeError(SimulationError, ValueError):
    """A PWM command outside +-pwm_max or not one per wheel (the firmware must clamp)."""


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


@dataclass
class _ListenerSlot:
    fn: Listener
    period_us: int
    next_us: int


def _rng(seed: int, key: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(key,)))


def _default_physics(robot: RobotDescription, **kwargs: Any) -> PhysicsLike:
    from omnibot.sim.physics import Physics

    accepted = inspect.signature(Physics).parameters
    if "seed" not in accepted:
        kwargs.pop("seed", None)
    return Physics(robot, **kwargs)


class Simulator:
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
        self._physics = self._make_physics(physics_factory or _default_physics)
        start = self._place(start_pose)

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
        self._listeners: list[_ListenerSlot] = []
        self._next_notify_us = 0
        self._pack_step_state()
        self._touching: dict[str, int] = {}
        """Last touch (us) of each body outside the world (a fleet's other robots) by name."""

        self._make_sensors()
        self.scan_driver: Callable[[Simulator], None] | None = None
        """Who records the poses and flushes the scanner instead of the simulator (a fleet: see
        :meth:`set_scan_driver`); called with the simulator when its scanner starts or stops."""

        self._check_clear(start)
        if truth_recorder is not None:
            self.add_listener(truth_recorder, period=truth_recorder.period)

    def _check_clear(self, start: tuple[float, ...]) -> None:
        """Refuse a start pose whose outline overlaps the world."""
        x, y, th = self._pose_row.tolist()
        touching = self._find_contacts(x, y, th)
        if touching >= 0:
            raise SimulationSetupError(
                f"start pose {tuple(float(c) for c in start)} overlaps {self.world.contact_owners[touching]} "
                f"of world '{self.world.name}'"
            )

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

    def _place(self, start_pose: Pose2D | Sequence[float] | None) -> tuple[float, ...]:
        """Put the robot at ``start_pose`` (else the world's start, else the origin) and keep views of
        its state rows; returns the start as given."""
        given = start_pose if start_pose is not None else self.world.start or Pose2D(0.0, 0.0, 0.0)
        start = (given.x, given.y, given.theta) if isinstance(given, Pose2D) else tuple(given)
        if len(start) != 3:
            raise SimulationSetupError(f"start_pose is (x, y, theta), got {start}")
        self._physics.reset(pose=np.array([start], dtype=float))
        # views of robot 0's state: the physics updates its arrays in place
        self._pose_row = self._physics.pose[0]
        self._twist_row = self._physics.twist[0]
        return start

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
        of0, of1, of2, of3, of_end, oi0, oi1, oi2, oi3, oi_end = kernels.sim_offsets.py_func(si)
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
        sf[of3:of_end] = np.array([wh.position for wh in robot.wheels], dtype=float).ravel()
        self._contact_out = sf[of1:of2].reshape(n_rows, 6)
        self._contact_speed = sf[of2:of3]
        self._new_contact = self._si[oi1:oi2]
        self._world_packed = self.world.packed
        self._extra = np.zeros((4, 3))
        self._step_ids = self._ids if self._patchy else self._floor_ids
        self._n_surfaces = len(self._physics.surfaces)
        self._state6 = np.zeros(6)
        self._force = np.zeros((1, 3))

    def _make_sensors(self) -> None:
        """The encoders, tracking wheels, gyro, sonars and laser scanner, each on its own random
        stream of the seed."""
        robot, seed = self.robot, self.seed
        enc_index = np.array(
            [self._wheel_names.index(e.wheel) for e in robot.encoders.motors], dtype=np.int64
        )
        angles = self._physics.wheel_angle
        self._encoder_wheels: list[int] = enc_index.tolist()
        self.encoders = MotorEncoders(
            [e.counts_per_rev for e in robot.encoders.motors],
            _rng(seed, _RNG_ENCODERS),
            initial_angles=angles[0, enc_index],
            source=lambda: self._physics.wheel_angle[0, enc_index],
        )
        self.tracking = TrackingWheels(robot.encoders.tracking, _rng(seed, _RNG_TRACKING))
        self.gyro = Gyro(robot.gyro, _rng(seed, _RNG_GYRO)) if robot.gyro is not None else None
        if self.gyro is not None:
            self.gyro.refill(self.dt)
        self._no_gyro = np.zeros(0)
        self._sensors = self._sensor_arrays()
        self.sonars = [Sonar(s, _rng(seed, _RNG_SONAR + i)) for i, s in enumerate(robot.sonars)]
        self._scanner = LaserScanner(robot.scanner, seed, _RNG_SCANNER) if robot.scanner is not None else None
        self._scan_listeners: list[ScanListener] = []
        self._scan_asked = False
        self._scan_on = False
        self._scan_self = False  # on, and recorded and flushed here (no scan_driver)
        self._scan_due_us = 0
        self._scan_stride_us = max(1, round(SCAN_POSE_PERIOD / self.dt)) * self._dt_us
        self._scan_next_us = 0
        self._scan_log = PoseLog(1, self._scan_stride_us / 1e6)

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
    def contacts(self) -> list[Contact]:
        """Contacts found at the start of the last step."""
        return self.world.contact_list(self._contact_out[: self._si[layout.I_COUNT]])

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

    def snapshot(self) -> Snapshot:
        """The robot's time, pose and velocity now."""
        x, y, th = self._pose_row.tolist()
        vx, vy, w = self._twist_row.tolist()
        return Snapshot(self.clock.now(), x, y, th, vx, vy, w)

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

    def encoder_counts(self) -> list[int]:
        """Motor encoder counts in robot.encoders.motors order."""
        return [int(c) for c in self.encoders.counts]

    def encoder_count(self, index: int) -> int:
        """Motor encoder ``index``'s count: ``encoder_counts()[index]``, the others not counted (unless
        edges may be missed: those are drawn for all at once)."""
        encoders = self.encoders
        if encoders.miss_probability > 0.0:
            return self.encoder_counts()[index]
        return encoders.count_at(index, float(self._physics.wheel_angle[0, self._encoder_wheels[index]]))

    def tracking_counts(self) -> list[int]:
        """Tracking-wheel encoder counts in robot.encoders.tracking order."""
        return [int(c) for c in self.tracking.counts]

    def gyro_rate(self) -> float:
        """Latest gyro sample, rad/s."""
        if self.gyro is None:
            raise SimulationError(f"robot '{self.robot.name}' has no gyro")
        return self.gyro.rate

    def sonar_ping(self, index: int | str = 0) -> float | None:
        """Range (m) from sonar ``index`` (position or name), or None for no echo.

        Pinging again within the sonar's ``period_min`` returns the previous result (see
        :meth:`omnibot.sim.sensors.Sonar.ping`).
        """
        if isinstance(index, str):
            names = [s.spec.name for s in self.sonars]
            if index not in names:
                raise SimulationError(f"robot '{self.robot.name}' has no sonar '{index}' (has {names})")
            index = names.index(index)
        if not 0 <= index < len(self.sonars):
            raise SimulationError(
                f"robot '{self.robot.name}' has {len(self.sonars)} sonars, no index {index}"
            )
        others = self.neighbours() if self.neighbours is not None else None
        return self.sonars[index].ping(self.time, self._physics.pose[0], self.world, others)

    @property
    def scanner(self) -> LaserScanner | None:
        """The robot's laser scanner, or None if its description has none."""
        return self._scanner

    @property
    def last_scan(self) -> Scan | None:
        """The latest complete revolution of the scanner (None before the first, or without a scanner).

        Reading it switches the scanner on for good (it stays on: someone wants scans), so the first
        read returns None and a revolution is there one to two revolutions of simulated time later.
        """
        if self._scanner is None:
            return None
        if not self._scan_asked:
            self._scan_asked = True
            self._scan_switch()
        return self._scanner.last

    def add_scan_listener(self, fn: ScanListener) -> None:
        """Call ``fn(scan)`` with every revolution the scanner completes from now on (in simulated
        time, from the thread that steps the simulator). SimulationError if the robot has no scanner."""
        if self._scanner is None:
            raise SimulationError(f"robot '{self.robot.name}' has no scanner (add a 'scanner:' section)")
        self._scan_listeners.append(fn)
        self._scan_switch()

    def remove_scan_listener(self, fn: ScanListener) -> None:
        """Stop calling ``fn`` (no error if it was not registered)."""
        self._scan_listeners = [f for f in self._scan_listeners if f != fn]
        self._scan_switch()

    def _scan_switch(self) -> None:
        """Start or stop the scanner as someone wants scans or nobody does."""
        sc = self._scanner
        if sc is None:
            return
        want = bool(self._scan_listeners) or self._scan_asked
        if want == self._scan_on:
            return
        self._scan_on = want
        if want:
            now_us = self.clock.ticks_us()
            sc.start(now_us / 1e6)
            self._scan_due_us = self._due_us(sc.due)
            if self.scan_driver is None:
                self._scan_log.reset(now_us / 1e6, self._pose_row.tolist())
                self._scan_next_us = now_us + self._scan_stride_us
        else:
            sc.stop()
        self._scan_self = want and self.scan_driver is None
        if self.scan_driver is not None:
            self.scan_driver(self)

    def set_scan_driver(self, driver: Callable[[Simulator], None] | None) -> None:
        """Let ``driver`` (a fleet) record the poses and call :meth:`scan_flush` (None: the simulator
        does it). A revolution under way is dropped; the scanner goes on if someone wants scans."""
        asked, listeners = self._scan_asked, self._scan_listeners
        self._scan_asked, self._scan_listeners = False, []
        self._scan_switch()  # off under the old driver
        self.scan_driver = driver
        self._scan_asked, self._scan_listeners = asked, listeners
        self._scan_switch()  # on again under the new one

    @property
    def pose_array(self) -> FloatArray:
        """The live true pose (x, y, theta) as a read-only (3,) view (what a fleet records)."""
        view: FloatArray = self._pose_row.view()
        view.flags.writeable = False
        return view

    @staticmethod
    def _due_us(due: float) -> int:
        """A flush time in s as the first step end (whole us) at or after it."""
        return math.ceil(due * 1e6 - 1e-3)

    def scan_flush(
        self,
        now_us: int,
        poses: PoseLog,
        own: int = 0,
        bodies: tuple[FloatArray, NDArray[np.int64]] | None = None,
    ) -> int:
        """Cast the scanner's rays due by ``now_us`` with the poses of ``poses`` (this robot is body
        ``own``; ``bodies`` the outlines of all, see :meth:`LaserScanner.flush`), hand the completed
        revolutions to the scan listeners, and return when (us) the next flush is due."""
        sc = self._scanner
        if sc is None or not self._scan_on:
            return 2**62
        segments = self.world.segments
        others = self.neighbours() if self.neighbours is not None and self.scan_driver is None else None
        if others is not None and len(others):
            segments = np.concatenate((segments, others))
        scans = sc.flush(now_us / 1e6, segments, poses, own, bodies)
        due = self._due_us(sc.due)
        if others is not None:
            due = min(due, now_us + round(SCAN_OTHERS_EVERY * 1e6))
        self._scan_due_us = due
        for scan in scans:
            for fn in list(self._scan_listeners):
                fn(scan)
        return due

    def _scan_tick(self, now_us: int) -> None:
        """Record the pose for the scanner (the robot alone) and flush it when due."""
        self._scan_log.rows.extend(self._pose_row.tolist())
        self._scan_next_us += self._scan_stride_us
        if now_us >= self._scan_due_us:
            assert self._scanner is not None
            self.scan_flush(now_us, self._scan_log)
            self._scan_log.trim(self._scanner.needs_from)

    # ------------------------------------------------------------------ listeners

    def add_listener(self, fn: Listener, period: float | None = None) -> None:
        """Call ``fn(snapshot)`` now, then after every step (period None) or every ``period`` s."""
        period_us = 0 if period is None else max(1, round(period * 1e6))
        now = self.clock.ticks_us()
        self._listeners.append(_ListenerSlot(fn, period_us, now + period_us))
        self._next_notify_us = min(slot.next_us for slot in self._listeners)
        fn(self.snapshot())

    def remove_listener(self, fn: Listener) -> None:
        """Stop calling ``fn``."""
        self._listeners = [s for s in self._listeners if s.fn != fn]
        self._next_notify_us = min((slot.next_us for slot in self._listeners), default=0)

    def on_collision(self, fn: CollisionListener) -> None:
        """Call ``fn(event)`` for every new collision (also appended to :attr:`collisions`)."""
        self._collision_listeners.append(fn)

    # ------------------------------------------------------------------ stepping

    def advance(self, seconds: float) -> None:
        """Step for ``seconds`` of simulated time (rounded to whole steps)."""
        if seconds < 0:
            raise ValueError(f"cannot advance by a negative time ({seconds} s)")
        self.step(round(seconds / self.dt))

    def step(self, n: int = 1) -> None:
        """Advance ``n`` steps of ``dt``."""
        for _ in range(n):
            self._step_once()

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
        _, of1, of2, of3, _, _, oi1, oi2, _, _ = kernels.sim_offsets.py_func(si)
        self._contact_out = sf[of1:of2].reshape(-1, 6)
        self._contact_speed = sf[of2:of3]
        self._new_contact = si[oi1:oi2]
        if self.gyro is not None:
            self.gyro.state = gyro_state
        self.tracking.state = tracking_state
        self._sensors = self._sensor_arrays()

    def _step_once(self) -> None:
        now_us = self.clock.ticks_us()
        n_extra = self._extra_forces(now_us) if self._pushes or any(self._applied) else 0
        physics = self._packed
        if physics is not None:
            status = jit.active.robot_step(
                physics.buffer, self._step_ids, physics.m, self._n_surfaces, *self._world_packed, self._sf, self._si,
                self._extra, n_extra, *self._sensors, now_us, self.dt,
            )  # fmt: skip
        else:
            status = self._step_other(now_us, n_extra)
        self._finish_step(status, now_us)

    def _finish_step(self, status: int, now_us: int) -> None:
        """What follows the compiled step of the step that began at ``now_us`` (its ``status`` bits;
        a fleet's :func:`~omnibot.sim.kernels.fleet_step` too): the collision events, the clock, the
        sensors' normal draws, the scanner and the listeners."""
        if status & layout.STEP_BAD_SURFACE:
            raise SimulationError(f"surface_ids must index the {self._n_surfaces} surfaces of this Physics")
        if self._packed is not None:
            self._packed.count_step()
        if status & layout.STEP_COLLISION:
            self._collisions_found()
        self.clock.advance_us(self._dt_us)
        if status & layout.STEP_REFILL:
            self.tracking.refill()
            if self.gyro is not None:
                self.gyro.refill(self.dt)
            self._sensors = self._sensor_arrays()
        if self._scan_self and now_us + self._dt_us >= self._scan_next_us:
            self._scan_tick(now_us + self._dt_us)
        if self._listeners and now_us + self._dt_us >= self._next_notify_us:
            self._notify()

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
        return status | jit.active.robot_after(state, self.dt, *self._sensors)

    def _extra_forces(self, now_us: int) -> int:
        """Put the applied force and the hand pushes still acting into the extra-force rows; their count."""
        rows: list[Sequence[float]] = []
        if any(self._applied):
            rows.append(self._applied)
            self._applied = [0.0, 0.0, 0.0]
        if self._pushes:
            self._pushes = [p for p in self._pushes if p[0] > now_us]
            rows += [p[1:] for p in self._pushes]
        if len(rows) > len(self._extra):
            self._extra = np.zeros((2 * len(rows), 3))
        if rows:
            self._extra[: len(rows)] = rows
        return len(rows)

    def _collisions_found(self) -> None:
        """Collision events for the contacts the last step's test flagged as new (in row order)."""
        count = int(self._si[layout.I_COUNT])
        rows = self._contact_out[:count]
        sf = self._sf
        pose = Pose2D(float(sf[layout.F_AT_X]), float(sf[layout.F_AT_Y]), float(sf[layout.F_AT_TH]))
        for a, contact in enumerate(self.world.contact_list(rows)):
            if self._new_contact[a]:
                self._collide(contact, float(self._contact_speed[a]), pose)

    def _notify(self) -> None:
        now = self.clock.ticks_us()
        snap: Snapshot | None = None
        for slot in self._listeners:
            if now >= slot.next_us:
                snap = snap or self.snapshot()
                if slot.period_us:
                    slot.next_us = (now // slot.period_us + 1) * slot.period_us
                slot.fn(snap)
        self._next_notify_us = min((slot.next_us for slot in self._listeners), default=0)

    def _find_contacts(self, x: float, y: float, th: float) -> int:
        """Test the outline at (x, y, th) against the world; returns the owner id of the first contact or -1.

        Fills the contact rows and the broad-phase clearance (as the compiled step does).
        """
        count, clearance = self.world.contacts_at(self._outline, x, y, th, self._contact_out)
        sf = self._sf
        sf[layout.F_CLEAR_X], sf[layout.F_CLEAR_Y], sf[layout.F_CLEAR] = x, y, clearance
        self._si[layout.I_COUNT] = count
        return int(self._contact_out[0, 5]) if count else -1

    def touch(self, contact: Contact, speed: float) -> None:
        """A contact with something outside the world (a fleet's other robot) at this step: a
        :class:`CollisionEvent` when the robot starts touching ``contact.owner``, as for walls."""
        if not self._still_touching(contact.owner, self.clock.ticks_us()):
            self._collide(contact, speed)

    def _still_touching(self, owner: str, now_us: int) -> bool:
        last = self._touching.get(owner)
        self._touching[owner] = now_us
        return last is not None and now_us - last <= CONTACT_RELEASE * 1e6

    def _collide(self, contact: Contact, speed: float, pose: Pose2D | None = None) -> None:
        event = CollisionEvent(
            self.time,
            contact.point[0],
            contact.point[1],
            contact.normal,
            contact.depth,
            speed,
            contact.owner,
            self.pose if pose is None else pose,
        )
        self.collisions.append(event)
        for fn in self._collision_listeners:
            fn(event)
