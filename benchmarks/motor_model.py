"""What the two-number motor model can do, against what the calibration's fit finds (issue 17).

    python -m benchmarks.motor_model [--surface carpet] [--map fit|table|gain|model] [--no-stand]
                                     [--wheels N] [--seed 3]

Calibrates omni4 with the acceptance perturbation (wheel radius +5 %, torque constants +10, -10, -10,
+10 %) on one floor, as tests/calibration/test_acceptance.py does (seed 3, ``Plan(levels=7)``, 1 m
MOVEs at 0.3, 0.6 and 0.9 m/s on courses 0..90 and back), with the motor map

* ``fit``: as ``omnibot calibrate`` fits it (motors.py: the stand test's torque constants, then one
  gain per motor with its speed term tied to it, from the balance runs);
* ``gain``: each motor's true gain 1/s, one constant per motor, no speed term;
* ``model``: the true two-number model, gain 1/s and speed term (s - 1/s) E (E from the description);
* ``table``: the map before the stand test: each balance power's gains fitted alone, a gain table
  over power per motor, no speed terms (implies ``--no-stand``).

``--no-stand``: the calibration as on a robot nobody lifts (``omnibot calibrate --port ... --yes``):
no stand test, so the fit gives one constant gain per motor and no speed terms. ``--wheels N``: the
wheels start at angles drawn with seed N (0: all at 0, as the acceptance test), i.e. every run begins
with the rollers somewhere else; the simulator's ``--seed`` only moves the sensors' noise, which these
runs do not read, so the wheels are what makes two runs differ.

The known maps replace the balance fit's outcome (its runs still measure the speeds the host's
patterns need at every power; the offsets are measured as always, the stand test runs but is not
used). Prints the check's summary, the floor's reach and
every MOVE within it. A few minutes of CPU per run.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterator, Sequence
from contextlib import AbstractContextManager, contextmanager

import numpy as np

from omnibot.calibration import (
    ACCEPTANCE,
    AccuracyPlan,
    Plan,
    accuracy_entries,
    motors,
    parse_perturbation,
    perturbed_robot,
    session,
    summary_table,
)
from omnibot.calibration.accuracy import describe_reach, within_reach
from omnibot.calibration.motorfit import Balance, Stand, emf_counts
from omnibot.calibration.motors import balance_model
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.runner import Runner
from omnibot.client import RobotClient
from omnibot.robot import RobotDescription, load_robot
from omnibot.sim import SimDevice
from omnibot.transport import LockstepLink

SEED = 3


def known_map(kind: str) -> Callable[..., Balance]:
    """A replacement of :func:`omnibot.calibration.motors.balance_model` giving the true motors' map."""

    def balance(
        runner: Runner,
        offsets: Sequence[float],
        powers: Sequence[int],
        k: float,
        durations: Sequence[float] | None = None,
        folded: Sequence[float] | None = None,
        stand: Stand | None = None,
    ) -> Balance:
        result = balance_model(runner, offsets, powers, k, durations, folded)
        s = np.array(parse_perturbation(ACCEPTANCE, runner.geometry.motors)["torque_constant"])
        result.log_gains = [[float(v) for v in np.log(1.0 / s)]] * len(result.powers)
        if kind == "model":
            emf = np.array(emf_counts(runner.robot))
            result.speed = [round(float(v), 1) for v in (s - 1.0 / s) * emf]
        return result

    return balance


def table_map(
    runner: Runner,
    offsets: Sequence[float],
    powers: Sequence[int],
    k: float,
    durations: Sequence[float] | None = None,
    folded: Sequence[float] | None = None,
    stand: Stand | None = None,
) -> Balance:
    """A replacement of :func:`omnibot.calibration.motors.balance_model` fitting each power's gains
    alone (a gain table over power per motor, no speed terms: the map before the stand test)."""
    out = Balance()
    for j, power in enumerate(powers):
        one = balance_model(runner, offsets, [power], k, [durations[j]] if durations else None, folded)
        out.powers += one.powers
        out.log_gains += one.log_gains
        out.before += one.before
        out.after += one.after
        out.rates += one.rates
    return out


