"""Seed 000's Fig. 5 and Fig. 6 beside the simulator's and the calibration's (omni4, wood and carpet).

Run: ``python -m benchmarks.seed000_figures [--calibration CAL.yaml] [--plot DIR]`` (about 20 s;
``--calibration`` takes the file of a default ``omnibot calibrate`` for Fig. 6, ``--plot DIR`` writes
``seed000_fig5.png`` and, with a calibration, ``seed000_fig6.png``).

The seed's numbers: the paper prints its figures as images only; their data are in its authors'
workbook (OSLL omnibot, ``docs/Calibration_test.xlsx``, commit 31c0ff0, sheets ``Data`` and
``Figure2``), whose axis series is ``shared/data``'s ``omni4_straight_power_sweep.csv``. Each series
is the seed's experiment: from rest, the distance in 1000 ms with two opposite motors at +-P (course
0) or all four at +-P (45 degrees), and the time to complete one and two full turns with all four
at +P (rotation; the rate is the wheel path along R_c = 96 mm over that time, as the seed plots it).
The seed does not say on which floor; it says the floors differ by "up to 20 %". Each series' fit is
summed up as its mean abs error over the seed's powers on each floor (:func:`series_errors`).

Fig. 6 (K_t and K_r) is about power, and its statement, "rotation without movement requires more
power than turning adjustment", is checked twice: on the simulated robot itself (the same power as
rotation in place from rest and as a turn added to a robot already moving, :func:`turn_against_rotation`)
and on a calibration's tables read in the seed's terms (its firmware has no motor map, so its K_r
carries the motors' start, which ours keeps in the map's offsets: :mod:`omnibot.calibration.seedterms`).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from omnibot.robot import kinematics as kin
from omnibot.robot import load_robot
from omnibot.sim import Physics

R_C = 0.096
"""m: seed 000's robot radius (the wheel path of a rotation)."""
AXIS_MM = {70: 120, 80: 190, 90: 280, 100: 350, 110: 420, 120: 480, 130: 530, 140: 570, 150: 620, 160: 660,
           170: 710, 180: 750, 190: 790, 200: 850, 210: 880, 220: 930, 230: 970, 240: 1020, 250: 1060, 255: 1090}  # fmt: skip
"""Course 0, mm in 1000 ms (workbook column ``0° (mm)``)."""
AXIS_OTHER_MM = {
    90: {70: 150, 80: 240, 100: 380, 130: 550, 160: 710, 190: 840, 220: 950, 250: 1110, 255: 1120},
    180: {80: 150, 100: 330, 130: 480, 160: 610, 190: 720, 220: 880, 250: 1000, 255: 1060},
    270: {80: 140, 100: 310, 130: 480, 160: 620, 190: 730, 220: 870, 250: 1000, 255: 1070},
}
"""The other axis courses, mm in 1000 ms (``shared/data``'s sweep; the simulated robot is symmetric, so
course 0's simulated series stands for them)."""
DIAGONAL_MM = {80: (None, None, 100), 90: (130, None, 110), 100: (210, 250, 220), 110: (280, 320, 310),
               120: (360, 370, 380), 130: (400, 410, 420), 140: (460, 470, 460), 150: (490, 530, 500),
               160: (550, 570, 520), 170: (590, 650, 560), 180: (630, 670, 620), 190: (700, 670, 730),
               200: (760, 790, 730), 210: (810, 830, 760), 220: (830, 880, 790), 255: (990, 1000, 990)}  # fmt: skip
"""45 degrees: mm in 1000 ms, runs ``45° #1``, ``45° #2`` and ``225°`` (None: not measured)."""
ROTATION_MS = {60: (2650, 5050), 70: (2000, 3800), 80: (1675, 3200), 90: (1440, 2800), 100: (1300, 2450),
               110: (1145, 2250), 120: (1165, 2040), 130: (975, 1850), 140: (905, 1720), 150: (845, 1600),
               160: (800, 1500), 170: (750, 1430), 180: (720, 1340), 190: (680, 1280), 200: (650, 1210),
               210: (625, 1155), 220: (605, 1105), 255: (521, 945)}  # fmt: skip
