"""Seed 003's main movement directions, driven open loop on each preset in the simulator.

For every direction the wheel pattern comes from the robot's inverse kinematics, scaled so the
busiest motor gets ``power`` PWM counts (the direction-keeping saturation), and is held for
``duration`` seconds from rest. What the robot actually does (its direction of travel, speed and
heading drift) shows what the wheel dynamics, roller friction and floor add to the ideal model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from omnibot.progress import Progress
from omnibot.robot import RobotDescription
from omnibot.robot import kinematics as kin
from omnibot.sim import Simulator

DIRECTIONS: tuple[tuple[str, float, float, float], ...] = (
    ("forward", 1, 0, 0),
    ("backward", -1, 0, 0),
    ("left", 0, 1, 0),
    ("right", 0, -1, 0),
    ("forward-left", 1, 1, 0),
    ("forward-right", 1, -1, 0),
    ("backward-left", -1, 1, 0),
    ("backward-right", -1, -1, 0),
    ("rotate ccw", 0, 0, 1),
    ("rotate cw", 0, 0, -1),
)
"""Name and body twist direction (vx, vy, w) of seed 003's Fig. 4 motions."""


@dataclass(frozen=True)
class DirectionRun:
    """One open-loop run: the PWM pattern, commanded and achieved direction (degrees), distance (m),
    heading change (degrees) and the pose trail."""

    name: str
    pwm: tuple[int, ...]
    commanded_deg: float | None
    """Commanded direction of travel (None for a rotation)."""
    achieved_deg: float
    """Direction of the displacement (for a rotation: the turn in degrees)."""
    distance: float
    heading_change_deg: float
    trail: np.ndarray
    """(k, 3) pose samples x, y, theta every 10 ms."""


def wheel_pattern(robot: RobotDescription, twist: tuple[float, float, float], power: int) -> list[int]:
    """PWM per motor for a twist direction: inverse kinematics, busiest motor at ``power``."""
    J = robot.wheel_matrix
    scale = 1.0 if twist[2] == 0 else 0.15  # a rotation of 1 rad/s per 0.15 m/s keeps wheels comparable
    speeds = kin.inverse(J, (twist[0], twist[1], twist[2] * scale))
    peak = float(np.max(np.abs(speeds)))
    return [round(power * s / peak) for s in speeds]


def run_direction(
    robot: RobotDescription,
    name: str,
    twist: tuple[float, float, float],
    *,
    power: int,
    duration: float,
    surface: str,
    seed: int,
) -> DirectionRun:
    """Drive ``robot`` open-loop in the direction of ``twist`` for ``duration`` s on a fresh simulator,
    the busiest motor at ``power`` PWM counts; what it achieved."""
    sim = Simulator(robot, surface=surface, seed=seed)
    pwm = wheel_pattern(robot, twist, power)
    trail: list[tuple[float, float, float]] = []
    sim.set_pwm(pwm)
    for k in range(round(duration / sim.dt)):
        if k % 10 == 0:
            p = sim.pose
            trail.append((p.x, p.y, p.theta))
        sim.step()
    p = sim.pose
    trail.append((p.x, p.y, p.theta))
    rotation = twist[0] == 0 and twist[1] == 0
    return DirectionRun(
        name=name,
        pwm=tuple(pwm),
        commanded_deg=None if rotation else math.degrees(math.atan2(twist[1], twist[0])),
        achieved_deg=math.degrees(p.theta) if rotation else math.degrees(math.atan2(p.y, p.x)),
        distance=math.hypot(p.x, p.y),
        heading_change_deg=math.degrees(p.theta),
        trail=np.array(trail),
    )


def run_tour(
    robot: RobotDescription,
    *,
    power: int = 180,
    duration: float = 1.0,
    surface: str = "wood",
    seed: int = 0,
    progress: Progress | None = None,
) -> list[DirectionRun]:
    """Every direction of :data:`DIRECTIONS`, each from rest at the origin (``progress`` counts them)."""
    runs = []
    for name, vx, vy, w in DIRECTIONS:
        if progress is not None:
            progress.set_postfix_str(name)
        runs.append(
            run_direction(
                robot, name, (vx, vy, w), power=power, duration=duration, surface=surface, seed=seed
            )
        )
        if progress is not None:
            progress.update(1)
    return runs


def format_table(robot: RobotDescription, runs: list[DirectionRun]) -> str:
    """The runs as a text table: PWM per motor, commanded and achieved direction, distance and heading."""
    lines = [
        f"{robot.name}: open-loop main directions (seed 003, Fig. 4)",
        f"  {'motion':15s} {'PWM per motor':24s} {'commanded':>9s} {'achieved':>9s} {'distance':>9s} {'heading':>8s}",
    ]
    for r in runs:
        cmd = "   rotate" if r.commanded_deg is None else f"{r.commanded_deg:8.1f}°"
        ach = f"{r.achieved_deg:8.1f}°"
        pwm = ",".join(f"{p:d}" for p in r.pwm)
        lines.append(
            f"  {r.name:15s} {pwm:24s} {cmd:>9s} {ach:>9s} {r.distance:8.3f}m {r.heading_change_deg:7.1f}°"
        )
    return "\n".join(lines)


def plot_tour(robot: RobotDescription, runs: list[DirectionRun], path: Path) -> None:
    """One panel: every translation's trail from the origin, with heading ticks; rotations listed."""
    from omnibot.plots import new_figure, save

    fig, axes = new_figure(1, 1, size=(6.5, 6.0))
    ax = axes[0][0]
    for r in runs:
        if r.commanded_deg is None:
            continue
        (line,) = ax.plot(r.trail[:, 0], r.trail[:, 1], label=r.name)
        for x, y, th in r.trail[:: max(1, len(r.trail) // 5)]:
            ax.arrow(x, y, 0.03 * math.cos(th), 0.03 * math.sin(th), width=0.002, color=line.get_color())
        c = math.radians(r.commanded_deg)
        ax.plot([0, r.distance * math.cos(c)], [0, r.distance * math.sin(c)], ":", color=line.get_color())
    rot = ", ".join(f"{r.name}: {r.heading_change_deg:.0f}°" for r in runs if r.commanded_deg is None)
    ax.set_title(f"{robot.name}: main directions, open loop ({rot})", fontsize=9)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    save(fig, str(path))
