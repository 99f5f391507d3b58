"""Fleet step cost, source trees side by side: :func:`benchmarks.sim_speed.fleet_step_seconds` for
k = 1, 2, 4, 8 robots, in rounds.

Run: ``python -m benchmarks.fleet_speed [--src DIR ...] [--rounds N]``. Each ``--src`` is an omnibot
source tree (``src/`` of a checkout, default this one's; a ``git archive`` of an older commit to
compare). Every round measures each tree in a fresh interpreter, one after the other, so a machine
whose load changes during the run weighs on every tree alike; the figures are each round's (CPU of
the stepping thread per fleet step, best of 5) and, per tree, the median and range over the rounds
of the fleet of 8 over the fleet of 1. Results go in BENCHMARKS.md ("Simulator speed", Fleets).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIZES = (1, 2, 4, 8)

_MEASURE = """
import json, sys
from benchmarks.sim_speed import fleet_step_seconds
print(json.dumps({k: fleet_step_seconds(k, steps=int(sys.argv[1])) for k in (1, 2, 4, 8)}))
"""


def measure(src: Path, steps: int = 1500) -> dict[int, float]:
    """Seconds per step of a fleet of each size in :data:`SIZES`, in a fresh interpreter on ``src``."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join((str(src), str(ROOT))))
    out = subprocess.run(
        [sys.executable, "-c", _MEASURE, str(steps)], env=env, capture_output=True, text=True, check=True
    )
    return {int(k): float(t) for k, t in json.loads(out.stdout.splitlines()[-1]).items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--src",
        type=Path,
        action="append",
        help="an omnibot source tree (repeat it to compare; default ./src)",
    )
    parser.add_argument("--rounds", type=int, default=5, help="rounds, each tree once a round (default 5)")
    parser.add_argument("--steps", type=int, default=1500, help="fleet steps measured a size (default 1500)")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    args = parser.parse_args(argv)
    sources = [s.resolve() for s in args.src or [ROOT / "src"]]
    rounds: dict[str, list[dict[int, float]]] = {str(s): [] for s in sources}
    for r in range(args.rounds):
        for src in sources:
            times = measure(src, args.steps)
            rounds[str(src)].append(times)
            if not args.json:
                us = " / ".join(f"{times[k] * 1e6:.1f}" for k in SIZES)
                print(
                    f"round {r + 1} {src}: {us} us for k = 1 / 2 / 4 / 8, {times[8] / times[1]:.2f} x",
                    flush=True,
                )
    medians = {src: {k: statistics.median(t[k] for t in runs) for k in SIZES} for src, runs in rounds.items()}
    ratios = {src: sorted(round(t[8] / t[1], 2) for t in runs) for src, runs in rounds.items()}
    if args.json:
        summary = {
            src: {
                "median_us": {k: round(m * 1e6, 1) for k, m in medians[src].items()},
                "ratio_8_over_1": ratios[src],
            }
            for src in rounds
        }
        print(json.dumps({"rounds": rounds, "summary": summary}))
        return 0
    for src in rounds:
        low, high = ratios[src][0], ratios[src][-1]
        median = " / ".join(f"{medians[src][k] * 1e6:.1f}" for k in SIZES)
        print(
            f"{src}: median {median} us; fleet of 8 over 1: {low:.2f}-{high:.2f} "
            f"(median {statistics.median(ratios[src]):.2f})"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
