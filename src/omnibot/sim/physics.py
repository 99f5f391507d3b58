"""Planar rigid-body physics of N omni/mecanum robots at once, driven by DC motors through wheel contacts.

State per robot (n robots, m wheels each; arrays are updated in place, so references stay valid)::

    pose (n,3)        world x, y (m), theta (rad, continuous: never wrapped)
    twist (n,3)       body-frame vx, vy (m/s), w (rad/s)
    wheel_angle (n,m) rad (continuous), wheel_speed (n,m) rad/s

Wheel i sits at p_i (body frame), a positive wheel speed carries the robot along u_i (drive angle),
its rollers constrain the direction t_i = u_i turned by gamma_i and roll freely along n_i = t_i turned
by +90 degrees. With v_c = v + w x p_i the body velocity at the contact point::

    slip along t_i      s_i = v_c . t_i - r omega_i cos(gamma_i)
    roller rolling      q_i = v_c . n_i + r omega_i sin(gamma_i)
    floor force         F_i = -g mu N_i tanh(s_i / v_eps) t_i  -  c_i(phi_i) N_i tanh(q_i / q_eps) n_i
    roller resistance   c_i(phi) = c0_i k_surf (1 + f_i (1 - cos(count_i phi)) / 2)   (f = 1: up to 2x)
    wheel reaction      tau_floor = -r (F_i . u_i) = -r cos(gamma) F_t + r sin(gamma) F_n
    combined drag       b_i N_i sin(2 beta_i) on both rolling directions: -b N sin(2 beta) q_i along n_i,
                        and the torque -r^2 b N sin(2 beta) omega_i at the axle, where
                        sin(2 beta) = 2 |r omega| |q| / ((r omega)^2 + q^2)

with g = RollerSpec.grip (the roller material's friction relative to soft rubber), c0 its
rolling_resistance, f its friction_variation, phi the wheel angle (0 = least friction), and mu,
v_eps, k_surf from the :class:`~omnibot.floor.surfaces.Surface` under the wheel. For a plain omni
wheel (gamma = 0) the reaction is -r F_t; the sin term keeps the mecanum model energy-consistent:
the floor forces only ever dissipate (power F_t s + F_n q <= 0). The combined drag (b =
RollerSpec.combined_drag, per unit load and m/s) is the rollers' extra loss while the wheel drives
and its rollers roll at once (the contact crosses the roller diagonally, at angle beta from the
wheel's rolling direction): zero on a wheel that stands still or whose rollers do not turn, largest
at 45 degrees; it is a linear damping with its weight taken at the step's start, so it stays
implicit and dissipative. Sizes and sources of every effect: docs/simulator.md.

Motor and driver (one per wheel), with d = clip(pwm / pwm_max, -1, 1)::

    driver on           |pwm| >= deadband and pwm != 0; off: terminals open, the motor coasts (i = 0)
    battery             V_bus -> V_oc - R_batt * sum(d_i i_i)  (previous step's current; V_bus moves
                        there by 1/(1 + R_batt sum 1/R_i) per step: a few-ms lag, stable for any battery)
    state of charge     q -= I_batt dt / (3600 capacity_ah), V_oc = cells * curve(q) (robot/battery.py),
                        for a battery given a ``charge``; without one V_oc stays the nominal voltage
    motor voltage       V_m = d (V_bus - V_drop)               (averaged PWM)
    current             i = clip((V_m - k G omega) / R, -I_max, I_max)
    wheel torque        tau = eta G k i - tau_c tanh(omega / omega_eps) - b omega + tau_floor
    wheel inertia       J = J_wheel + G^2 J_rotor

The electrical time constant L/R (1 ms or less for these motors, far below the mechanical one) is
neglected: the current follows the voltage at once. Gear losses are a constant efficiency eta on
the motor torque. Normal loads are static: the least-norm solution of sum N_i = m g,
sum N_i p_i = 0 (centre of mass at the body origin) over the wheels that touch the floor (``lifted``
wheels carry nothing), negative loads clipped. A rigid four-wheel robot with one wheel lifted thus
rests on the diagonal pair through its centre and the wheel opposite the lifted one carries nothing.

Integration (fixed dt, default 1 ms). The generalised velocity q = (vx, vy, w, omega_1..omega_m)
obeys M dq/dt = H^T f(Hq) + tau_motor, where the rows of H give the 3m "contact speeds" (slip s_i,
roller speed q_i, axle speed omega_i) and f the regularised friction laws above. Each step solves
the linearised backward-Euler system::

    (M/dt + H^T K H + D_motor) dq = H^T f + tau_motor,     K = diag(F_max tanh(x) / x)

K holds the secant slopes of the friction laws (x: contact speed over its regularisation speed),
not the tangents: every friction term becomes implicit in the form f_new = -k x_new, which on its
own can stop a contact within a step but never reverse it, and all together only remove energy;
the stiff regularisation stays stable at 1 kHz however hard a wheel slips. The back-EMF damping
(D_motor, dropped while the current is limited) is implicit too. The body-frame (Coriolis) term
is then applied as the exact rotation of (vx, vy) by -w dt and the pose advanced with the new twist
at the mid-step heading. No randomness, no wall clock: a run is deterministic, and a batch of n
equals n single runs.

Implementation: this class holds parameters and state in numpy arrays; one compiled kernel,
:func:`omnibot.sim.kernels.physics_step`, advances them in place (the matrix above has an arrow
structure, a dense body block and a diagonal wheel block, so the kernel eliminates the wheels and
solves a 3x3 system: O(m) per robot, about a microsecond per step for one robot). Its state,
inputs and parameters are views of one buffer (:attr:`Physics.buffer`), so the simulator's compiled
step of one robot takes them as one argument. :meth:`Physics.run` is the batch API: many steps of
many independent robots in one call, the robots shared out among all cores (numba's threads);
with ``exact=False`` the robots are stepped side by side in vector lanes (:mod:`omnibot.sim.kernels.lanes`:
faster, within a stated tolerance of the exact step rather than bit for bit).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.errors import SimulationError
from omnibot.floor import Surface, get_surface, static_loads
from omnibot.robot import RobotDescription
from omnibot.sim import jit, kernels
from omnibot.sim.kernels import layout
from omnibot.sim.physics_charge import BatteryCharge
from omnibot.sim.physics_parameters import parameters
from omnibot.sim.physics_state import StateArrays

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


class Physics(StateArrays):
    """N robots (identical, or each with its own description) on a floor, advanced by fixed steps.

    ``robot`` is one :class:`RobotDescription` (all ``n`` robots alike, n default 1) or a sequence of
    descriptions, one per robot, so Monte-Carlo runs can give each robot slightly different true
    parameters (all with the same wheel count; ``n`` then defaults to, and must equal, its length).
    ``surfaces`` lists the floor materials (names or :class:`Surface`); :meth:`step` takes per-wheel
    indices into it, and index 0 is the floor everywhere when it is given none.

    ``lifted`` is a read-only (n,m) mask: assign a new mask to lift wheels off the floor (their load
    goes to the others). Other state arrays may be written in place (e.g. ``twist[0, 0] = 0.5``);
    assigning to a state attribute also writes in place, so references stay valid.
    """

    def __init__(
        self,
        robot: RobotDescription | Sequence[RobotDescription],
        n: int | None = None,
        surfaces: Sequence[str | Surface] = ("wood",),
        dt: float = 0.001,
    ) -> None:
        robots = [robot] if isinstance(robot, RobotDescription) else list(robot)
        if not robots:
            raise SimulationError("Physics needs at least one robot description")
        if n is None:
            n = len(robots)
        if len(robots) == 1:
            robots = robots * n
        if n < 1 or len(robots) != n:
            raise SimulationError(f"got {len(robots)} robot descriptions for n={n} robots")
        m = robots[0].n_wheels
        if any(r.n_wheels != m for r in robots):
            raise SimulationError("all robots in one Physics must have the same number of wheels")
        if not dt > 0:
            raise SimulationError(f"dt must be positive, got {dt}")
        if not surfaces:
            raise SimulationError("give at least one surface")
        self.robots: tuple[RobotDescription, ...] = tuple(robots)
        self.n, self.m, self.dt = n, m, float(dt)
        self.surfaces: tuple[Surface, ...] = tuple(get_surface(s) for s in surfaces)

        # state, inputs and parameters are views of one buffer, so a compiled step of the whole
        # simulator takes them as one argument (kernels.physics_views)
        self._bind(np.zeros(kernels.physics_offsets.py_func(n, m, len(self.surfaces))[-1]))
        # self._battery: bus voltage, battery current of the last step
        tables = parameters(self.robots, self.surfaces, self.dt)
        self._wp[:], self._rp[:], self._surf[:] = tables.wheels, tables.robots, tables.surfaces
        self._x, self._y, self._mass = tables.x, tables.y, tables.mass
        self._grip, self._scrub = tables.grip, tables.scrub
        self._v_open[:] = [r.battery.voltage for r in self.robots]
        self._charge = BatteryCharge(self.robots)
        self._charge.set_open_voltage(self._v_open)
        self._battery[:, 0] = self._v_open
        # input buffers: the kernel always gets C-contiguous float64 / int64 arrays (one compilation)
        self._ids = np.zeros((n, m), dtype=np.int64)
        self._floor = np.zeros((n, m), dtype=np.int64)
        self._steps = 0
        self._lifted = np.zeros((n, m), dtype=bool)
        self._set_loads()

    def _bind(self, buffer: FloatArray) -> None:
        """Make ``buffer`` the packed buffer and the state arrays its views."""
        self._buffer = buffer
        (
            self._pose, self._q, self._wheel_angle, self._current, self._traction, self._battery,
            self._v_open, self._pwm, self._ext, self._wp, self._rp, self._surf,
        ) = self._views()  # fmt: skip

    def _views(self) -> tuple[FloatArray, ...]:
        """Numpy views of the packed buffer, in :func:`~omnibot.sim.kernels.physics_offsets` order."""
        o = kernels.physics_offsets.py_func(self.n, self.m, len(self.surfaces))
        shapes = [
            (self.n, 3), (self.n, 3 + self.m), (self.n, self.m), (self.n, self.m), (self.n, self.m), (self.n, 2),
            (self.n,), (self.n, self.m), (self.n, 3), (self.n, self.m, layout.W_COLUMNS),
            (self.n, layout.R_COLUMNS), (len(self.surfaces), layout.S_COLUMNS),
        ]  # fmt: skip
        return tuple(self._buffer[o[k] : o[k + 1]].reshape(shape) for k, shape in enumerate(shapes))

    @property
    def pwm(self) -> FloatArray:
        """(n,m) PWM counts of the next step (what :meth:`step` copies its ``pwm`` into); writable in place."""
        return self._pwm

    @property
    def buffer(self) -> FloatArray:
        """The packed state, inputs and parameters (:func:`~omnibot.sim.kernels.physics_views`)."""
        return self._buffer

    def rehome(self, buffer: FloatArray) -> None:
        """Move the packed state, inputs and parameters into ``buffer`` (1-D float64 of
        :attr:`buffer`'s size, e.g. a view of a fleet's buffer) and keep them there: the views this
        object hands out from now on are of ``buffer`` (those handed out before are not)."""
        if buffer.shape != self._buffer.shape or buffer.dtype != np.float64:
            raise SimulationError(
                f"a physics buffer is {self._buffer.shape} float64, got {buffer.shape} {buffer.dtype}"
            )
        buffer[...] = self._buffer
        self._bind(buffer)

    def count_step(self) -> None:
        """Account for a step the compiled simulator step made on :attr:`buffer` (time, battery charge)."""
        self._steps += 1  # _stepped(0, 1), a call less: once a robot a step
        if self._charge.draining:  # _drain's test, a call less while no battery drains
            self._drain()

    def _drain(self) -> None:
        """Run the draining batteries down by the last step's current."""
        if self._charge.draining:
            self._charge.drain(self._battery[:, 1], self.dt, self._v_open)

    def _set_loads(self) -> None:
        self._load = static_loads(self._x, self._y, self._mass, self._lifted)
        self._load.flags.writeable = False
        self._wp[..., layout.W_LOAD] = self._load
        self._wp[..., layout.W_GRIP_LOAD] = self._grip * self._load
        self._wp[..., layout.W_SCRUB_LOAD] = self._scrub * self._load

    # ------------------------------------------------------------------ state access (and StateArrays')

    @property
    def battery_charge(self) -> FloatArray:
        """(n,) state of charge, 0..1 (stays 1 for a battery without ``charge``: never runs down)."""
        return self._charge.charge.copy()

    @battery_charge.setter
    def battery_charge(self, value: ArrayLike) -> None:
        self._charge.set(value, self._v_open)

    @property
    def time(self) -> float:
        """Simulated time since the last reset, s (step count times dt: no drift)."""
        return self._steps * self.dt

    @property
    def lifted(self) -> BoolArray:
        """(n,m) mask of wheels off the floor (read-only view; assign a new mask to change it)."""
        view = self._lifted.view()
        view.flags.writeable = False
        return view

    @lifted.setter
    def lifted(self, mask: ArrayLike) -> None:
        self._lifted = np.broadcast_to(np.asarray(mask, dtype=bool), (self.n, self.m)).copy()
        self._set_loads()

    @property
    def normal_load(self) -> FloatArray:
        """(n,m) static normal load on each wheel, N (read-only)."""
        return self._load

    @property
    def battery_voltage(self) -> FloatArray:
        """(n,) battery terminal voltage at the last step, V."""
        return self._battery[:, 0].copy()

    def _contact_speeds(self) -> FloatArray:
        out = np.empty((self.n, self.m, 2))
        jit.active.contact_speeds(self._q, self._wp, out)
        return out

    @property
    def slip(self) -> FloatArray:
        """(n,m) slip speed along each wheel's traction direction, m/s (contact velocity minus rim)."""
        return self._contact_speeds()[:, :, 0].copy()

    @property
    def roller_speed(self) -> FloatArray:
        """(n,m) speed of the floor under each wheel along its free roller direction, m/s."""
        return self._contact_speeds()[:, :, 1].copy()

    def velocity_world(self) -> FloatArray:
        """(n,3) world-frame velocity: vx, vy (m/s), w (rad/s)."""
        c, s = np.cos(self._pose[:, 2]), np.sin(self._pose[:, 2])
        vx, vy = self._q[:, 0], self._q[:, 1]
        return np.stack([c * vx - s * vy, s * vx + c * vy, self._q[:, 2]], axis=1)

    def contact_points_world(self) -> FloatArray:
        """(n,m,2) world positions of the wheel contact points, m."""
        c, s = np.cos(self._pose[:, 2:3]), np.sin(self._pose[:, 2:3])
        out = np.empty((self.n, self.m, 2))
        out[:, :, 0] = self._pose[:, 0:1] + c * self._x - s * self._y
        out[:, :, 1] = self._pose[:, 1:2] + s * self._x + c * self._y
        return out

    def reset(self, pose: ArrayLike | None = None, wheel_angle: ArrayLike | None = None) -> None:
        """Put every robot at rest at ``pose`` ((3,) or (n,3), default the origin), time 0.

        ``wheel_angle`` ((m,) or (n,m), default 0) sets where each wheel's roller friction cycle
        starts: angle 0 is the low-friction position seed 000 set its wheels to before measuring.
        """
        self._pose[:] = 0.0 if pose is None else np.broadcast_to(np.asarray(pose, dtype=float), (self.n, 3))
        self._wheel_angle[:] = (
            0.0 if wheel_angle is None else np.broadcast_to(np.asarray(wheel_angle, float), (self.n, self.m))
        )
        self._q[:] = 0.0
        self._current[:] = 0.0
        self._traction[:] = 0.0
        self._battery[:, 0] = self._v_open
        self._battery[:, 1] = 0.0
        self._steps = 0

    # ------------------------------------------------------------------ dynamics

    def _inputs(
        self, pwm: ArrayLike, surface_ids: ArrayLike | None, external_force: ArrayLike | None
    ) -> NDArray[np.int64]:
        """Copy a step's inputs into the input arrays; the surface ids to step with."""
        self._pwm[...] = pwm
        if external_force is not None:
            self._ext[...] = external_force
        if surface_ids is None:
            return self._floor
        self._ids[...] = surface_ids
        return self._ids

    def step(
        self,
        pwm: ArrayLike,
        surface_ids: ArrayLike | None = None,
        external_force: ArrayLike | None = None,
    ) -> None:
        """Advance all robots by dt.

        ``pwm``: (n,m) signed PWM counts (broadcastable); ``surface_ids``: (n,m) indices into
        ``surfaces`` for the floor under each wheel (default 0); ``external_force``: (n,3) world
        Fx, Fy (N) and torque about the body origin (N m), e.g. from collisions or a push by hand.
        """
        ids = self._inputs(pwm, surface_ids, external_force)
        failed = jit.active.physics_step(
            self._pose,
            self._q,
            self._wheel_angle,
            self._current,
            self._traction,
            self._battery,
            self._v_open,
            self._pwm,
            ids,
            self._ext,
            external_force is not None,
            self._wp,
            self._rp,
            self._surf,
            self.dt,
        )
        self._stepped(failed, 1)

    def run(
        self,
        pwm: ArrayLike,
        steps: int = 1,
        surface_ids: ArrayLike | None = None,
        external_force: ArrayLike | None = None,
        exact: bool = True,
    ) -> None:
        """Advance all robots ``steps`` steps with the same inputs, on every core: the batch API.

        ``exact`` (default): the same as ``steps`` calls of :meth:`step`, bit for bit (each robot's
        arithmetic is the same, only shared out among numba's threads, each robot stepped ``steps``
        times in a row by one thread; ``numba.set_num_threads`` chooses how many). ``exact=False``:
        the robots in vector lanes with the kernel's own tanh, sin and cos
        (:func:`omnibot.sim.kernels.lanes.physics_run`), about 4 times faster (BENCHMARKS.md); not bit for
        bit: every state within 1e-12 of its largest value of the exact step's over 2 s
        (``tests/sim/kernels/test_lanes.py``; 7e-13 measured after 10 s).
        A battery with a ``charge`` is stepped one step per call so its charge follows. Each kernel
        compiles on its first call in a process (numba's threading layer; cached on disk after).
        """
        if steps < 0:
            raise SimulationError(f"steps must be >= 0, got {steps}")
        ids = self._inputs(pwm, surface_ids, external_force)
        chunks = [1] * steps if self._charge.draining else [steps] if steps else []
        if exact:
            kernel = jit.active.physics_step_parallel
        else:  # imported on first use: defining the lanes' kernels takes 40 ms that a simulator never needs
            from omnibot.sim.kernels import lanes

            kernel = lanes.physics_run
        for chunk in chunks:
            failed = kernel(
                self._buffer,
                ids,
                self.n,
                self.m,
                len(self.surfaces),
                external_force is not None,
                self.dt,
                chunk,
            )
            self._stepped(failed, chunk)

    def _stepped(self, failed: int, steps: int) -> None:
        """Account for ``steps`` steps a kernel made (time, battery charge), or raise if it failed."""
        if failed:
            raise SimulationError(f"surface_ids must index the {len(self.surfaces)} surfaces of this Physics")
        self._steps += steps
        self._drain()


__all__ = ["Physics"]