"""Rotation: ms to complete one and two full turns (``1 rnd (mS)``, ``2 rnd (mS)``)."""
FIG6_X = (*(k / 25.5 for k in range(26)), 1.0)
"""Power as a PWM ratio, the abscissa of the seed's Fig. 6."""
FIG6_KT = (0.2745, 0.298, 0.3216, 0.3451, 0.3686, 0.3922, 0.4706, 0.549, 0.6275, 0.7059, 0.7843, 0.8627,
           0.9412, 1.0196, 1.098, 1.1765, 1.2549, 1.3333, 1.4118, 1.4902, 1.5686, 1.6471, 1.7255, 1.8039,
           1.8824, 1.9608, 2.0)  # fmt: skip
"""The seed's K_t (``Turning (Kt)``)."""
FIG6_KR = (0.3012, 0.3702, 0.4392, 0.5082, 0.5772, 0.6463, 0.7153, 0.7974, 0.8927, 0.988, 1.0833, 1.1785,
           1.2738, 1.3691, 1.4643, 1.5596, 1.6549, 1.7502, 1.8454, 1.9407, 2.036, 2.1313, 2.2265, 2.3218,
           2.4171, 2.5124, 2.56)  # fmt: skip
"""The seed's K_r (``Rotation (Kr)``): above K_t at every power, 1.10-1.65 times it."""
SURFACES = ("wood", "carpet")
MOVING = 100
"""PWM counts of the busiest motors of the motion a turn is added to (0.34 m/s on the axis)."""
TURN_POWERS = (30, 45, 60, 85, 120)
"""Powers of the rotation and of the turn added to it: K_t's knots of the default calibration (12-85)
and one above the motion's own power."""
STILL = 1e-3
"""m/s: a rim speed below this is the friction law's creep (a robot that does not turn)."""
SETTLE_STEPS, AVERAGE_STEPS = 3000, 1000
"""ms to the steady state, and the span whose ends' rates are averaged."""
MOVE_SHIFT, ROTATE_SHIFT = 40, 10
"""OSLL omnibot v0.038's ``CALIBRATION_MOVE_SHIFT`` and ``CALIBRATION_ROTATE_SHIFT``: the counts its
MOVE and its ROTATE add to each driven motor's power, above which each has its own power per mm/s
(0.24 x (1 - 40/255) and 0.19 x (1 - 10/255): the rotation's is 0.90 of the move's)."""
RIM_SPEEDS = (0.3, 0.4, 0.5, 0.6)
"""m/s where both of the seed's from-rest series have data (its slowest full turn is 0.23 m/s)."""


def _pattern(twist: tuple[float, float, float]) -> np.ndarray:
    robot = load_robot("omni4")
    rim = kin.inverse(robot.wheel_matrix, twist)
    pattern = rim / np.abs(rim).max()
    pattern[np.abs(pattern) < 1e-9] = 0.0
    return np.asarray(pattern)


def distances(course_deg: float, powers: list[int], surface: str) -> np.ndarray:
    """m travelled in 1000 ms from rest, the busiest motors at each power (the seed's patterns)."""
    a = math.radians(course_deg)
    pwm = np.outer(powers, _pattern((math.cos(a), math.sin(a), 0.0)))
    ph = Physics(load_robot("omni4"), n=len(powers), surfaces=(surface,))
    ph.run(pwm, 1000)
    return np.asarray(np.hypot(ph.pose[:, 0], ph.pose[:, 1]))


