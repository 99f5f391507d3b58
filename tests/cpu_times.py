"""Where a run of the suite spends its CPU: each test's, and the sum per work unit of tests/parallel.py.

``pytest --cpu-times DIR ...`` (any run, ``-n N`` too: each worker writes its own file) records one
JSON line per test in ``DIR``: its CPU seconds (``getrusage`` of the process and of its children
reaped meanwhile, user and system, from its setup to its teardown: module fixtures count in the
first test that needs them, a session-long child in the test whose teardown reaps it), its wall
seconds, its start (monotonic) and its worker. ``python -m tests.cpu_times DIR [--tests N]`` prints
the units' sums, costliest first, with the N costliest tests.

CPU is what compares between runs on a shared machine; the wall is the load's.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import time
from collections.abc import Generator, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import pytest

from tests import parallel


def cpu_seconds() -> float:
    """User and system CPU of this process and of its reaped children, s."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


@dataclass(frozen=True)
class Record:
    """One test's run."""

    nodeid: str
    cpu: float
    wall: float
    start: float
    worker: str


class Recorder:
    """The plugin ``--cpu-times DIR`` registers: a :class:`Record` per test, appended to
    ``DIR/<worker>-<pid>.jsonl``."""

    def __init__(self, directory: Path) -> None:
        directory.mkdir(parents=True, exist_ok=True)
        self.worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        self.path = directory / f"{self.worker}-{os.getpid()}.jsonl"

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item: pytest.Item) -> Generator[None, object, None]:
        cpu, start = cpu_seconds(), time.monotonic()
        yield
        record = Record(item.nodeid, cpu_seconds() - cpu, time.monotonic() - start, start, self.worker)
        with self.path.open("a", encoding="utf-8") as f:
            f.write(json.dumps(asdict(record)) + "\n")


def read(directory: Path) -> list[Record]:
    """Every record in ``directory``'s files."""
    return [
        Record(**json.loads(line))
        for path in sorted(directory.glob("*.jsonl"))
        for line in path.read_text(encoding="utf-8").splitlines()
        if line.strip()
    ]


@dataclass(frozen=True)
class UnitCost:
    """A work unit's tests summed."""

    unit: str
    cpu: float
    wall: float
    tests: int


def per_unit(records: Sequence[Record]) -> list[UnitCost]:
    """The records summed per work unit (:func:`tests.parallel.unit_of`), costliest CPU first."""
    sums: dict[str, list[float]] = {}
    for r in records:
        total = sums.setdefault(parallel.unit_of(r.nodeid), [0.0, 0.0, 0.0])
        total[0] += r.cpu
        total[1] += r.wall
        total[2] += 1
    units = [UnitCost(unit, cpu, wall, int(n)) for unit, (cpu, wall, n) in sums.items()]
    return sorted(units, key=lambda u: (-u.cpu, u.unit))


def report(records: Sequence[Record], units: int = 40, tests: int = 20) -> str:
    """The ``units`` costliest units and ``tests`` costliest tests, and the whole."""
    lines = [
        f"{len(records)} tests, {sum(r.cpu for r in records):.1f} s of CPU",
        "",
        "CPU s   wall s  tests  unit",
    ]
    lines += [f"{u.cpu:7.1f} {u.wall:7.1f} {u.tests:6d}  {u.unit}" for u in per_unit(records)[:units]]
    lines += ["", "CPU s   wall s  test"]
    costliest = sorted(records, key=lambda r: -r.cpu)[:tests]
    lines += [f"{r.cpu:7.1f} {r.wall:7.1f}  {r.nodeid}" for r in costliest]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.cpu_times", description=__doc__.split("\n")[0])
    parser.add_argument("directory", type=Path, help="the directory given to pytest --cpu-times")
    parser.add_argument("--units", type=int, default=40, help="units listed (default 40)")
    parser.add_argument("--tests", type=int, default=20, help="tests listed (default 20)")
    args = parser.parse_args(argv)
    print(report(read(args.directory), args.units, args.tests))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
