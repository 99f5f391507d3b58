"""The idle wheels' roller drag, measured: the drag runs and the MOVEs that tune its coast
(:mod:`omnibot.calibration.rollerfit` fits both).

Runs (:func:`roller_runs`): raw POWER along each idle axis in turn, round the circle (omni4: 0, 90,
180, 270 degrees), at three powers over the working range and two durations each (the second twice
the first). Each run turns the next axis's idle wheels by its whole distance, so their roller
phases come out spread over the pitch; the encoder counts at each run's start give the phases of the
wheels that stand still.

Coast (:func:`tune_coast`): MOVEs round the motor axes with and without the drag term uploaded; the
gain that cancels the drag in them gives the coast table the controller uses.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from omnibot.calibration.coastfit import (
    CoastTuning,
    IdleDrag,
    coast_row,
    coast_tuning,
    fit_coast_speed,
    fit_idle_drag,
    idle_row,
    spec_drag,
)
from omnibot.calibration.deadband import turn_wheels
from omnibot.calibration.patterns import course_pattern, top_power
from omnibot.calibration.plan import Plan
from omnibot.calibration.rollerfit import GROUP, RollerFit, axis_courses
from omnibot.calibration.runner import Runner
from omnibot.calibration.runs import STRAIGHT, RunInfo, RunResult
from omnibot.robot import CalibrationSpec, PiecewiseLinear, RollerDragSpec

PROBE = 0.6
"""s of each power's first run, which sets the durations of the others."""
SHARES = (0.3, 0.55, 0.8)
"""The runs' powers, as fractions of the way from the axis's dead band to full power."""


def roller_runs(runner: Runner, plan: Plan, deadband: int, rounds: int = 4) -> list[RunResult]:
    """The drag runs (see the module docstring): per power a probe, then ``rounds`` times round the
    axes, alternating the two durations."""
    geo = runner.geometry
    courses = axis_courses(geo)
    top = top_power(runner.motors, geo.pwm_max)

    def run(course: float, power: int, duration: float, group: str) -> RunResult:
        info = RunInfo(
            STRAIGHT,
            f"roller drag, course {course:g} deg, power {power} for {duration:g} s",
            math.radians(course),
        )
        runner.note(f"roller drag: course {course:g}, power {power}")
        pattern = course_pattern(geo, course, power, runner.motors, runner.rate)
        return runner.power_run(
            pattern, duration, info, group, power=power, course_deg=course, folded_deg=0.0
        )

    out = []
    for share in SHARES:
        power = max(1, round(deadband + share * (top - deadband)))
        probe = run(courses[0], power, PROBE, f"{GROUP}:probe")
        speed = max((probe.amount or 0.0) / PROBE, 0.05)
        # the first duration covers about 40 % of the reference move, the second twice that
        first = round(min(max(0.4 * plan.move_length / speed, 0.3), 3.0), 2)
        for k in range(rounds):
            for course in courses:
                out.append(run(course, power, first * (1 + k % 2), GROUP))
    return out


PHASE_STEP = 0.381966
"""Roller pitches between the phases :func:`tune_coast` sets one round after another (the golden
section: every phase over the pitch is near one of the first few)."""
MIN_SHIFT = 0.1
"""Roller pitches: a wheel this close to the phase asked is left where it stands."""


def set_idle_phase(runner: Runner, course: float, target: float, loss: float = 0.0, tries: int = 2) -> float:
    """ROTATE in place so that the first wheel standing still on a MOVE along ``course`` stands at
    roller phase ``target`` (a fraction of its pitch from the encoders' origin); returns the pitches
    by which the last ROTATE fell short of the turn asked (pass it back as ``loss`` next time).

    A rotation in place turns every wheel by the same rim distance and leaves the robot where it is
    (omni4: 11.7 degrees per roller pitch). It turns one to two pitches, always the same way (a
    ROTATE of a few degrees does not get out of its dead band), asking ``loss`` pitches more (a short
    open-loop ROTATE falls short by about its start and stop: on the simulated carpet 4 degrees of
    11-23, a third of a pitch), and once more when it still missed by more than :data:`MIN_SHIFT`.
    The wheels' phases relative to each other move only with travel, so the other idle wheels
    follow at whatever offset the MOVEs before left them. The phase reached is what the encoders
    then say, not the one asked."""
    geo, robot = runner.geometry, runner.robot
    idle = geo.idle_wheels(course)
    if not idle or not geo.roller_pitch[idle[0]] > 0.0:
        return loss
    i = idle[0]
    pitch = geo.roller_pitch[i]
    rim = geo.rotation_rim()
    metres = [2.0 * math.pi * w.radius / w.rollers.count for w in robot.wheels]
    per = rim[i] * max(metres) / (min(abs(v) for v in rim) * metres[i])  # wheel i's pitches per unit
    for _ in range(tries):
        counts = runner.tap.counts()
        if counts is None:
            return loss
        shift = (target - (counts[i] % pitch) / pitch) % 1.0
        if min(shift, 1.0 - shift) < MIN_SHIFT:
            return loss
        asked = shift + 1.0 + loss
        turn_wheels(runner, asked / per, f"{GROUP}:phase", "roller gain")
        after = runner.tap.counts()
        if after is not None:
            loss = min(max(asked - (after[i] - counts[i]) / pitch, -0.5), 1.0)
    return loss


