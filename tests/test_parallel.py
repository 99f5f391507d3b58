"""tests/parallel.py names modules by path: a renamed or removed module would silently drop out of its
group, of the units dealt first or of the serial pass. Every name must still be a test module."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tests import parallel

ROOT = Path(__file__).resolve().parents[1]


def test_every_module_named_exists() -> None:
    named = [*parallel.SERIAL, *(f"tests/ros2/{m}" for m in parallel.ROS2_HALF), *parallel.GROUPS]
    named += [unit for unit in parallel.FIRST if unit not in set(parallel.GROUPS.values())]
    named += list(parallel.SPLIT)
    missing = [path for path in named if not (ROOT / path.split("::")[0]).exists()]
    assert not missing, missing
    # a test named by its function (a unit of a SPLIT module, or a serial test) is still defined there
    tests = [name for name in named if "::" in name]
    assert tests
    gone = [n for n in tests if f"def {n.split('::')[1]}(" not in (ROOT / n.split("::")[0]).read_text()]
    assert not gone, gone


def test_a_split_module_makes_nothing_once_for_its_tests() -> None:
    """Its tests run on different workers: a module-scoped fixture there would be made once per worker."""
    for path in parallel.SPLIT:
        assert "scope=" not in (ROOT / path).read_text(), path


def test_the_ros2_modules_are_in_two_units_and_others_are_their_own() -> None:
    ros2 = {parallel.unit_of(f"tests/ros2/{p.name}::t") for p in (ROOT / "tests/ros2").glob("test_*.py")}
    assert ros2 == {"ros2/1", "ros2/2"}
    assert parallel.unit_of("tests/ros2/test_backends.py::t[x]") == "ros2/1"
    assert parallel.unit_of("tests/ros2/test_clock.py::t") == "ros2/2"
    assert parallel.unit_of("tests/web/test_page.py::t") == "browser"
    assert parallel.unit_of("tests/apps/test_follow.py::t") == "tests/apps/test_follow.py"
    assert parallel.unit_of("tests/apps/test_calibrate.py::t[x-y]") == "tests/apps/test_calibrate.py::t"
    assert set(parallel.FIRST) >= {"ros2/1", "ros2/2", "browser"} and len(set(parallel.FIRST)) == len(
        parallel.FIRST
    )


CONFTEST = """
from tests import parallel

def pytest_xdist_make_scheduler(config, log):
    return parallel.scheduler(config, log, first={first!r})
"""

MODULE = """
import os
import pytest

@pytest.mark.parametrize("k", range({n}))
def test_{name}(k):
    with open("ran.txt", "a") as f:
        f.write(os.environ["PYTEST_XDIST_WORKER"] + " {name}\\n")
"""


def run_units(tmp_path: Path, tests: dict[str, int], first: tuple[str, ...]) -> list[tuple[str, str]]:
    """pytest on two workers over modules ``test_NAME.py`` of ``tests[NAME]`` tests each, the modules
    ``first`` dealt first: (worker, module name) of each test in the order each worker ran them."""
    (tmp_path / "conftest.py").write_text(CONFTEST.format(first=first))
    for name, n in tests.items():
        (tmp_path / f"test_{name}.py").write_text(MODULE.format(name=name, n=n))
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}  # not this worker's
    env["PYTHONPATH"] = str(ROOT)
    command = [sys.executable, "-m", "pytest", "-q", "-n", "2", "-p", "no:cacheprovider"]
    done = subprocess.run(
        command, check=False, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stdout + done.stderr
    ran = [line.split() for line in (tmp_path / "ran.txt").read_text().splitlines()]
    assert sorted(name for _, name in ran) == sorted(name for name, n in tests.items() for _ in range(n))
    return [(worker, name) for worker, name in ran]


def test_the_workers_run_the_units_dealt_first_whole(tmp_path: Path) -> None:
    """Two workers, modules of 2, 3 and 4 tests (their units), c and b dealt first: each worker's first
    tests are c's or b's, and every module runs on one worker. (The scheduler once sorted its copy of
    the collection: the workers ran the tests at those indices of their own, unsorted, collection: a's
    and b's where c's were dealt, b split over both workers.)"""
    ran = run_units(tmp_path, {"a": 2, "b": 3, "c": 4}, first=("test_c.py", "test_b.py"))
    workers = {name: {w for w, m in ran if m == name} for name in "abc"}
    assert all(len(w) == 1 for w in workers.values()), ran
    first = {w: next(m for v, m in ran if v == w) for w, _ in ran}
    assert sorted(first.values()) == ["b", "c"], ran


def test_no_costly_unit_waits_behind_another_on_one_worker(tmp_path: Path) -> None:
    """Costly single tests c, b and e, cheap modules a and d of three tests: each worker starts on c or
    b and is dealt a cheap module behind it, and e goes to the first worker done with its costly test.
    (xdist dealt each worker's second unit from the front of the queue: e behind c on one worker, to
    start only when c ended, as the acceptance calibration waited out mecanum4's default run.)"""
    ran = run_units(
        tmp_path, {"a": 3, "b": 1, "c": 1, "d": 3, "e": 1}, first=("test_c.py", "test_b.py", "test_e.py")
    )
    for worker in {w for w, _ in ran}:
        units = [m for w, m in ran if w == worker]
        order = [m for k, m in enumerate(units) if k == 0 or units[k - 1] != m]
        assert order[0] in "bc" and order[1] in "ad", ran