def turn_times(powers: list[int], surface: str, turns: int = 2, limit: float = 10.0) -> np.ndarray:
    """s to complete 1..``turns`` full turns from rest (rows), all four motors at each power; nan if
    not within ``limit``."""
    pwm = np.outer(powers, _pattern((0.0, 0.0, 1.0)))
    ph = Physics(load_robot("omni4"), n=len(powers), surfaces=(surface,))
    out = np.full((turns, len(powers)), np.nan)
    while ph.time < limit and np.isnan(out).any():
        ph.step(pwm)
        angle = np.abs(ph.pose[:, 2])
        for k in range(turns):
            done = np.isnan(out[k]) & (angle >= math.tau * (k + 1))
            out[k][done] = ph.time
    return out


def turn_against_rotation(
    surface: str, moving: int = MOVING, powers: tuple[int, ...] = TURN_POWERS
) -> dict[str, Any]:
    """Seed 000's Fig. 6 statement on the simulated robot itself, no firmware: the steady rim speed
    along R_c (m/s) that each power gives as rotation in place from rest (``rotation``) and as a turn
    added to a robot already moving on course 0 and 45 with its busiest motors at ``moving``
    (``course 0``, ``course 45``: the turn rate it adds, times R_c). Where a power turns the moving
    robot faster than the robot at rest, the seed's K_r lies above its K_t there."""
    rot = _pattern((0.0, 0.0, 1.0))
    ph = Physics(load_robot("omni4"), n=3 * len(powers) + 2, surfaces=(surface,))
    rows = [p * rot for p in powers]
    for course in (0.0, 45.0):
        a = math.radians(course)
        base = moving * _pattern((math.cos(a), math.sin(a), 0.0))
        rows += [base + p * rot for p in powers] + [base]
    pwm = np.array(rows)
    ph.run(pwm, SETTLE_STEPS)
    w = ph.twist[:, 2].copy()
    ph.run(pwm, AVERAGE_STEPS)
    w = (w + ph.twist[:, 2]) / 2  # the rate averaged over the ends of a roller's swing
    n = len(powers)
    out: dict[str, Any] = {"rotation": dict(zip(powers, (R_C * np.abs(w[:n])).tolist(), strict=True))}
    for k, name in enumerate(("course 0", "course 45")):
        block = w[n + k * (n + 1) : n + (k + 1) * (n + 1)]
        out[name] = dict(zip(powers, (R_C * np.abs(block[:n] - block[n])).tolist(), strict=True))
    return out


def measure() -> dict[str, Any]:
    """The three series, simulated on each floor, beside the seed's."""
    out: dict[str, Any] = {"axis": {}, "diagonal": {}, "rotation": {}, "turns": {}}
    for surface in SURFACES:
        out["turns"][surface] = turn_against_rotation(surface)
        p = sorted(AXIS_MM)
        out["axis"][surface] = dict(zip(p, (1000 * distances(0.0, p, surface)).tolist(), strict=True))
        p = sorted(DIAGONAL_MM)
        out["diagonal"][surface] = dict(zip(p, (1000 * distances(45.0, p, surface)).tolist(), strict=True))
        p = sorted(ROTATION_MS)
        times = turn_times(p, surface)
        out["rotation"][surface] = {q: (1000 * times[0, i], 1000 * times[1, i]) for i, q in enumerate(p)}
    return out


def rotation_rate(ms: float, turns: int) -> float:
    """cm/s of wheel path along R_c for ``turns`` full turns in ``ms``."""
    return 100 * turns * math.tau * R_C / (ms / 1000.0)


def least_power(rates: Mapping[int, float], speeds: tuple[float, ...] = RIM_SPEEDS) -> np.ndarray:
    """The least power (counts) of a series of rates (m/s by power) that reaches each speed, linear
    between its powers; nan where its slowest rate is already faster or its fastest is slower."""
    powers = sorted(rates)
    out = np.full(len(speeds), np.nan)
    for k, speed in enumerate(speeds):
        above = [i for i in range(1, len(powers)) if rates[powers[i]] >= speed > rates[powers[i - 1]]]
        if above:
            lo, hi = powers[above[0] - 1], powers[above[0]]
            out[k] = lo + (hi - lo) * (speed - rates[lo]) / (rates[hi] - rates[lo])
    return out


