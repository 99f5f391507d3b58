"""mixins.py: a class of parts left as it is on CPython, one class without bases on MicroPython."""

from __future__ import annotations

from pathlib import Path

import pytest

from omnibot.firmware import mixins
from omnibot.firmware.config import build_config, stage_board
from omnibot.robot import load_robot
from tests.firmware.test_micropython import run_code


class _State:
    def __init__(self) -> None:
        self.kind = 0

    @property
    def moving(self) -> bool:
        return self.kind != 0


class _Drive(_State):
    def drive(self) -> str:
        self.kind = 1
        return "drive"


class _Brake(_State):
    def brake(self) -> str:
        self.kind = 0
        return "brake"


class _Executor(_Drive, _Brake):
    def step(self) -> str:
        return self.drive() + self.brake()


def test_cpython_keeps_the_class_of_parts() -> None:
    assert mixins.flat(_Executor) is _Executor


def test_micropython_gets_one_class_with_every_part(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(mixins, "MICROPYTHON", True)
    flat = mixins.flat(_Executor)
    assert flat.__bases__ == (object,) and flat.__name__ == "_Executor"
    ex = flat()
    assert ex.step() == "drivebrake" and not ex.moving
    assert ex.drive() == "drive" and ex.moving  # the property came along
    assert {"__init__", "moving", "drive", "brake", "step"} <= set(vars(flat))


def test_a_name_two_parts_define_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    class Other(_State):
        def drive(self) -> str:
            return "other"

    class Both(_Drive, Other):
        pass

    monkeypatch.setattr(mixins, "MICROPYTHON", True)
    with pytest.raises(TypeError, match="drive"):
        mixins.flat(Both)


FLAT_CHECK = """
from omnibot.firmware.controller import Controller
from omnibot.firmware.motion import Executor
for cls, parts in ((Controller, ("handle", "execute", "emit", "state", "_init_state", "poll")),
                   (Executor, ("vel", "_drive", "_land_step", "brake_to_rest", "moving", "step"))):
    names = cls.__dict__
    print(cls.__name__, cls.__bases__ == (object,), all(p in names for p in parts),
          names["__qualname__"] == cls.__name__)
"""


def test_the_board_runs_the_controller_and_executor_as_one_class_each(tmp_path: Path) -> None:
    """Under MicroPython (its unix port) the controller's and the executor's classes have no bases:
    every method and property is found in the class itself, as before they were split."""
    stage = tmp_path / "board"
    stage_board(stage, build_config(load_robot("omni4")))
    proc = run_code(stage, FLAT_CHECK)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split("\n")[:2] == ["Controller True True True", "Executor True True True"]
