"""tests/cpu_times.py: a test's CPU counts its children's, records sum per work unit."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from dataclasses import asdict
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from tests import conftest, cpu_times
from tests.cpu_times import Record

BURN = "import time\nt = time.process_time()\nwhile time.process_time() - t < {s}: pass\n"


def _burn(seconds: float) -> None:
    start = time.process_time()
    while time.process_time() - start < seconds:
        pass


def test_a_tests_cpu_is_its_own_and_its_reaped_childrens(tmp_path: Path) -> None:
    recorder = cpu_times.Recorder(tmp_path / "times")
    protocol = recorder.pytest_runtest_protocol(SimpleNamespace(nodeid="tests/x.py::t"))  # type: ignore[arg-type]
    next(protocol)  # the test's setup, call and teardown run here
    _burn(0.1)
    subprocess.run([sys.executable, "-c", BURN.format(s=0.3)], check=True)
    with pytest.raises(StopIteration):
        protocol.send(None)
    (record,) = cpu_times.read(tmp_path / "times")
    assert record.nodeid == "tests/x.py::t" and record.worker == recorder.worker
    assert record.cpu >= 0.4 and record.wall >= 0.4
    assert recorder.path.name.startswith(f"{recorder.worker}-")


def test_the_option_registers_the_recorder(tmp_path: Path) -> None:
    registered: list[Any] = []
    options: dict[str, str | None] = {"cpu_times": str(tmp_path / "times")}
    config = SimpleNamespace(
        getoption=options.get,
        pluginmanager=SimpleNamespace(register=lambda plugin, name: registered.append((name, plugin))),
        addinivalue_line=lambda *_: None,
    )
    conftest.pytest_configure(config)  # type: ignore[arg-type]
    assert [name for name, _ in registered] == ["cpu_times"]
    assert isinstance(registered[0][1], cpu_times.Recorder) and (tmp_path / "times").is_dir()
    options["cpu_times"] = None
    conftest.pytest_configure(config)  # type: ignore[arg-type]
    assert len(registered) == 1


def test_records_sum_per_work_unit_costliest_first(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    calibrate = "tests/apps/test_calibrate.py::test_bad_input_exits_2"
    records = [
        Record("tests/robot/test_kinematics.py::test_a", 0.5, 1.0, 0.0, "gw0"),
        Record("tests/robot/test_kinematics.py::test_b[1]", 0.25, 1.0, 1.0, "gw0"),
        Record(f"{calibrate}[a]", 2.0, 3.0, 0.0, "gw1"),  # a SPLIT module: a unit per test function
        Record(f"{calibrate}[b]", 1.0, 3.0, 3.0, "gw1"),
        Record("tests/ros2/test_backends.py::test_x[dds]", 4.0, 30.0, 0.0, "gw2"),  # ROS2_HALF's
        Record("tests/ros2/test_goal.py::test_y", 0.5, 1.0, 30.0, "gw2"),
    ]
    assert cpu_times.per_unit(records) == [
        cpu_times.UnitCost("ros2/1", 4.5, 31.0, 2),
        cpu_times.UnitCost(calibrate, 3.0, 6.0, 2),
        cpu_times.UnitCost("tests/robot/test_kinematics.py", 0.75, 2.0, 2),
    ]
    recorder = cpu_times.Recorder(tmp_path)
    recorder.path.write_text("".join(json.dumps(asdict(r)) + "\n" for r in records), encoding="utf-8")
    assert cpu_times.read(tmp_path) == records
    assert cpu_times.main([str(tmp_path), "--units", "2", "--tests", "1"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "6 tests, 8.2 s of CPU"
    assert out[3].split() == ["4.5", "31.0", "2", "ros2/1"] and out[4].endswith(calibrate)
    assert out[-1].split() == ["4.0", "30.0", "tests/ros2/test_backends.py::test_x[dds]"]