def rotation_against_axis(
    axis_mm: Mapping[int, float], rotation_ms: Mapping[int, tuple[float, float]]
) -> np.ndarray:
    """Rotation's power above the firmware's rotate shift over the axis's above its move shift, at
    each of :data:`RIM_SPEEDS`, read from the seed's experiments from rest as the firmware's tables
    read them (rim speed: mm in 1000 ms on the axis, a full turn's wheel path over its time): rows
    for the first turn and for the second (two turns' time less one's)."""
    axis = least_power({p: mm / 1000.0 for p, mm in axis_mm.items()}) - MOVE_SHIFT
    turns = [{p: rotation_rate(ms[0], 1) / 100 for p, ms in rotation_ms.items()}]
    turns.append({p: rotation_rate(ms[1] - ms[0], 1) / 100 for p, ms in rotation_ms.items()})
    return np.array([(least_power(rates) - ROTATE_SHIFT) / axis for rates in turns])


def seed_rotation_against_axis() -> np.ndarray:
    """:func:`rotation_against_axis` of the seed's workbook, one pair of rows per axis course (0, 90,
    180, 270): the spread of its robot's asymmetry and of its two readings of a turn."""
    courses = [AXIS_MM, *AXIS_OTHER_MM.values()]
    return np.concatenate([rotation_against_axis(mm, ROTATION_MS) for mm in courses])


def simulated_rotation_against_axis(surface: str = "wood", limit: float = 6.0) -> np.ndarray:
    """:func:`rotation_against_axis` of the seed's experiments on the simulated robot (its axis series
    on course 0: the simulated robot is symmetric), every 5 counts from 40 to 230."""
    powers = list(range(40, 231, 5))
    axis = dict(zip(powers, (1000 * distances(0.0, powers, surface)).tolist(), strict=True))
    times = 1000 * turn_times(powers, surface, limit=limit)
    done = [i for i, p in enumerate(powers) if not np.isnan(times[:, i]).any()]
    rotation = {powers[i]: (float(times[0, i]), float(times[1, i])) for i in done}
    return rotation_against_axis(axis, rotation)


def _seed_mean(row: tuple[int | None, ...]) -> float:
    return float(np.mean([v for v in row if v is not None]))


def _mean_error(pairs: list[tuple[float, float]]) -> float:
    """Mean of |simulated / seed - 1| over (simulated, seed) pairs."""
    return float(np.mean([abs(sim / seed - 1.0) for sim, seed in pairs]))


def series_errors(result: dict[str, Any], surface: str) -> dict[str, float]:
    """Mean abs error (a fraction) of each of the seed's series on ``surface``, over all its powers:
    the four axis courses (mm in 1 s), 45 degrees (against the mean of its runs) and rotation's first
    and second full turns (their times)."""
    axis = result["axis"][surface]
    out = {"course 0": _mean_error([(axis[p], mm) for p, mm in AXIS_MM.items()])}
    for course, seed in AXIS_OTHER_MM.items():
        out[f"course {course}"] = _mean_error([(axis[p], mm) for p, mm in seed.items()])
    diagonal = result["diagonal"][surface]
    out["45 degrees"] = _mean_error([(diagonal[p], _seed_mean(runs)) for p, runs in DIAGONAL_MM.items()])
    rotation = result["rotation"][surface]
    for k, name in enumerate(("rotation, 1st turn", "rotation, 2nd turn")):
        out[name] = _mean_error([(rotation[p][k], ms[k]) for p, ms in ROTATION_MS.items()])
    return out


def error_table(result: dict[str, Any]) -> str:
    """Markdown: each series' mean abs error against the seed on each floor (:func:`series_errors`)."""
    errors = {surface: series_errors(result, surface) for surface in SURFACES}
    lines = [
        "| series: mean abs error over the seed's powers | " + " | ".join(SURFACES) + " |",
        "|---|" + "---|" * len(SURFACES),
    ]
    for name in errors[SURFACES[0]]:
        lines.append(f"| {name} | " + " | ".join(f"{100 * errors[s][name]:.1f} %" for s in SURFACES) + " |")
    return "\n".join(lines)


