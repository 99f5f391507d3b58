"""How ``make test`` spreads the suite over the machine's cores (pytest-xdist, ``pytest -n N``).

Two passes (the Makefile's ``test``):

1. ``pytest -n 2 -m "not serial"``: the workers take whole **work units**, a unit being a test module
   or one of :data:`GROUPS` (modules that must not run beside each other: one worker runs the unit's
   tests one after another, in their usual order). A module is one unit because its module- and
   session-scoped fixtures (a calibration, a recorded run, a ROS 2 session, a browser) are then made
   once, as in a serial run, not once per worker. The costliest units are handed out first
   (:data:`FIRST`), so that no long one starts last while the other worker idles.
2. ``pytest -m serial``: the modules of :data:`SERIAL`, alone on the machine, in one process.

A test that must not share the machine (it measures wall-clock time that a busy neighbour would
stretch) goes into :data:`SERIAL`; tests that must not share something with each other (a fixed port,
a file outside their ``tmp_path``, a process-wide resource) go into one group of :data:`GROUPS`.
Session-scoped fixtures that build something outside ``tmp_path`` must be safe when two workers start
at once (a file lock: ``omnibot.uno.emulator``'s build, ``tests/logs/conftest.py``'s readers), or be
built by the Makefile before pytest starts (the simulator's kernels, the UNO images).

``pytest`` without ``-n`` runs everything in one process, in collection order, as before: the way to
debug a test.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import pytest

SERIAL: dict[str, str] = {
    "tests/uno/test_line_rate.py": "streams VELs at 115200 baud of wall-clock time: whether the emulated UNO keeps up",
    "tests/ros2/test_bridge_dds.py": "cmd_vel at 20 Hz of wall-clock time, judged by the robot's top speed and stop"
    " (0.23 m/s for 0.2 beside another worker at load 15)",
}
"""Modules (path prefixes) run in the serial pass, and why they need the machine to themselves."""

GROUPS: dict[str, str] = {
    "tests/ros2/": "ros2",
    "tests/web/test_page.py": "browser",
    "tests/web/test_scan_page.py": "browser",
}
"""Path prefix -> work unit: the modules of one unit run on one worker, one after another (one
chromium at a time; one private network namespace with DDS at a time)."""

FIRST: tuple[str, ...] = (
    # measured 2026-12-06 under pytest -n 2 (CPU s, and wall s at load 12-17: how long a worker is busy)
    "ros2",  # 104 s, 442 s: bridges, peers and namespaces that wait on the wall clock
    "tests/calibration/test_acceptance.py",  # 81 s, 313 s: one calibration of two floors
    "tests/apps/test_calibrate.py",  # 49 s, 305 s: three quick calibrations
    "tests/cli/test_pty.py",  # 24 s, 165 s
    "tests/navigation/test_runner.py",  # 26 s, 159 s
    "tests/navigation/test_explore.py",  # 20 s, 123 s
    "tests/uno/test_sketch.py",  # 16 s, 118 s: arduino-mk builds
    "tests/contract/test_sonar_stop.py",  # 21 s, 111 s
    "tests/navigation/test_slipcal.py",  # 17 s, 94 s
    "tests/navigation/test_goto.py",  # 16 s, 90 s
    "tests/apps/test_follow.py",  # 24 s, 79 s
    "tests/logs/test_bounded.py",  # 12 s, 73 s
    "tests/sim/test_emulator.py",  # 25 s, 61 s
    "browser",  # 13 s, 52 s
)
"""The costliest units (CPU or waiting, measured), dealt out first in this order."""


def unit_of(nodeid: str) -> str:
    """The work unit of a test: its group (:data:`GROUPS`), else its module."""
    path = nodeid.split("::", 1)[0]
    return next((group for prefix, group in GROUPS.items() if path.startswith(prefix)), path)


def is_serial(nodeid: str) -> bool:
    return nodeid.startswith(tuple(SERIAL))


def mark_serial(items: Sequence[pytest.Item]) -> None:
    """Mark the tests of :data:`SERIAL` ``serial`` (``-m serial`` / ``-m "not serial"`` select them)."""
    for item in items:
        if is_serial(item.nodeid):
            item.add_marker(pytest.mark.serial)


def scheduler(config: pytest.Config, log: Any) -> Any:
    """xdist's scheduler for ``pytest -n N`` (``--dist load``, the default): whole units, costliest first."""
    from xdist.scheduler import LoadScopeScheduling

    rank = {unit: i for i, unit in enumerate(FIRST)}

    class UnitScheduling(LoadScopeScheduling):  # type: ignore[misc]
        def __init__(self, config: pytest.Config, log: Any) -> None:
            super().__init__(config, log)
            config.option.loadscopereorder = False  # keep the order given here, not by test count

        def _split_scope(self, nodeid: str) -> str:
            return unit_of(nodeid)

        def add_node_collection(self, node: Any, collection: Sequence[str]) -> None:
            ordered = sorted(collection, key=lambda nodeid: rank.get(unit_of(nodeid), len(rank)))
            super().add_node_collection(node, ordered)

    return UnitScheduling(config, log)


if __name__ == "__main__":  # the Makefile's serial pass collects only these (not the whole suite again)
    print(" ".join(sorted(SERIAL)))
