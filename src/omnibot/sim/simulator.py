"""One simulated robot: physics, sensors and a world behind a small facade, on a simulated clock.

::

    set_pwm(...) -> step()/advance() ----------------------------------------------> clock += dt
                      |  surface ids under each wheel   <- World.surface_ids (every step)
                      |  wall/obstacle push-back force  <- World.contacts    (every step)
                      |  hand pushes (push())
                      v
                   Physics.step(pwm, surface_ids, external_force)
                      v
      encoders, tracking wheels, gyro (every step) ; sonars (on ping) ; listeners ; collision events

Collisions use a penalty force: each contact pushes along its normal with a spring-damper whose
stiffness is set from the simulation step (natural frequency 0.25/dt for the effective mass at the
contact point, critically damped), so the response is stiff yet stable for any robot mass, plus a
little wall friction. The robot sinks at most millimetres into a wall. A collision event is
reported when the robot starts touching a wall or obstacle (after 0.25 s without touching it,
so one bump that bounces is one event).

Listeners get a :class:`Snapshot` once when added and then after every step, or every ``period``
seconds; :class:`TruthRecorder` is such a listener writing ``t,x,y,theta`` CSV.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.errors import SimulationError
from omnibot.robot.description import RobotDescription
from omnibot.robot.kinematics import Twist
from omnibot.sim.clock import SimClock
from omnibot.sim.sensors import Gyro, MotorEncoders, Sonar, TrackingWheels
from omnibot.sim.world import Contact, Pose, World, convex_hull, load_world

FloatArray = NDArray[np.float64]

CONTACT_OMEGA_DT = 0.25
"""Contact spring natural frequency times dt (well inside the explicit-integration limit of 2)."""
CONTACT_DAMPING = 1.0
WALL_FRICTION = 0.2
CONTACT_RELEASE = 0.25
"""Seconds without touching after which touching the same wall again is a new collision event."""

# fixed RNG stream keys, so that adding one sensor does not change another's noise
_RNG_ENCODERS, _RNG_TRACKING, _RNG_GYRO, _RNG_SONAR = 0, 1, 2, 100


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

    def reset(self, pose: ArrayLike | None = None) -> None: ...

    def step(
        self, pwm: ArrayLike, surface_ids: ArrayLike | None = None, external_force: ArrayLike | None = None
    ) -> None: ...

    def contact_points_world(self) -> FloatArray: ...


PhysicsFactory = Callable[..., PhysicsLike]
"""Called as ``factory(robot, n=1, surfaces=names, dt=dt, seed=seed)``."""


@dataclass(frozen=True, slots=True)
class Snapshot:
    """Ground truth at one instant: time (s), world pose (m, m, rad, continuous), body twist."""

    t: float
    x: float
    y: float
    theta: float
    vx: float
    vy: float
    w: float

    @property
    def pose(self) -> Pose:
        return Pose(self.x, self.y, self.theta)

    @property
    def twist(self) -> Twist:
        return Twist(self.vx, self.vy, self.w)


@dataclass(frozen=True, slots=True)
class CollisionEvent:
    """The robot started touching a wall or obstacle.

    ``x, y`` is the contact point (world, m), ``normal`` the direction the wall pushes the robot,
    ``speed`` the approach speed of the contact point along it (m/s), ``owner`` the world item.
    """

    time: float
    x: float
    y: float
    normal: tuple[float, float]
    depth: float
    speed: float
    owner: str
    pose: Pose


Listener = Callable[[Snapshot], None]
CollisionListener = Callable[[CollisionEvent], None]


class TruthRecorder:
    """A listener writing ground truth as CSV ``t,x,y,theta`` (s, m, m, rad; theta not wrapped).

    Writes one row per ``period`` seconds of simulated time (on the grid 0, period, 2 period...),
    whatever rate it is called at, and flushes the stream every ``flush_every`` simulated seconds
    (so a reader following the file in real time lags at most that much). Give it a path (opened and
    closed by the recorder) or an open text stream (left open).
    """

    def __init__(self, file: str | Path | IO[str], period: float = 0.01, flush_every: float = 0.1) -> None:
        if period <= 0:
            raise ValueError(f"period must be > 0, got {period}")
        self.period = period
        self.flush_every = flush_every
        self._next_flush = flush_every
        if isinstance(file, str | Path):
            self._stream: IO[str] = open(file, "w", encoding="utf-8", newline="")  # noqa: SIM115
            self._owned = True
        else:
            self._stream, self._owned = file, False
        self._stream.write("t,x,y,theta\n")
        self._next = 0
        self.rows = 0
        self.closed = False

    def __call__(self, snap: Snapshot) -> None:
        """Write a row if a new period has begun (does nothing once closed)."""
        k = math.floor(snap.t / self.period + 1e-6)
        if k < self._next or self.closed:
            return
        self._next = k + 1
        self._stream.write(f"{snap.t:.6f},{snap.x:.6f},{snap.y:.6f},{snap.theta:.6f}\n")
        self.rows += 1
        if snap.t >= self._next_flush:
            self._stream.flush()
            self._next_flush = snap.t + self.flush_every

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        if self._owned:
            self._stream.close()
        else:
            self._stream.flush()

    def __enter__(self) -> TruthRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


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
    ``physics_factory`` replaces :class:`~omnibot.sim.physics.Physics` (tests use a stand-in).
    """

    def __init__(
        self,
        robot: RobotDescription,
        *,
        surface: str | None = None,
        world: World | str | Path | None = None,
        seed: int = 0,
        dt: float = 0.001,
        start_pose: Sequence[float] | None = None,
        truth_recorder: TruthRecorder | None = None,
        physics_factory: PhysicsFactory | None = None,
    ) -> None:
        self.robot = robot
        self.seed = seed
        dt_us = round(dt * 1e6)
        if dt_us <= 0 or abs(dt_us - dt * 1e6) > 1e-6:
            raise SimulationError(f"dt must be a positive whole number of microseconds, got {dt} s")
        self._dt_us = dt_us
        self.dt = dt_us / 1e6
        self.clock = SimClock()

        w = load_world("empty") if world is None else world if isinstance(world, World) else load_world(world)
        self.world = w.with_floor(surface) if surface is not None and surface != w.floor else w

        factory = physics_factory or _default_physics
        self._physics = factory(robot, n=1, surfaces=self.world.surface_names, dt=self.dt, seed=seed)
        known = [s.name for s in self._physics.surfaces]
        missing = [s for s in self.world.surface_names if s not in known]
        if missing:
            raise SimulationError(f"world '{self.world.name}' uses surfaces the physics lacks: {missing}")
        self._surface_map = np.array([known.index(s) for s in self.world.surface_names], dtype=np.int64)
        self._floor_ids = np.full((1, robot.n_wheels), self._surface_map[0], dtype=np.int64)

        start = start_pose if start_pose is not None else self.world.start or (0.0, 0.0, 0.0)
        if len(start) != 3:
            raise SimulationError(f"start_pose is (x, y, theta), got {tuple(start)}")
        self._physics.reset(pose=np.array([start], dtype=float))

        self._pwm = np.zeros(robot.n_wheels, dtype=np.int64)
        self._pwm_max = np.array([wh.motor.pwm_max for wh in robot.wheels], dtype=np.int64)
        self._outline = convex_hull(robot.footprint.outline())
        self._pushes: list[tuple[int, float, float, float]] = []
        self._touching: dict[str, int] = {}
        self.contacts: list[Contact] = []
        """Contacts found at the start of the last step."""
        self.collisions: list[CollisionEvent] = []
        self._collision_listeners: list[CollisionListener] = []
        self._listeners: list[_ListenerSlot] = []

        names = [wh.name for wh in robot.wheels]
        self._enc_index = np.array([names.index(e.wheel) for e in robot.encoders.motors], dtype=np.int64)
        self.encoders = MotorEncoders(
            [e.counts_per_rev for e in robot.encoders.motors],
            _rng(seed, _RNG_ENCODERS),
            initial_angles=self._physics.wheel_angle[0, self._enc_index],
        )
        self.tracking = TrackingWheels(robot.encoders.tracking, _rng(seed, _RNG_TRACKING))
        self.gyro = Gyro(robot.gyro, _rng(seed, _RNG_GYRO)) if robot.gyro is not None else None
        self.sonars = [Sonar(s, _rng(seed, _RNG_SONAR + i)) for i, s in enumerate(robot.sonars)]

        touching = self._find_contacts()
        if touching:
            raise SimulationError(
                f"start pose {tuple(float(c) for c in start)} overlaps {touching[0].owner} of world "
                f"'{self.world.name}'"
            )
        if truth_recorder is not None:
            self.add_listener(truth_recorder, period=truth_recorder.period)

    # ------------------------------------------------------------------ state

    @property
    def physics(self) -> PhysicsLike:
        return self._physics

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self.clock.now()

    @property
    def pose(self) -> Pose:
        """True world pose (x, y in m, theta in rad, continuous: not wrapped)."""
        x, y, th = (float(c) for c in self._physics.pose[0])
        return Pose(x, y, th)

    @property
    def twist(self) -> Twist:
        """True body-frame velocity (vx, vy in m/s, w in rad/s)."""
        vx, vy, w = (float(c) for c in self._physics.twist[0])
        return Twist(vx, vy, w)

    @property
    def wheel_speeds(self) -> list[float]:
        """True wheel speeds, rad/s, in robot.wheels order."""
        return [float(v) for v in self._physics.wheel_speed[0]]

    @property
    def pwm(self) -> list[int]:
        return [int(v) for v in self._pwm]

    @property
    def battery_voltage(self) -> float:
        """Battery terminal voltage: nominal minus the internal-resistance drop of the drive current."""
        own = getattr(self._physics, "battery_voltage", None)
        if own is not None:
            return float(np.asarray(own, dtype=float).reshape(-1)[0])
        duty = np.abs(self._pwm) / self._pwm_max
        current = float(np.sum(np.abs(self._physics.motor_current[0]) * duty))
        bat = self.robot.battery
        return max(0.0, bat.voltage - bat.internal_resistance * current)

    def snapshot(self) -> Snapshot:
        x, y, th = (float(c) for c in self._physics.pose[0])
        vx, vy, w = (float(c) for c in self._physics.twist[0])
        return Snapshot(self.time, x, y, th, vx, vy, w)

    # ------------------------------------------------------------------ commands

    def set_pwm(self, values: Sequence[int]) -> None:
        """Signed PWM counts, one per wheel (robot.wheels order). Out of range raises, never clamps."""
        vals = list(values)
        names = [w.name for w in self.robot.wheels]
        if len(vals) != len(names):
            raise PwmRangeError(f"set_pwm needs {len(names)} values ({', '.join(names)}), got {len(vals)}")
        out = np.zeros(len(vals), dtype=np.int64)
        for i, v in enumerate(vals):
            if isinstance(v, bool) or not isinstance(v, int | np.integer | float) or int(v) != v:
                raise PwmRangeError(f"PWM for wheel '{names[i]}' must be a whole number of counts, got {v!r}")
            if abs(int(v)) > self._pwm_max[i]:
                raise PwmRangeError(
                    f"PWM {int(v)} for wheel '{names[i]}' is outside +-{self._pwm_max[i]} "
                    "(the firmware must clamp)"
                )
            out[i] = int(v)
        self._pwm = out

    def lift_wheel(self, name: str, lifted: bool = True) -> None:
        """Fault injection: lift a wheel off the floor (it spins freely and drives nothing)."""
        index = [w.name for w in self.robot.wheels].index(self.robot.wheel(name).name)
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
            self._pwm = np.zeros_like(self._pwm)
        end = self.clock.ticks_us() + round(duration * 1e6)
        self._pushes.append((end, float(force_xy[0]), float(force_xy[1]), float(torque)))

    # ------------------------------------------------------------------ sensors

    def encoder_counts(self) -> list[int]:
        """Motor encoder counts in robot.encoders.motors order."""
        return [int(c) for c in self.encoders.counts]

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
        return self.sonars[index].ping(self.time, self._physics.pose[0], self.world)

    # ------------------------------------------------------------------ listeners

    def add_listener(self, fn: Listener, period: float | None = None) -> None:
        """Call ``fn(snapshot)`` now, then after every step (period None) or every ``period`` s."""
        period_us = 0 if period is None else max(1, round(period * 1e6))
        now = self.clock.ticks_us()
        self._listeners.append(_ListenerSlot(fn, period_us, now + period_us))
        fn(self.snapshot())

    def remove_listener(self, fn: Listener) -> None:
        self._listeners = [s for s in self._listeners if s.fn != fn]

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

    def _step_once(self) -> None:
        ph = self._physics
        twist0 = np.array(ph.twist[0], dtype=float)
        now_us = self.clock.ticks_us()
        ids = self._surface_ids()
        force = self._contact_force(now_us, twist0)
        self._pushes = [p for p in self._pushes if p[0] > now_us]
        for _, fx, fy, tz in self._pushes:
            force += (fx, fy, tz)
        ph.step(self._pwm[None, :], ids, force[None, :] if np.any(force) else None)
        self.clock.advance_us(self._dt_us)

        mean_twist = 0.5 * (twist0 + np.asarray(ph.twist[0], dtype=float))
        self.encoders.update(ph.wheel_angle[0, self._enc_index])
        self.tracking.update(mean_twist, self.dt)
        if self.gyro is not None:
            self.gyro.update(self.dt, float(mean_twist[2]))
        if self._listeners:
            self._notify()

    def _surface_ids(self) -> NDArray[np.int64]:
        if len(self.world.surface_names) == 1:
            return self._floor_ids
        local = self.world.surface_ids(self._physics.contact_points_world()[0])
        return self._surface_map[local][None, :]

    def _notify(self) -> None:
        now = self.clock.ticks_us()
        snap: Snapshot | None = None
        for slot in self._listeners:
            if now >= slot.next_us:
                snap = snap or self.snapshot()
                if slot.period_us:
                    slot.next_us = (now // slot.period_us + 1) * slot.period_us
                slot.fn(snap)

    def _find_contacts(self) -> list[Contact]:
        if len(self.world.segments) == 0:
            return []
        x, y, th = (float(c) for c in self._physics.pose[0])
        c, s = math.cos(th), math.sin(th)
        outline = self._outline @ np.array([[c, s], [-s, c]]) + (x, y)
        return self.world.contacts(outline)

    def _contact_force(self, now_us: int, twist: FloatArray) -> FloatArray:
        """Penalty force (world Fx, Fy, torque) of every contact; records collision events."""
        self.contacts = self._find_contacts()
        force = np.zeros(3)
        if not self.contacts:
            return force
        x, y, th = (float(c) for c in self._physics.pose[0])
        c, s = math.cos(th), math.sin(th)
        vx, vy, w = (float(v) for v in twist)
        vwx, vwy = c * vx - s * vy, s * vx + c * vy
        m, inertia = self.robot.mass, self.robot.yaw_inertia
        omega = CONTACT_OMEGA_DT / self.dt
        for contact in self.contacts:
            rx, ry = contact.point[0] - x, contact.point[1] - y
            nx, ny = contact.normal
            px, py = vwx - w * ry, vwy + w * rx
            vn, vt = px * nx + py * ny, -px * ny + py * nx
            rn = rx * ny - ry * nx
            m_eff = 1.0 / (1.0 / m + rn * rn / inertia)
            fn = max(0.0, m_eff * omega * omega * contact.depth - 2 * CONTACT_DAMPING * m_eff * omega * vn)
            ft = -WALL_FRICTION * fn * math.tanh(vt / 0.05)
            fx, fy = fn * nx - ft * ny, fn * ny + ft * nx
            force += (fx, fy, rx * fy - ry * fx)
            self._touch(now_us, contact, -vn)
        return force

    def _touch(self, now_us: int, contact: Contact, speed: float) -> None:
        last = self._touching.get(contact.owner)
        self._touching[contact.owner] = now_us
        if last is not None and now_us - last <= CONTACT_RELEASE * 1e6:
            return
        event = CollisionEvent(
            self.time,
            contact.point[0],
            contact.point[1],
            contact.normal,
            contact.depth,
            speed,
            contact.owner,
            self.pose,
        )
        self.collisions.append(event)
        for fn in self._collision_listeners:
            fn(event)
