"""tests/parallel.py names modules by path: a renamed or removed module would silently drop out of its
group, of the units dealt first or of the serial pass. Every name must still be a test module."""

from __future__ import annotations

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