def table(result: dict[str, Any]) -> str:
    """Markdown: per series and power, the seed's value, ours on wood and on carpet, carpet / wood."""
    lines = [
        "| series | power | seed 000 | wood | carpet | carpet / wood |",
        "|---|---|---|---|---|---|",
    ]
    for p in (70, 80, 100, 130, 160, 190, 220, 255):
        w, c = result["axis"]["wood"][p], result["axis"]["carpet"][p]
        lines.append(f"| course 0, mm in 1 s | {p} | {AXIS_MM[p]} | {w:.0f} | {c:.0f} | {c / w:.2f} |")
    for p in (80, 90, 100, 130, 160, 190, 220, 255):
        w, c = result["diagonal"]["wood"][p], result["diagonal"]["carpet"][p]
        lines.append(
            f"| 45 degrees, mm in 1 s | {p} | {_seed_mean(DIAGONAL_MM[p]):.0f} | {w:.0f} | {c:.0f} | {c / w:.2f} |"
        )
    for p in (60, 70, 80, 100, 130, 160, 190, 220, 255):
        w, c = result["rotation"]["wood"][p][0], result["rotation"]["carpet"][p][0]
        lines.append(
            f"| rotation, ms for one turn | {p} | {ROTATION_MS[p][0]} | {w:.0f} | {c:.0f} | {w / c:.2f} |"
        )
    return "\n".join(lines)


def turn_table(result: dict[str, Any]) -> str:
    """Markdown: per floor and power, the rim speed (cm/s along R_c) of rotation in place and of the
    same power added as a turn to a moving robot, and their ratio (K_r / K_t in the seed's terms; "at
    rest": the robot at rest does not turn at that power)."""
    lines = [
        f"| floor | power | rotation from rest | turn added on course 0 / 45 (moving at {MOVING}) | K_r / K_t |",
        "|---|---|---|---|---|",
    ]
    for surface in SURFACES:
        turns = result["turns"][surface]
        for p in TURN_POWERS:
            r, t0, t45 = turns["rotation"][p], turns["course 0"][p], turns["course 45"][p]
            ratio = " / ".join("at rest" if r < STILL else f"{t / r:.2f}" for t in (t0, t45))
            lines.append(f"| {surface} | {p} | {100 * r:.1f} | {100 * t0:.1f} / {100 * t45:.1f} | {ratio} |")
    return "\n".join(lines)


def calibration_tables(path: Path) -> dict[str, dict[str, tuple[list[float], list[float]]]]:
    """{floor: {name: (x, y)}} of a calibration file's floors: its ``k_t`` and ``k_r`` and both in seed
    000's terms (``seed k_t``, ``seed k_r``: the motor map counted in, :mod:`omnibot.calibration.seedterms`;
    K_t at its own powers, for a turn added to a motion at :data:`MOVING`; K_r at both tables')."""
    from omnibot.calibration import load_calibration
    from omnibot.calibration.seedterms import seed_kr, seed_kt

    out = {}
    for floor, spec in load_calibration(path).surfaces.items():
        assert spec.k_t is not None and spec.k_r is not None
        xs = list(spec.k_t.x)
        both = sorted({*xs, *spec.k_r.x})
        out[floor] = {
            "k_t": (xs, list(spec.k_t.y)),
            "k_r": (list(spec.k_r.x), list(spec.k_r.y)),
            "seed k_t": (xs, seed_kt(spec, xs, MOVING)),
            "seed k_r": (both, seed_kr(spec, both)),
        }
    return out


