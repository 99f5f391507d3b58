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
    "tests/calibration/test_acceptance.py",  # one calibration of two floors, 60-140 s of CPU
    "ros2",  # bridges, peers and namespaces that wait on the wall clock: minutes of waiting
    "tests/apps/test_calibrate.py",  # three quick calibrations
    "browser",
    "tests/cli/test_pty.py",
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
