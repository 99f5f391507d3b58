"""A readable, plain-text summary of a robot description (``omnibot robot show``)."""

from __future__ import annotations

import math

from omnibot.robot.description import RobotDescription


def describe(robot: RobotDescription) -> str:
    """Multi-line summary: body, wheels, motors, sensors, limits and the kinematics matrix."""
    lines = [f"{robot.name}: {robot.summary}" if robot.summary else robot.name, ""]
    fp = robot.footprint
    size = f"radius {fp.radius:g} m" if fp.shape == "circle" else f"{fp.shape} {fp.length}x{fp.width} m"
    lines.append(
        f"body      mass {robot.mass:g} kg, yaw inertia {robot.yaw_inertia:g} kg m^2, footprint {size}"
    )
    b = robot.battery
    lines.append(f"battery   {b.voltage:g} V, {b.internal_resistance:g} ohm, {b.capacity_ah:g} Ah")
    lines.append("")
    lines.append("wheel          x [m]    y [m]  drive [deg]  gamma [deg]  radius [m]")
    for w in robot.wheels:
        x, y = w.position
        drive = math.degrees(math.remainder(w.drive_angle, math.tau)) + 0.0  # (-180, 180], never -0
        lines.append(f"{w.name:12s} {x:7.4f}  {y:7.4f}  {drive:11.2f}  {w.gamma_deg:11.2f}  {w.radius:10.4f}")
    m = robot.wheels[0].motor
    same = all(w.motor == m for w in robot.wheels)
    current = "none" if m.current_limit is None else f"{m.current_limit:g} A"
    lines.append("")
    lines.append(
        f"motor{'s' if same else ' (wheel 1)'}    R {m.resistance:g} ohm, k {m.torque_constant:g} N m/A, gear {m.gear_ratio:g}:1, "
        f"driver drop {m.driver_drop:g} V, current limit {current}, PWM {m.pwm_bits} bit"
    )
    if not same:
        lines.append("          (motors differ per wheel)")
    lines += _sensor_lines(robot)
    lim = robot.limits
    lines.append("")
    lines.append(
        f"limits    speed {lim.speed_min:g}..{lim.speed_max:g} m/s, turn {lim.angular_speed_max:g} rad/s, "
        f"curvature {lim.curvature_max:g} 1/m, accel {lim.acceleration_max:g} m/s^2"
    )
    lines.append("")
    lines.append("inverse kinematics: wheel rad/s = J (vx, vy, w)")
    for w, row in zip(robot.wheels, robot.inverse_rows, strict=True):
        lines.append(f"  {w.name:12s} " + " ".join(f"{v:9.4f}" for v in row))
    return "\n".join(lines)


def _sensor_lines(robot: RobotDescription) -> list[str]:
    """The encoders (motor and tracking), the gyro, each sonar and the laser scanner."""
    lines = []
    enc = robot.encoders
    if enc.motors:
        lines.append(
            f"encoders  motor: {', '.join(f'{e.wheel} {e.counts_per_rev} counts/rev' for e in enc.motors)}"
        )
    if enc.tracking:
        lines.append(
            "          tracking: "
            + ", ".join(f"{t.name} r={t.radius:g} m {t.counts_per_rev} counts/rev" for t in enc.tracking)
        )
    if robot.gyro is not None:
        lines.append(f"gyro      {robot.gyro.model}, {robot.gyro.rate_hz:g} Hz")
    for s in robot.sonars:
        lines.append(
            f"sonar     {s.name} at ({s.x:g}, {s.y:g}) facing {s.angle_deg:g} deg, cone {s.cone_deg:g} deg, "
            f"{s.min_range:g}-{s.max_range:g} m"
        )
    sc = robot.scanner
    if sc is not None:
        lines.append(
            f"scanner   {sc.model} '{sc.frame}' at ({sc.x:g}, {sc.y:g}, {sc.z:g} m) facing {sc.yaw_deg:g} deg, "
            f"{sc.rays} rays at {sc.rate_hz:g} Hz {sc.spin}, {sc.range_min:g}-{sc.range_max:g} m, "
            f"noise {sc.noise_std:g} m + {sc.noise_fraction:.2%}, dropout {sc.dropout:g}"
            + ("" if sc.motion_distortion else ", no motion distortion")
        )
    return lines