def probe_drag(rollers: RollerDragSpec) -> RollerDragSpec:
    """The term the slowest speed's MOVEs run with: the drag runs' coefficients, each wheel's scaled up
    to the largest wheel's amplitude, without a coast. The controller's powers are whole PWM
    counts, so a term of about one count (the drag runs' on a wheel they could not tell well) says
    little about what a count is worth; a term as large as the drag itself does."""
    amps = [math.hypot(c, s) for c, s in zip(rollers.cos, rollers.sin, strict=True)]
    top = max(amps)
    scale = [top / a if a > 0.0 else 0.0 for a in amps]
    if top <= 0.0:
        return rollers.model_copy(update={"coast": None})
    return RollerDragSpec(
        cos=tuple(round(c * k, 2) for c, k in zip(rollers.cos, scale, strict=True)),
        sin=tuple(round(s * k, 2) for s, k in zip(rollers.sin, scale, strict=True)),
    )


def tune_coast(
    runner: Runner,
    spec: CalibrationSpec,
    fit: RollerFit,
    speeds: Sequence[float],
    length: float,
    rounds: int = 4,
    slow_rounds: int | None = None,
) -> CoastTuning | None:
    """MOVEs of ``length`` round the motor axes at each speed (``rounds`` times round; the slowest
    speed ``slow_rounds`` times, default the same), alternately with and without the drag term of
    ``spec`` uploaded, each from idle wheels put at a chosen roller phase (:func:`set_idle_phase`,
    spread over the pitch round after round), and the term that cancels the drag in them.

    At the slowest speed, where a PWM count moves a MOVE the most, the MOVEs (with the term of
    :func:`probe_drag`) measure each idle wheel's drag themselves
    (:func:`~omnibot.calibration.coastfit.fit_idle_drag`); those
    coefficients replace the drag runs' and are uploaded for the faster speeds, which measure only
    how much of them each needs. Per faster speed, with D_j the drag at the run's phases and g_j the
    term's gain (0 when off)::

        distance_j = e_course - lambda D_j + mu g_j D_j

    so the gain that cancels it is ``lambda / mu`` (the slowest speed's is 1), and the coast table is
    ``(gain - 1) L / V``. Leaves the controller with ``spec`` uploaded (the session uploads the
    section built with the result). None when a speed's runs could not tell (then the drag runs'
    coefficients and coast stand)."""
    geo = runner.geometry
    rollers = spec.rollers
    if rollers is None or not fit.kept:
        return None
    courses = axis_courses(geo)
    found: list[tuple[float, float, float, float]] = []
    ahead: list[tuple[float, float, float]] = []
    idle: IdleDrag | None = None
    runs, loss = 0, 0.0
    try:
        for speed in sorted(speeds):
            slowest = not found
            term = probe_drag(rollers) if slowest else rollers
            n = slow_rounds if slow_rounds is not None and slowest else rounds
            rows, full, b, loss = _gain_runs(runner, spec, term, courses, speed, length, n, loss)
            runs += n * len(courses)
            if slowest:
                idle = fit_idle_drag(geo, courses, full, b)
                if idle is None:
                    return None
                found.append((speed, idle.power, idle.power, 1.0))
                ahead += idle.ahead
                rollers = RollerDragSpec(cos=idle.cos, sin=idle.sin)  # gain 1 at the faster speeds
                continue
            got = fit_coast_speed(courses, rows, b)
            if got is None:
                return None
            lam, mu, course_ahead = got
            found.append((speed, lam, mu, lam / mu))
            ahead += course_ahead
    finally:
        runner.client.upload_calibration(spec)
    return coast_tuning(found, ahead, runs, length, idle)


def _gain_runs(
    runner: Runner,
    spec: CalibrationSpec,
    term: RollerDragSpec,
    courses: Sequence[float],
    speed: float,
    length: float,
    rounds: int,
    loss: float,
) -> tuple[list[list[float]], list[list[float]], list[float], float]:
    """One speed's MOVEs of :func:`tune_coast`: ``rounds`` times round the courses, alternately with
    and without the drag ``term`` in ``spec`` uploaded, each from idle wheels at a chosen roller
    phase. The faster speeds' fit rows, the slowest's, the distances, and the phase setting's
    running ``loss``."""
    geo = runner.geometry
    table = term.coast or PiecewiseLinear(x=(0.0,), y=(0.0,))
    gain = 1.0 + table(speed) * speed / length
    on_spec = spec.model_copy(update={"rollers": term})
    off = spec.model_copy(update={"rollers": None})
    rows: list[list[float]] = []  # the faster speeds' fit
    full: list[list[float]] = []  # the slowest's
    b: list[float] = []
    for k in range(rounds):
        on = k % 2 == 0
        runner.client.upload_calibration(on_spec if on else off)
        for j, course in enumerate(courses):
            target = (PHASE_STEP * (k // 2) + 0.5 * (k % 2) + j / 8.0) % 1.0
            loss = set_idle_phase(runner, course, target, loss)
            runner.note(f"roller gain {speed:g} m/s")
            detail = f" ({'with' if on else 'without'} the term)"
            r = runner.move("roller drag gain", length, speed, course, f"{GROUP}:gain", detail)
            if r.truth is None or r.truth.distance is None or r.counts is None:
                continue
            counts = r.counts[: geo.motors]
            d = spec_drag(geo, term, course, counts)
            rows.append(coast_row(courses, course, d, gain if on else 0.0))
            full.append(idle_row(geo, courses, course, counts, gain * d if on else 0.0))
            b.append(r.truth.distance)
    return rows, full, b, loss
