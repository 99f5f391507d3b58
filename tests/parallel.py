"""How ``make test`` spreads the suite over the machine's cores (pytest-xdist, ``pytest -n N``).

Two passes (the Makefile's ``test``):

1. ``pytest -n 4 -m "not serial"``: the workers take whole **work units**, a unit being a test module
   or one of :data:`GROUPS` (modules that must not run beside each other: one worker runs the unit's
   tests one after another, in their usual order). A module is one unit because its module- and
   session-scoped fixtures (a calibration, a recorded run, a ROS 2 session, a browser) are then made
   once, as in a serial run, not once per worker. A module of :data:`SPLIT` (no such fixtures, and
   tests too costly to run one after another) is a unit per test function instead. The costliest units are handed out first
   (:data:`FIRST`), so that no long one starts last while the other workers idle. Four workers on
   two cores: the two ROS 2 units (:data:`ROS2_HALF`) keep two of them for most of the pass, waiting
   on the wall clock (discovery, real-time bridges) at a sixth of a core each; the other two keep
   both cores busy with everything else meanwhile.
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
    "tests/ros2/test_interrupt.py": "SIGINT to the bridge's exit in wall-clock time (1.2-2.1 s measured,"
    " bounded at 5 s: a loaded worker's teardown must not count)",
    "tests/mapping/test_sampling.py::test_ompl_planners_give_clear_paths": "OMPL's planners search for 0.2 s of"
    " wall-clock time (found no path in it beside three workers at load 25)",
}
"""Modules or tests (node id prefixes) run in the serial pass, and why they need the machine to themselves."""

SPLIT: dict[str, str] = {
    "tests/apps/test_calibrate.py": "each test its own command, no module-scoped fixture; its default runs"
    " of two floors (mecanum4 about 160 s of CPU, omni4 116 s) and quick runs (37, 23 and 7 s) kept one"
    " worker for 343 s of CPU, the longest unit of the pass by far (the rest of it about 500 s on two cores)",
}
"""Modules whose test functions are each a unit of their own (their parametrized cases together), and
why: a test module of more CPU than the pass can spare on one worker, with nothing made once for all
its tests."""

ROS2_HALF: tuple[str, ...] = (
    # the ROS 2 modules' wall time (summed per test, the CPU plugin of BENCHMARKS.md) in one run of the
    # whole first pass on 4 workers, the machine at load 12-21 (2026-12-07, c6303ac): these 590 s
    "test_backends.py",  # 227 s: four operators, each a Python with rclpy in its namespace
    "test_fleet_dds.py",  # 138 s: two robots in one process, each in its namespace
    "test_fleet_hosts.py",  # 130 s: two hosts joined by a veth pair
    "test_rclpy_navigate.py",  # 94 s: navigate_to_pose goes, is pre-empted and cancelled
    "test_goal.py",  # 1 s
    # and the rest 507 s: test_rclpy_goal_pose 294 s (three runs to a goal in the map), test_rclpy_values
    # 56 s, test_rclpy_scan_map 34 s, test_rclpy_interop 30 s, test_rclpy_cmd_vel 27 s, test_clock 25 s,
    # test_cmd_vel 14 s, test_dds 11 s, the others a few s each
)
"""The modules of the first ROS 2 unit, ``ros2/1``; the other modules of tests/ros2 are ``ros2/2``, of
about the same wall time. The two may run side by side: each test's DDS participants live in a private
network namespace with a private ``/dev/shm`` (tests/ros2/netns_helper.py), so the two cannot meet.
No more than two at once: their bridges and peers keep the wall clock's pace (and their waiting is what
the extra workers of ``make test`` fill with other units)."""

GROUPS: dict[str, str] = {
    **{f"tests/ros2/{module}": "ros2/1" for module in ROS2_HALF},
    "tests/ros2/": "ros2/2",
    "tests/web/test_page.py": "browser",
    "tests/web/test_scan_page.py": "browser",
}
"""Path prefix -> work unit (the first prefix that matches): the modules of one unit run on one worker,
one after another (one chromium at a time; two ROS 2 modules at a time at most)."""

FIRST: tuple[str, ...] = (
    # how long each unit kept its worker (pytest --durations, summed) in one run of the first pass on 4
    # workers at load 10-28 (2026-12-06: CPU times were a third to a tenth of these), and CPU s where
    # measured alone
    "ros2/1",  # 590 s, 80 s CPU (2026-12-07, load 12-21); the two ROS 2 units first, on workers of their
    "ros2/2",  # 507 s, 112 s CPU; own, mostly waiting (bridges, peers, namespaces at the wall clock's pace)
    # CPU s in one process (nice'd, load 15-20, 2026-12-06 21:00; mecanum4's from its timeout's comment):
    # SPLIT's module's costliest tests, each a unit of its own
    # (2026-12-07, load 12-21: mecanum4 153 s, omni4 86 s, the quick run 27 s, two floors 17 s)
    "tests/apps/test_calibrate.py::test_the_default_run_on_mecanum4_improves_every_course_and_exits_0",  # 160 s
    "tests/apps/test_calibrate.py::test_the_default_run_on_omni4_improves_every_part_and_exits_0",  # 116 s
    # 81-86 s CPU: one calibration of two floors (its 600 s guard hit at load 25 when the scheduler
    # split the module: three workers made the calibration at once, 254 s of CPU on 2026-12-07)
    "tests/calibration/test_acceptance.py",
    "tests/apps/test_calibrate.py::test_quick_run_writes_the_file_and_the_report",  # 37 s
    "tests/apps/test_calibrate.py::test_a_port_with_two_floors_asks_between_them",  # 23 s
    # the rest: wall on a worker, as above
    "tests/navigation/test_explore.py",  # 189 s
    "tests/uno/test_sketch.py",  # 186 s building its own 4 sketches; 19 s alone (load 8) with make's (2c197b0)
    "tests/apps/test_follow.py",  # 166 s
    "tests/sim/test_jit.py",  # 123-133 s at load 19, about 30 s CPU: a cold start followed through one whole compile
    # bound by the wall clock, not the CPU: the UNO and the Mega in simavr keep its pace (114 s of wall
    # for 16 s of CPU alone at load 2-4, 2026-12-08); dealt among the costly CPU-bound units, whose
    # workers fill the cores while it waits, not among the cheap ones at the end, where it was the
    # last unit running for its last 130 s (one run of the first pass at load 8: 944-1074 s of 1,102)
    "tests/contract/test_sonar_stop.py",
    "tests/navigation/test_runner.py",  # 156 s
    "tests/test_packaging.py",  # 135 s: builds the wheel and sdist, installs into fresh venvs
    "tests/apps/test_goto.py",  # 130 s
    "tests/cli/test_pty.py",  # 125 s
    "tests/navigation/test_slipcal.py",  # 117 s
    "tests/calibration/test_motors.py",  # 104 s
    "tests/cli/test_sim_link.py",  # 82 s
    "tests/benchmarks/test_sim_speed.py",  # 61 s
    "tests/control/test_tracker_heading.py",  # 61 s
    "tests/navigation/test_goto.py",  # 59 s
    "tests/calibration/test_rollers.py",  # 37 s
    "tests/sim/test_emulator.py",  # 36 s at load 13 (its cold start no longer compiles: tests/sim/test_jit.py does)
    "tests/benchmarks/test_attack_suite.py",  # 34 s
    "browser",  # 31 s
    "tests/calibration/test_reachmoves.py",  # 29 s
    "tests/navigation/test_goto_source.py",  # 29 s
    "tests/apps/test_mapping.py",  # 27 s
    # bound by the wall clock too (the pty, MicroPython, UNO and Mega backends run in real time; wall
    # s against CPU s in that run at load 8): before the cheap units, so that none ends the pass
    "tests/contract/test_safety.py",  # 29 s against 3.5
    "tests/contract/test_commands.py",  # 27 s against 2.9
    "tests/contract/test_errors.py",  # 26 s against 3.2
    "tests/uno/test_emulator.py",  # 20 s against 3.6
    "tests/uno/test_hil.py",  # 19 s against 3.1 alone at load 2-4 (21 s against 7.1 in that run)
)
"""The costliest units (CPU or waiting, measured), dealt out first in this order."""


def unit_of(nodeid: str) -> str:
    """The work unit of a test: its group (:data:`GROUPS`), its function in a module of :data:`SPLIT`
    (``path::name``, without the parameters), else its module."""
    path = nodeid.split("::", 1)[0]
    if path in SPLIT:
        return nodeid.split("[", 1)[0]
    return next((group for prefix, group in GROUPS.items() if path.startswith(prefix)), path)


def is_serial(nodeid: str) -> bool:
    return nodeid.startswith(tuple(SERIAL))


def mark_serial(items: Sequence[pytest.Item]) -> None:
    """Mark the tests of :data:`SERIAL` ``serial`` (``-m serial`` / ``-m "not serial"`` select them)."""
    for item in items:
        if is_serial(item.nodeid):
            item.add_marker(pytest.mark.serial)


def scheduler(config: pytest.Config, log: Any, first: Sequence[str] = FIRST) -> Any:
    """xdist's scheduler for ``pytest -n N`` (``--dist load``, the default): whole units, those of
    ``first`` (default :data:`FIRST`) first in its order, the rest in collection order.

    Only the queue of units is reordered, never a collection: a worker runs the tests at the indices
    it is sent in its own collection, in collection order (an earlier version sorted the collection
    the scheduler kept, so every worker ran other tests than the unit dealt to it: chunks of the
    collection order, units split across workers and groups side by side).

    A worker runs a test only once it holds the next one, so xdist deals each worker a second unit at
    the start and another whenever two of its tests are left. Behind a unit of ``first`` that second
    unit is the first one not in ``first``: it would otherwise be the next costly unit, held back for
    as long as the one before it runs (the acceptance calibration waited out mecanum4's default run,
    a single test, on one worker while the others ran cheap modules)."""
    from xdist.scheduler import LoadScopeScheduling

    rank = {unit: i for i, unit in enumerate(first)}

    class UnitScheduling(LoadScopeScheduling):  # type: ignore[misc]
        def __init__(self, config: pytest.Config, log: Any) -> None:
            super().__init__(config, log)
            config.option.loadscopereorder = False  # keep the order given here, not by test count
            self.ranked = False

        def _split_scope(self, nodeid: str) -> str:
            return unit_of(nodeid)

        def _assign_work_unit(self, node: Any) -> None:
            if not self.ranked:  # the queue is complete at the first unit dealt
                units = sorted(self.workqueue.items(), key=lambda unit: rank.get(unit[0], len(rank)))
                self.workqueue.clear()
                self.workqueue.update(units)
                self.ranked = True
            if self.busy_with_a_costly_unit(node):
                cheap = next((unit for unit in self.workqueue if unit not in rank), None)
                if cheap is not None:
                    self.workqueue.move_to_end(cheap, last=False)
            super()._assign_work_unit(node)

        def busy_with_a_costly_unit(self, node: Any) -> bool:
            """Whether ``node`` has tests of a unit of ``first`` still to finish: the unit it is dealt
            now only keeps it fed (a worker runs a test once it holds the next one), and waits behind
            that costly one, so a cheap unit, not the next costly one."""
            work = self.assigned_work.get(node, {})
            return any(unit in rank and not all(tests.values()) for unit, tests in work.items())

    return UnitScheduling(config, log)


if __name__ == "__main__":  # the Makefile's serial pass collects only these (not the whole suite again)
    print(" ".join(sorted(SERIAL)))
