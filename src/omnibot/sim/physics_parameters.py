"""The physics' parameters, from the robot descriptions and the floor, in the columns the kernels
read (:mod:`omnibot.sim.kernels.layout`): per wheel (the contact rows of H, motor, driver and
rollers), per robot (mass, inertia, battery) and per surface (friction, slip speed, rolling)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from omnibot.floor import Surface
from omnibot.robot import RobotDescription, WheelSpec
from omnibot.robot.kinematics import contact_rows
from omnibot.sim.kernels import layout

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Parameters:
    """The kernels' parameter tables and what the static loads are computed from.

    ``x``, ``y`` (n, m) are the wheels' positions; the static load scales ``grip`` (the rollers'
    grip) and ``scrub`` (their combined drag) into ``wheels``' load columns (``Physics._set_loads``).
    """

    wheels: FloatArray
    """(n, m, W_COLUMNS) per wheel."""
    robots: FloatArray
    """(n, R_COLUMNS) per robot."""
    surfaces: FloatArray
    """(S, S_COLUMNS) per floor surface."""
    x: FloatArray
    y: FloatArray
    grip: FloatArray
    scrub: FloatArray
    mass: FloatArray
    """(n,) each robot's mass, kg."""


def parameters(robots: Sequence[RobotDescription], surfaces: Sequence[Surface], dt: float) -> Parameters:
    """Every parameter table of robots (all with the same wheel count) on ``surfaces``, stepped by dt."""

    def per_wheel(fn: Callable[[WheelSpec], float]) -> FloatArray:
        return np.array([[float(fn(w)) for w in r.wheels] for r in robots])

    wheels = _wheel_table(per_wheel, dt)
    inv_res = 1.0 / per_wheel(lambda w: w.motor.resistance)
    mass = np.array([float(r.mass) for r in robots])
    return Parameters(
        wheels=wheels,
        robots=_robot_table(robots, mass, inv_res, dt),
        surfaces=_surface_table(surfaces),
        x=per_wheel(lambda w: w.position[0]),
        y=per_wheel(lambda w: w.position[1]),
        grip=per_wheel(lambda w: w.rollers.grip),
        scrub=per_wheel(lambda w: w.rollers.combined_drag),
        mass=mass,
    )


def _wheel_table(wp: Callable[[Callable[[WheelSpec], float]], FloatArray], dt: float) -> FloatArray:
    """(n, m, W_COLUMNS): the contact rows of H, the motor and driver, the rollers (the load
    columns are the static loads', set apart)."""
    x, y = wp(lambda w: w.position[0]), wp(lambda w: w.position[1])
    gamma = wp(lambda w: w.gamma)
    r = wp(lambda w: w.radius)
    traction, roller = contact_rows(x, y, wp(lambda w: w.drive_angle), gamma)
    W = np.zeros((*x.shape, layout.W_COLUMNS))
    # Rows of H per wheel: traction (slip) speed and roller speed over vx, vy, w and the wheel's omega.
    W[..., layout.W_TX : layout.W_TW + 1] = traction
    W[..., layout.W_TA] = -r * np.cos(gamma)
    W[..., layout.W_NX : layout.W_NW + 1] = roller
    W[..., layout.W_NA] = r * np.sin(gamma)
    W[..., layout.W_J_DT] = wp(lambda w: w.inertia + w.motor.gear_ratio**2 * w.motor.rotor_inertia) / dt
    k = wp(lambda w: w.motor.torque_constant)
    gear = wp(lambda w: w.motor.gear_ratio)
    eta = wp(lambda w: w.motor.gear_efficiency)
    inv_res = 1.0 / wp(lambda w: w.motor.resistance)
    ke = k * gear  # back-EMF, V per wheel rad/s
    kt = eta * k * gear  # wheel torque, N m per A
    W[..., layout.W_INV_PWM_MAX] = 1.0 / wp(lambda w: w.motor.pwm_max)
    W[..., layout.W_ON_THRESHOLD] = np.maximum(wp(lambda w: w.motor.deadband), 1e-9)
    W[..., layout.W_DROP] = wp(lambda w: w.motor.driver_drop)
    W[..., layout.W_INV_RES] = inv_res
    W[..., layout.W_KE_RES] = ke * inv_res
    W[..., layout.W_I_MAX] = wp(lambda w: w.motor.current_max)
    W[..., layout.W_KT] = kt
    W[..., layout.W_EMF_DAMPING] = kt * ke * inv_res
    W[..., layout.W_VISC] = wp(lambda w: w.motor.friction_viscous)
    W[..., layout.W_STATIC] = wp(lambda w: w.motor.friction_static)
    rr0 = wp(lambda w: w.rollers.rolling_resistance)
    rr_var = 0.5 * rr0 * wp(lambda w: w.rollers.friction_variation)
    W[..., layout.W_RR_VAR] = rr_var
    W[..., layout.W_RR_TOP] = rr0 + rr_var
    W[..., layout.W_ROLLER_COUNT] = wp(lambda w: w.rollers.count)
    W[..., layout.W_RADIUS] = r
    return W


def _robot_table(
    robots: Sequence[RobotDescription], mass: FloatArray, inv_res: FloatArray, dt: float
) -> FloatArray:
    """(n, R_COLUMNS): mass and yaw inertia over dt, the battery's resistance and relaxation."""
    r_batt = np.array([float(rb.battery.internal_resistance) for rb in robots])
    R = np.zeros((len(robots), layout.R_COLUMNS))
    R[:, layout.R_M_DT] = mass / dt
    R[:, layout.R_I_DT] = np.array([float(rb.yaw_inertia) for rb in robots]) / dt
    R[:, layout.R_BATT_RES] = r_batt
    # relaxing V_bus by 1/(1 + R_batt sum(1/R)) per step keeps the lagged coupling stable for any battery
    R[:, layout.R_BATT_RELAX] = 1.0 / (1.0 + r_batt * inv_res.sum(axis=1))
    return R


def _surface_table(surfaces: Sequence[Surface]) -> FloatArray:
    """(S, S_COLUMNS): each surface's friction coefficient, 1 / slip speed, rolling multiplier."""
    S = np.zeros((len(surfaces), layout.S_COLUMNS))
    S[:, layout.S_MU] = [s.mu for s in surfaces]
    S[:, layout.S_INV_VEPS] = [1.0 / s.slip_velocity for s in surfaces]
    S[:, layout.S_ROLL] = [s.rolling_multiplier for s in surfaces]
    return S


__all__ = ["Parameters", "parameters"]