def plot(result: dict[str, Any], target: Path, tables: dict[str, Any] | None) -> None:
    """Fig. 5 (the three series, cm/s against the PWM ratio) and, with a calibration, Fig. 6."""
    from omnibot.plots import new_figure, save

    fig, axes = new_figure(1, 3, size=(16.0, 4.6))
    specs: list[tuple[str, dict[int, Any], Callable[[Any], list[float]], str]] = [
        ("course 0 (two motors)", AXIS_MM, lambda v: [v / 10], "axis"),
        ("45 degrees (four motors)", DIAGONAL_MM, lambda v: [x / 10 for x in v if x is not None], "diagonal"),
        (
            "rotation (four motors, wheel path along R_c)",
            ROTATION_MS,
            lambda v: [rotation_rate(v[0], 1), rotation_rate(v[1], 2)],
            "rotation",
        ),
    ]
    for ax, (title, seed, seed_values, key) in zip(axes[0], specs, strict=True):
        for p, v in sorted(seed.items()):
            ys = seed_values(v)
            ax.plot([p / 255] * len(ys), ys, "ko", ms=3.5, label="seed 000" if p == min(seed) else None)
        for k, surface in enumerate(SURFACES):
            sim = result[key][surface]
            ps = sorted(sim)
            if key == "rotation":
                ys = [rotation_rate(sim[p][0], 1) if math.isfinite(sim[p][0]) else math.nan for p in ps]
            else:
                ys = [sim[p] / 10 for p in ps]
            ax.plot([p / 255 for p in ps], ys, color=f"C{k}", lw=1.5, label=f"simulator, {surface}")
        ax.set_title(title)
        ax.set_xlabel("power (PWM ratio)")
        ax.set_ylabel("cm/s (cm in the first second; rotation: over the turn)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    save(fig, str(target / "seed000_fig5.png"))
    if not tables:
        return
    fig, axes = new_figure(1, 1, size=(7.0, 4.8))
    ax = axes[0][0]
    ax.plot(FIG6_X, FIG6_KT, "k--", label="seed 000: K_t")
    ax.plot(FIG6_X, FIG6_KR, "k-", label="seed 000: K_r")
    for k, (floor, t) in enumerate(sorted(tables.items())):
        for name, style in (("seed k_t", "--"), ("seed k_r", "-"), ("k_r", ":")):
            x, y = t[name]
            label = (
                f"{floor}: " + {"seed k_t": "K_t", "seed k_r": "K_r, offsets in", "k_r": "K_r, table"}[name]
            )
            ax.plot(np.array(x) / 255, y, style, color=f"C{k}", marker=".", label=label)
    ax.set_xlabel("uncalibrated power (PWM ratio)")
    ax.set_ylabel("factor")
    ax.set_ylim(0, 4)
    ax.set_title(
        "K_t and K_r in seed 000's terms (its Fig. 6; ours: omnibot calibrate, default)", fontsize=10
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    save(fig, str(target / "seed000_fig6.png"))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--calibration", type=Path, help="a default `omnibot calibrate`'s file, for Fig. 6")
    parser.add_argument("--plot", type=Path, help="directory for seed000_fig5.png (and seed000_fig6.png)")
    args = parser.parse_args(argv)
    result = measure()
    print(table(result))
    print()
    print(error_table(result))
    print()
    print(turn_table(result))
    tables = calibration_tables(args.calibration) if args.calibration else None
    if tables:
        for floor, t in sorted(tables.items()):
            kt_x, kt_y = t["k_t"]
            kr = np.interp(kt_x, *t["k_r"])
            pairs = ", ".join(f"{x:g}: {r:.3f} / {y:.3f}" for x, r, y in zip(kt_x, kr, kt_y, strict=True))
            print(f"{floor}: the tables' K_r / K_t at K_t's powers: {pairs}")
            skr = np.interp(kt_x, *t["seed k_r"])  # K_t's powers are among its knots
            skt = t["seed k_t"][1]
            pairs = ", ".join(f"{x:g}: {r:.3f} / {y:.3f}" for x, r, y in zip(kt_x, skr, skt, strict=True))
            print(f"{floor}: in seed 000's terms (motor map counted in): {pairs}")
    if args.plot:
        plot(result, args.plot, tables)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
