"""How much a calibration measures: the :class:`Plan` of one surface and the speed range it covers
(plain data, no I/O)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from omnibot.calibration.patterns import Geometry
from omnibot.errors import ConfigError
from omnibot.robot import RobotDescription

DIAGONAL = 45.0
"""degrees: a fold range wider than this has no mirror at the diagonal (a mecanum base folds onto
0..90: forward, the diagonals and sideways are three courses, not two)."""
SHORTEST_MOVE = 1.0
"""s: the calibration covers speeds at which a MOVE of the reference length lasts at least this."""


def speed_range(robot: RobotDescription, length: float) -> tuple[float, float]:
    """(slowest, fastest) MOVE speed the calibration and its checks cover for moves of ``length``:
    the robot's limits, the top cut to where such a MOVE still lasts :data:`SHORTEST_MOVE` (a 30 kg
    robot's 5 m/s is not for 1 m moves)."""
    lim = robot.limits
    hi = min(lim.speed_max, length / SHORTEST_MOVE)
    lo = max(lim.speed_min, 0.1 * hi) if lim.speed_min > 0 else 0.2 * hi
    return min(lo, hi), hi


@dataclass(frozen=True)
class Plan:
    """How much to measure. The defaults suit the simulator; :meth:`quick` a real robot and a tape."""

    course_count: int = 4
    """Calibrated courses, evenly from 0 to the robot's largest folded course (omni4: 0, 15, 30, 45)."""
    courses_deg: tuple[float, ...] | None = None
    """Explicit calibrated courses (folded degrees); overrides ``course_count``."""
    directions: int = 4
    """Raw courses per calibrated course (course + each idle axis and its opposite)."""
    probe: float = 1.0
    """s of power of the first run at the lowest power level (later levels: from the rate so far)."""
    t_min: float = 0.15
    """Shortest run, s."""
    rotate_rate_min: float = 0.5
    """rad/s: the slowest rotation the sweep needs to time (sets the longest rotation run)."""
    levels: int = 8
    """Power levels from the dead band to full power (denser near the dead band)."""
    deadband_step: int = 8
    deadband_positions: int = 3
    """Wheel positions each dead band is the mean over (deadband.spread_deadband; 1: one search)."""
    settle: float = 0.4
    """s to wait after a run for the robot to coast to a stop before measuring."""
    speed_margin: float = 1.2
    """A sweep stops above this times the robot's top speed."""
    move_length: float = 1.0
    """m: the MOVE length the translation fit is exact for (start/stop losses are per move)."""
    rotate_angle: float = math.radians(135.0)
    """rad: the ROTATE angle the rotation fit is exact for."""
    turn_courses_deg: tuple[float, ...] = (0.0, 45.0)
    turn_curvatures: tuple[float, ...] = (1.0, 2.0, 4.0, 7.0)
    """1/m, each run with both signs (clipped to the robot's curvature limit)."""
    turn_speed: float | None = None
    """m/s of the curved MOVEs (default: the middle of the robot's speed range)."""
    turn_rounds: int = 2
    gyro_still: float = 3.0
    """s of standstill for the gyro bias."""
    rotation_turns: float = 2.0
    """Full turns each way of the rotation test (gyro scale, wheel base)."""
    square_side: float = 1.0
    square_speed: float | None = None
    motor_map: bool = True
    """Fit the motor map (each motor's dead-band offset and gain table) before the sweeps."""
    balance_levels: int = 4
    """Nominal powers of the balance runs, spread over what the speed range needs."""
    roller_rounds: int = 4
    """Rounds of the idle axes at each power for the idle wheels' roller drag (rollers.py; 0: none),
    and of the coast MOVEs at each speed."""
    coast_slow_rounds: int = 8
    """Rounds of the coast MOVEs at their slowest speed, where a PWM count is the largest share of the
    speed: they measure each idle wheel's drag (rollers.tune_coast; 13 unknowns on omni4) and tell
    the motor pairs' offsets apart best."""
    slow_rounds: int = 2
    """Rounds of MOVEs at the bottom of the speed range on every raw course of each calibrated course,
    through the fitted tables, that anchor K_l's slow end (fits.anchor_slow_end; 0: none)."""
    reach_courses: tuple[float, ...] = (0.0, 1 / 3, 2 / 3, 1.0)
    """Folded courses, as shares of the robot's largest (omni4: 0, 15, 30, 45 degrees), on which MOVEs
    at the computed reach are driven and slowed until they land (reachmoves.py; (): none)."""
    reach_goal: float = 0.02
    """A reach MOVE lands when its distance is within this share of the length, unwarned: two
    thirds of the 3 % goal MOVEs within the reach are held to, so that one at the reach still meets
    it on another run (measured: the same carpet MOVE at its reach landed 2.3 % off on one run and
    3.2 % on the next, the wheels started elsewhere)."""
    reach_step: float = 0.05
    """Each round of reach MOVEs that does not land is driven again this share slower."""
    reach_phases: int = 1
    """Wheel positions each round of reach MOVEs on a course with idle wheels (omni4's axes) is driven
    at, 1 + 1/n roller pitches apart (the idle wheels' drag depends on where they stand; more than one
    was tried and is not the default, docs/calibration.md)."""
    slip: bool = True
    """Drive the wheel-slip runs (16 out-and-back, wheel-speed loop on) and fit the floor's creep."""

    @classmethod
    def quick(cls) -> Plan:
        """Seed 000's own scope: courses 0 and 45 (fold range ends; on a mecanum base 0, 45 and 90), two directions, fewer powers, one
        search per dead band, no extra coast MOVEs, one round of slow-end MOVEs, the reach driven on the
        axes, next to the diagonals and on them only (a person with a tape measures every run)."""
        return cls(
            course_count=2,
            directions=2,
            levels=6,
            turn_curvatures=(2.0, 5.0),
            turn_rounds=1,
            deadband_positions=1,
            coast_slow_rounds=4,
            slow_rounds=1,
            reach_courses=(0.0, 2 / 3, 1.0),
        )

    def reach_folds(self, geometry: Geometry) -> list[float]:
        """The folded courses (whole degrees) the reach MOVEs are driven on (:attr:`reach_courses`)."""
        top = geometry.fold_max
        if top <= DIAGONAL:
            return sorted({float(round(share * top)) for share in self.reach_courses})
        # no mirror at the diagonal (a mecanum base, 0..90): the shares of each half, from both ends
        half = top / 2.0
        return sorted({float(round(end)) for s in self.reach_courses for end in (s * half, top - s * half)})

    def calibrated_courses(self, geometry: Geometry) -> list[float]:
        """The courses to calibrate, degrees: the plan's (checked to increase within 0..fold_max), else
        ``course_count`` spread evenly over it; ConfigError for bad ones."""
        top = geometry.fold_max
        if self.courses_deg is not None:
            bad = [c for c in self.courses_deg if not 0.0 <= c <= top + 1e-9]
            if bad or list(self.courses_deg) != sorted(set(self.courses_deg)):
                raise ConfigError(
                    f"calibrated courses must increase strictly within 0..{top:g} degrees for this robot, "
                    f"got {list(self.courses_deg)}",
                    key="courses",
                )
            return [float(c) for c in self.courses_deg]
        n = max(1, self.course_count)
        if top > DIAGONAL:
            # no mirror at the diagonal (a mecanum base, 0..90): each half spread from both ends, so the
            # diagonal, where two wheels stand idle and K_l turns, is a course of its own
            half = top / 2.0
            ends = [round(half * k / max(n - 1, 1), 3) for k in range(max(n, 2))]
            return sorted({*ends, *(round(top - c, 3) for c in ends)})
        return [0.0] if n == 1 else [round(top * k / (n - 1), 3) for k in range(n)]