def main(argv: list[str] | None = None) -> int:
    """Run one calibration and print its check."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.motor_model", description=__doc__.split("\n")[0])
    ap.add_argument("--surface", default="carpet", choices=["wood", "carpet"])
    ap.add_argument("--map", default="model", choices=["fit", "table", "gain", "model"])
    ap.add_argument("--no-stand", action="store_true", help="no stand test (a robot nobody lifts)")
    ap.add_argument("--wheels", type=int, default=0, help="seed of the wheels' start angles (0: all at 0)")
    ap.add_argument("--seed", type=int, default=SEED, help="the simulator's seed")
    args = ap.parse_args(argv)
    nominal = load_robot("omni4")
    true = perturbed_robot(nominal, ACCEPTANCE)
    replaced = {"balance_model": balance_model, "simulator_lift": motors.simulator_lift}
    if args.map in ("gain", "model"):
        motors.__dict__["balance_model"] = known_map(args.map)  # the motor map step's fit, replaced
    elif args.map == "table":
        motors.__dict__["balance_model"] = table_map
    if args.no_stand or args.map == "table":
        motors.__dict__["simulator_lift"] = lambda client: None  # nobody lifts the robot
    try:
        return run(nominal, true, args.surface, args.map, args.seed, args.wheels)
    finally:
        motors.__dict__.update(replaced)


def lockstep_clients(
    nominal: RobotDescription, true: RobotDescription, seed: int, wheels: int
) -> Callable[[str], AbstractContextManager[RobotClient]]:
    """``open_client(surface)`` for :func:`omnibot.calibration.session.calibrate`: the lockstep
    simulator of ``true`` driven as ``nominal``, its wheels started at angles drawn with seed
    ``wheels`` (0: all at 0)."""

    @contextmanager
    def open_client(surface: str) -> Iterator[RobotClient]:
        dev = SimDevice(nominal, true_robot=true, surface=surface, seed=seed)
        if wheels:  # the wheels turned before the calibration starts (the counts show it)
            angles = dev.sim.physics.wheel_angle
            angles[0, :] = np.random.default_rng(wheels).uniform(0.0, 2 * np.pi, angles.shape[1])
        with RobotClient(LockstepLink(dev), nominal) as client:
            yield client

    return open_client


def run(
    nominal: RobotDescription, true: RobotDescription, surface_name: str, kind: str, seed: int, wheels: int
) -> int:
    """Calibrate on ``surface_name`` and print the check (:func:`main`)."""
    open_client = lockstep_clients(nominal, true, seed, wheels)

    result = session.calibrate(
        nominal,
        [surface_name],
        open_client,
        truth="sim",
        plan=Plan(levels=7),
        accuracy=AccuracyPlan(speeds=(0.3, 0.6, 0.9)),
    )
    s = result.sessions[0]
    runs = s.runs
    print(f"motor map ({kind}): {s.spec.motors}")
    print(
        f"{len(runs)} runs, {sum(r.duration for r in runs):.0f} s of commanded motion (the checks included)"
    )
    print(summary_table(accuracy_entries(result)))
    fold = Geometry.of(nominal).fold
    table = s.spec.reach
    moves = [r for r in s.after or [] if r.kind == "move"]
    within = (
        [r for r in moves if within_reach(r, table, fold)]
        if table is not None
        else [r for r in moves if r.speed <= (s.reach or 0.0)]
    )
    if not within:
        print("no MOVE of the check within the calibration's reach")
        return 1
    errors = [abs(r.error or 0.0) for r in within]
    courses = [abs(r.course_error_deg) for r in within if r.course_error_deg is not None]
    per_course = describe_reach(table) if table is not None else "every course"
    print(
        f"reach {s.reach or 0.0:.2f} m/s ({per_course}): {len(within)} MOVEs within it, distance error max "
        f"{100 * max(errors):.1f} %, mean {100 * sum(errors) / len(errors):.1f} %"
        + (f"; course error mean {sum(courses) / len(courses):.1f} deg" if courses else "")
    )
    beyond = [abs(r.error or 0.0) for r in moves if r not in within]
    if beyond:
        print(f"beyond it (run at the reach, warning 18): {len(beyond)} MOVEs, max {100 * max(beyond):.1f} %")
    for r in within:
        print(f"  course {r.course_deg:5.1f} at {r.speed:.2f} m/s: {100 * (r.error or 0.0):+5.1f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
