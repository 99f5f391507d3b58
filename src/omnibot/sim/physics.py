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

with g = RollerSpec.grip (the roller material's friction relative to soft rubber), c0 its
rolling_resistance, f its friction_variation, phi the wheel angle (0 = least friction), and mu,
v_eps, k_surf from the :class:`~omnibot.sim.surfaces.Surface` under the wheel. For a plain omni
wheel (gamma = 0) the reaction is -r F_t; the sin term keeps the mecanum model energy-consistent:
the floor forces only ever dissipate (power F_t s + F_n q <= 0).

Motor and driver (one per wheel), with d = clip(pwm / pwm_max, -1, 1)::

    driver on           |pwm| >= deadband and pwm != 0; off: terminals open, the motor coasts (i = 0)
    battery             V_bus -> V_oc - R_batt * sum(d_i i_i)  (previous step's current; V_bus moves
                        there by 1/(1 + R_batt sum 1/R_i) per step: a few-ms lag, stable for any battery)
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
(D_motor, dropped while the current is limited) is implicit too. The body-frame (Coriolis) term is then applied as the exact
rotation of (vx, vy) by -w dt and the pose advanced with the new twist at the mid-step heading.
No randomness, no wall clock: a run is deterministic, and a batch of n equals n single runs.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.errors import SimulationError
from omnibot.robot.description import RobotDescription
from omnibot.sim.surfaces import Surface, get_surface

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

GRAVITY = 9.81
WHEEL_SPEED_EPS = 0.01
"""rad/s: regularisation speed of the Coulomb friction at the wheel axle."""
ROLL_SPEED_EPS = 0.005
"""m/s: regularisation speed of the roller rolling resistance."""


def static_loads(x: FloatArray, y: FloatArray, mass: FloatArray, lifted: BoolArray) -> FloatArray:
    """Static normal loads (n,m) in N: least-norm loads on the wheels in contact, none on lifted ones.

    Solves sum N = m g, sum N x = 0, sum N y = 0 over the wheels in contact (least norm when more
    than three touch), clips negative loads (the robot would tip) and rescales the rest to m g.
    """
    support = (~lifted).astype(float)
    A = np.stack([support, x * support, y * support], axis=1)
    b = np.zeros((x.shape[0], 3, 1))
    b[:, 0, 0] = mass * GRAVITY
    loads = (np.linalg.pinv(A) @ b)[:, :, 0]
    loads = np.clip(loads, 0.0, None) * support
    total = loads.sum(axis=1)
    scale = np.divide(mass * GRAVITY, total, out=np.zeros_like(total), where=total > 1e-12)
    return np.asarray(loads * scale[:, None], dtype=float)


class Physics:
    """N robots (identical, or each with its own description) on a floor, advanced by fixed steps.

    ``robot`` is one :class:`RobotDescription` (all ``n`` robots alike, n default 1) or a sequence of
    descriptions, one per robot, so Monte-Carlo runs can give each robot slightly different true
    parameters (all with the same wheel count; ``n`` then defaults to, and must equal, its length).
    ``surfaces`` lists the floor materials (names or :class:`Surface`); :meth:`step` takes per-wheel
    indices into it, and index 0 is the floor everywhere when it is given none.

    ``lifted`` is a read-only (n,m) mask: assign a new mask to lift wheels off the floor (their load
    goes to the others). Other state arrays may be written in place (e.g. ``twist[0, 0] = 0.5``).
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

        self._pose = np.zeros((n, 3))
        self._q = np.zeros((n, 3 + m))
        self.wheel_angle = np.zeros((n, m))
        self.motor_current = np.zeros((n, m))
        """(n,m) motor current at the last step, A."""
        self.traction_force = np.zeros((n, m))
        """(n,m) floor force on the robot along each wheel's traction direction at the last step, N."""
        self._init_parameters()
        self.battery_open_voltage = self._v_nominal.copy()
        """(n,) open-circuit battery voltage, V (lower it to simulate a discharged battery)."""
        self._v_bus = self.battery_open_voltage.copy()
        self._i_batt = np.zeros(n)
        self._steps = 0
        self._custom_surface = False
        self._lifted = np.zeros((n, m), dtype=bool)
        self._set_loads()

    # ------------------------------------------------------------------ parameters

    def _wheel_param(self, fn: Any) -> FloatArray:
        return np.array([[float(fn(w)) for w in r.wheels] for r in self.robots])

    def _robot_param(self, fn: Any) -> FloatArray:
        return np.array([float(fn(r)) for r in self.robots])

    def _init_parameters(self) -> None:
        n, m = self.n, self.m
        wp, rp = self._wheel_param, self._robot_param
        self._x = wp(lambda w: w.position[0])
        self._y = wp(lambda w: w.position[1])
        drive = wp(lambda w: w.drive_angle)
        gamma = wp(lambda w: w.gamma)
        r = wp(lambda w: w.radius)
        phi = drive + gamma
        # Rows of H: traction (slip) speeds, roller speeds, axle speeds; columns vx, vy, w, omega_1..m.
        H = np.zeros((n, 3, m, 3 + m))
        H[:, 0, :, 0], H[:, 0, :, 1] = np.cos(phi), np.sin(phi)
        H[:, 0, :, 2] = self._x * np.sin(phi) - self._y * np.cos(phi)
        H[:, 1, :, 0], H[:, 1, :, 1] = -np.sin(phi), np.cos(phi)
        H[:, 1, :, 2] = self._x * np.cos(phi) + self._y * np.sin(phi)
        wheel = np.arange(m)
        H[:, 0, wheel, 3 + wheel] = -r * np.cos(gamma)
        H[:, 1, wheel, 3 + wheel] = r * np.sin(gamma)
        H[:, 2, wheel, 3 + wheel] = 1.0
        self._H = H.reshape(n, 3 * m, 3 + m).copy()
        self._HT = np.ascontiguousarray(self._H.transpose(0, 2, 1))
        # Robots with one geometry share H: then the products below are single BLAS calls.
        self._shared = bool(np.all(self._H[:1] == self._H))
        H0 = self._H[0]
        self._H0, self._H0T = H0.copy(), np.ascontiguousarray(H0.T)
        self._H0_outer = (H0[:, :, None] * H0[:, None, :]).reshape(3 * m, (3 + m) ** 2)

        self._mass = rp(lambda rb: rb.mass)
        inertia = wp(lambda w: w.inertia + w.motor.gear_ratio**2 * w.motor.rotor_inertia)
        diag = np.concatenate(
            [self._mass[:, None], self._mass[:, None], rp(lambda rb: rb.yaw_inertia)[:, None], inertia],
            axis=1,
        )
        self._M_dt = np.zeros((n, 3 + m, 3 + m))
        self._M_dt[:, np.arange(3 + m), np.arange(3 + m)] = diag / self.dt

        k = wp(lambda w: w.motor.torque_constant)
        gear = wp(lambda w: w.motor.gear_ratio)
        eta = wp(lambda w: w.motor.gear_efficiency)
        self._inv_res = 1.0 / wp(lambda w: w.motor.resistance)
        self._ke = k * gear  # back-EMF, V per wheel rad/s
        self._kt = eta * k * gear  # wheel torque, N m per A
        self._emf_damping = self._kt * self._ke * self._inv_res
        self._ke_res = self._ke * self._inv_res
        self._i_max = wp(lambda w: w.motor.current_limit)
        self._neg_i_max = -self._i_max
        self._drop = wp(lambda w: w.motor.driver_drop)
        self._on_threshold = np.maximum(wp(lambda w: w.motor.deadband), 1e-9)
        self._inv_pwm_max = 1.0 / wp(lambda w: w.motor.pwm_max)
        self._visc = wp(lambda w: w.motor.friction_viscous)
        self._v_nominal = rp(lambda rb: rb.battery.voltage)
        self._r_batt = rp(lambda rb: rb.battery.internal_resistance)
        # relaxing V_bus by 1/(1 + R_batt sum(1/R)) per step keeps the lagged coupling stable for any battery
        self._batt_relax = 1.0 / (1.0 + self._r_batt * self._inv_res.sum(axis=1))

        self._grip = wp(lambda w: w.rollers.grip)
        rr0 = wp(lambda w: w.rollers.rolling_resistance)
        self._rr_var = 0.5 * rr0 * wp(lambda w: w.rollers.friction_variation)
        self._rr_top = rr0 + self._rr_var
        self._roller_count = wp(lambda w: w.rollers.count)

        self._mu_tab = np.array([s.mu for s in self.surfaces])
        self._inv_veps_tab = np.array([1.0 / s.slip_velocity for s in self.surfaces])
        self._roll_tab = np.array([s.rolling_multiplier for s in self.surfaces])
        # Friction laws per contact row: saturation force (or torque) and 1/regularisation speed.
        self._fmax = np.empty((n, 3 * m))
        self._fmax[:, 2 * m :] = wp(lambda w: w.motor.friction_static)
        self._inv_eps = np.empty((n, 3 * m))
        self._inv_eps[:, :m] = self._inv_veps_tab[0]
        self._inv_eps[:, m : 2 * m] = 1.0 / ROLL_SPEED_EPS
        self._inv_eps[:, 2 * m :] = 1.0 / WHEEL_SPEED_EPS

    def _set_loads(self) -> None:
        self._load = static_loads(self._x, self._y, self._mass, self._lifted)
        self._load.flags.writeable = False
        self._grip_load = self._grip * self._load
        self._default_surface()

    def _default_surface(self) -> None:
        m = self.m
        self._fmax[:, :m] = self._mu_tab[0] * self._grip_load
        self._inv_eps[:, :m] = self._inv_veps_tab[0]
        self._roll_load = self._roll_tab[0] * self._load
        self._custom_surface = False

    def _apply_surface(self, surface_ids: ArrayLike) -> None:
        m = self.m
        ids = np.broadcast_to(np.asarray(surface_ids, dtype=np.intp), (self.n, m))
        if ids.min() < 0 or ids.max() >= len(self.surfaces):
            raise SimulationError(f"surface_ids must index the {len(self.surfaces)} surfaces of this Physics")
        self._fmax[:, :m] = self._mu_tab[ids] * self._grip_load
        self._inv_eps[:, :m] = self._inv_veps_tab[ids]
        self._roll_load = self._roll_tab[ids] * self._load
        self._custom_surface = True

    # ------------------------------------------------------------------ state access

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
        return self._v_bus.copy()

    @property
    def slip(self) -> FloatArray:
        """(n,m) slip speed along each wheel's traction direction, m/s (contact velocity minus rim)."""
        return np.asarray((self._H[:, : self.m] @ self._q[:, :, None])[:, :, 0], dtype=float)

    @property
    def roller_speed(self) -> FloatArray:
        """(n,m) speed of the floor under each wheel along its free roller direction, m/s."""
        return np.asarray((self._H[:, self.m : 2 * self.m] @ self._q[:, :, None])[:, :, 0], dtype=float)

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
        self.wheel_angle[:] = (
            0.0 if wheel_angle is None else np.broadcast_to(np.asarray(wheel_angle, float), (self.n, self.m))
        )
        self._q[:] = 0.0
        self.motor_current[:] = 0.0
        self.traction_force[:] = 0.0
        self._i_batt[:] = 0.0
        self._v_bus[:] = self.battery_open_voltage
        self._steps = 0

    # ------------------------------------------------------------------ dynamics

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
        m, dt, q = self.m, self.dt, self._q
        omega = q[:, 3:]

        # --- driver and motor: current, torque and its slope (back-EMF damping while not limited)
        pwm_a = np.asarray(pwm, dtype=float)
        duty = np.minimum(np.maximum(pwm_a * self._inv_pwm_max, -1.0), 1.0)
        on = np.abs(pwm_a) >= self._on_threshold
        v_bus = self._v_bus + self._batt_relax * (
            self.battery_open_voltage - self._r_batt * self._i_batt - self._v_bus
        )
        np.maximum(v_bus, 0.0, out=v_bus)
        i_stall = np.maximum(v_bus[:, None] - self._drop, 0.0) * self._inv_res
        i_free = duty * i_stall - self._ke_res * omega
        current = np.minimum(np.maximum(i_free, self._neg_i_max), self._i_max) * on
        linear = on & (np.abs(i_free) < self._i_max)

        # --- friction laws on every contact row (traction slip, roller rolling, axle)
        if surface_ids is not None:
            self._apply_surface(surface_ids)
        elif self._custom_surface:
            self._default_surface()
        fmax, inv_eps = self._fmax, self._inv_eps
        np.multiply(
            self._rr_top - self._rr_var * np.cos(self._roller_count * self.wheel_angle),
            self._roll_load,
            out=fmax[:, m : 2 * m],
        )
        x = q @ self._H0T if self._shared else (self._H @ q[:, :, None])[:, :, 0]
        x *= inv_eps
        th = np.tanh(x)
        force = fmax * th
        at_rest = x == 0.0  # there tanh(x)/x is 1: add 1 above and below
        kd = fmax * inv_eps * ((th + at_rest) / (x + at_rest))
        # axle rows also carry the motor: drive torque minus viscous friction, and their slopes
        force[:, 2 * m :] -= self._kt * current - self._visc * omega
        kd[:, 2 * m :] += self._emf_damping * linear + self._visc

        # --- linearised backward Euler on q = (twist, wheel speeds); force holds -f (sign folded)
        if self._shared:
            Q = force @ self._H0
            A = (kd @ self._H0_outer).reshape(self._M_dt.shape)
        else:
            Q = (self._HT @ force[:, :, None])[:, :, 0]
            A = self._HT @ (kd[:, :, None] * self._H)
        np.negative(Q, out=Q)
        if external_force is not None:
            f = np.broadcast_to(np.asarray(external_force, dtype=float), (self.n, 3))
            c, s = np.cos(self._pose[:, 2]), np.sin(self._pose[:, 2])
            Q[:, 0] += c * f[:, 0] + s * f[:, 1]
            Q[:, 1] += c * f[:, 1] - s * f[:, 0]
            Q[:, 2] += f[:, 2]
        A += self._M_dt
        q += np.linalg.solve(A, Q[:, :, None])[:, :, 0]

        # --- body-frame rotation of the velocity, pose and wheel angles ((x, y) pairs as complex views)
        w = q[:, 2]
        v = q[:, 0:2].view(np.complex128)[:, 0]
        v *= np.exp(w * (-1j * dt))
        heading = self._pose[:, 2] + (0.5 * dt) * w
        self._pose[:, 0:2].view(np.complex128)[:, 0] += np.exp(1j * heading) * v * dt
        self._pose[:, 2] += dt * w
        self.wheel_angle += dt * omega
        self.motor_current[:] = current
        np.negative(force[:, :m], out=self.traction_force)
        self._v_bus[:] = v_bus
        self._i_batt[:] = (duty * current).sum(axis=1)
        self._steps += 1


__all__ = ["GRAVITY", "ROLL_SPEED_EPS", "WHEEL_SPEED_EPS", "Physics", "static_loads"]
