"""A kinematic stand-in for omnibot.sim.physics.Physics, for testing the simulator facade alone.

Powered wheels (PWM != 0) turn at once at the no-load speed times the duty; the body twist relaxes
toward the least-squares twist of the powered wheels on the floor with time constant ``tau`` (a
traction force m (v_target - v) / tau, limited to mu m g), plus any external force. With no wheel
powered the robot coasts to rest with ``coast_tau``. Unpowered wheels roll with the body; lifted
wheels push nothing. Deterministic, with the same attribute API as Physics.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from omnibot.robot import RobotDescription


@dataclass(frozen=True)
class FakeSurface:
    name: str


class FakePhysics:
    def __init__(
        self, robot: RobotDescription, n=1, surfaces=("wood",), dt=0.001, tau=0.05, coast_tau=0.5, mu=0.5, **_
    ):
        self.robot, self.n, self.dt, self.tau, self.coast_tau, self.mu = robot, n, dt, tau, coast_tau, mu
        self.m = robot.n_wheels
        self.surfaces = [FakeSurface(s) for s in surfaces]
        self.J = np.asarray(robot.wheel_matrix)
        self.pos = np.array([w.position for w in robot.wheels])
        self.omega_max = np.array(
            [
                (robot.battery.voltage - w.motor.driver_drop) / (w.motor.torque_constant * w.motor.gear_ratio)
                for w in robot.wheels
            ]
        )
        self.pwm_max = np.array([w.motor.pwm_max for w in robot.wheels], dtype=float)
        self.pose = np.zeros((n, 3))
        self.twist = np.zeros((n, 3))
        self.wheel_angle = np.zeros((n, self.m))
        self.wheel_speed = np.zeros((n, self.m))
        self.motor_current = np.zeros((n, self.m))
        self.lifted = np.zeros((n, self.m), dtype=bool)
        self.battery_voltage = np.full(n, robot.battery.voltage)
        self.time = 0.0
        self.last_surface_ids: np.ndarray | None = None
        self.last_external_force: np.ndarray | None = None
        self.steps = 0

    def reset(self, pose=None):
        self.pose[:] = 0.0 if pose is None else np.broadcast_to(np.asarray(pose, float), (self.n, 3))
        self.twist[:] = 0.0
        self.wheel_angle[:] = 0.0
        self.wheel_speed[:] = 0.0
        self.time = 0.0

    def step(self, pwm, surface_ids=None, external_force=None):
        self.last_surface_ids = None if surface_ids is None else np.array(surface_ids)
        self.last_external_force = None if external_force is None else np.array(external_force)
        duty = np.broadcast_to(np.clip(np.asarray(pwm, float) / self.pwm_max, -1, 1), (self.n, self.m))
        mass, inertia = self.robot.mass, self.robot.yaw_inertia
        for i in range(self.n):
            powered = duty[i] != 0
            rolling = self.J @ self.twist[i]  # undriven wheels on the floor roll with the body
            self.wheel_speed[i] = np.where(
                powered, duty[i] * self.omega_max, np.where(self.lifted[i], 0, rolling)
            )
            driving = powered & ~self.lifted[i]
            target, tau = np.zeros(3), self.coast_tau
            if driving.any():
                target = np.linalg.lstsq(self.J[driving], self.wheel_speed[i, driving], rcond=None)[0]
                tau = self.tau
            acc = (target - self.twist[i]) / tau
            limit = self.mu * 9.81
            lin = np.hypot(acc[0], acc[1])
            if lin > limit:
                acc[:2] *= limit / lin
            if external_force is not None:
                f = np.broadcast_to(np.asarray(external_force, float), (self.n, 3))[i]
                c, s = np.cos(self.pose[i, 2]), np.sin(self.pose[i, 2])
                acc[0] += (c * f[0] + s * f[1]) / mass
                acc[1] += (-s * f[0] + c * f[1]) / mass
                acc[2] += f[2] / inertia
            self.twist[i] += acc * self.dt
            vx, vy, w = self.twist[i]
            c, s = np.cos(self.pose[i, 2]), np.sin(self.pose[i, 2])
            self.pose[i] += self.dt * np.array([c * vx - s * vy, s * vx + c * vy, w])
        self.wheel_angle += self.wheel_speed * self.dt
        self.motor_current[:] = np.abs(duty) * 0.5
        self.time += self.dt
        self.steps += 1

    def contact_points_world(self):
        out = np.empty((self.n, self.m, 2))
        for i in range(self.n):
            c, s = np.cos(self.pose[i, 2]), np.sin(self.pose[i, 2])
            out[i, :, 0] = self.pose[i, 0] + c * self.pos[:, 0] - s * self.pos[:, 1]
            out[i, :, 1] = self.pose[i, 1] + s * self.pos[:, 0] + c * self.pos[:, 1]
        return out


class ScriptedPhysics(FakePhysics):
    """Ignores the PWM: the body moves with a fixed body twist (for sensor tests through the facade)."""

    def __init__(self, robot, twist=(0.0, 0.0, 0.0), **kwargs):
        super().__init__(robot, **kwargs)
        self.script = np.asarray(twist, float)

    def step(self, pwm, surface_ids=None, external_force=None):
        self.last_surface_ids = None if surface_ids is None else np.array(surface_ids)
        self.twist[:] = self.script
        vx, vy, w = self.script
        for i in range(self.n):
            th = self.pose[i, 2] + 0.5 * self.dt * w
            c, s = np.cos(th), np.sin(th)
            self.pose[i] += self.dt * np.array([c * vx - s * vy, s * vx + c * vy, w])
        self.wheel_speed[:] = self.J @ self.script
        self.wheel_angle += self.wheel_speed * self.dt
        self.time += self.dt
        self.steps += 1
