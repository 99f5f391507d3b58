"""The calibrated reach in the firmware: CAL table 8, and an open-loop MOVE asked faster run at the
reach with WARN 18 (calibration.py's ``reach_at``, motion_commands.py's ``_move``).

The rig's calibration is seed 000's plain form (K = 220 PWM counts per m/s, flat factors): a MOVE at
V cm/s along x gives wheels 2 and 4 ``2.2 V`` counts.
"""

from __future__ import annotations

import math

import pytest

from omnibot.calibration import ACCEPTANCE, load_calibration, perturbed_robot
from omnibot.firmware.config import build_config
from omnibot.firmware.controller import Controller
from omnibot.protocol import codes
from omnibot.robot import ReachSpec, load_robot
from tests.calibration.conftest import sim_client
from tests.firmware.conftest import Rig, make_rig
from tests.firmware.test_progress import DATA, sim_move

REACHED = f"WARN,{codes.W_REACH},{codes.TEXTS[codes.W_REACH]}"
ERROR_38 = f"ERROR,{codes.E_CALIBRATION},{codes.TEXTS[codes.E_CALIBRATION]}"


def reach_rig() -> Rig:
    """The rig with a reach of 60 cm/s on the axes and 40 on the diagonals (45 degrees)."""
    rig = make_rig()
    assert rig.send("CAL,8,0,0,60;CAL,8,1,45,40\n") == ["OK", "OK"]
    return rig


def test_no_reach_by_default_every_move_runs_as_asked() -> None:
    rig = make_rig()
    assert rig.ctrl.calibration.reach_at(0.0) == 0.0
    assert rig.cmd("MOVE,100,100,30,0") == ["OK"]
    assert rig.run(1000) == ["IDLE"]  # 1 m at 1 m/s: 1 s, nothing said


def test_a_move_beyond_the_reach_runs_at_it_and_keeps_its_distance() -> None:
    rig = reach_rig()
    assert rig.cmd("MOVE,100,80,0,0") == ["OK", REACHED]
    assert rig.hal.powers == [0, 132, 0, -132]  # 2.2 x 60 cm/s, not 2.2 x 80
    assert rig.run(1660) == []  # 1 m at 0.6 m/s lasts 1.667 s, not 1.25
    assert rig.run(10) == ["IDLE"]
    # within the reach: as asked, nothing said
    assert rig.cmd("MOVE,100,60,180,0") == ["OK"]
    assert rig.hal.powers == [0, -132, 0, 132]
    assert rig.run(1670) == ["IDLE"]


def test_the_reach_folds_and_interpolates_the_course() -> None:
    rig = reach_rig()
    cal = rig.ctrl.calibration
    assert cal.reach_at(30.0) == pytest.approx(60 - 20 * 30 / 45)
    assert cal.reach_at(60.0) == 40.0  # held beyond the last course (a folded course is not)
    # course 120 folds to 30 (46.7 cm/s: run at 46), backwards too (L < 0)
    assert rig.cmd("MOVE,-100,50,120,0") == ["OK", REACHED]
    a = math.radians(120)
    x, y = -0.46 * math.cos(a), -0.46 * math.sin(a)
    assert rig.hal.powers == [round(220 * y), round(220 * x), -round(220 * y), -round(220 * x)]
    assert rig.run(2170) == []  # 100 / 46 s = 2.174 s
    assert rig.run(10) == ["IDLE"]
    # course 90 folds to 0: 60 cm/s; asked 45: as asked
    assert rig.cmd("MOVE,100,45,90,0") == ["OK"]


def test_delta_repeats_the_move_asked_and_warns_once_a_command() -> None:
    rig = reach_rig()
    assert rig.cmd("MOVE,50,80,0,0") == ["OK", REACHED]
    rig.run(1000)
    assert rig.hal.lines() == []
    assert rig.ctrl.executor.remembered == [50, 80, 0, 0]  # nothing the user gave changed
    assert rig.cmd("DELTA,0,0,0,0,3") == ["OK", REACHED]
    assert rig.run(2600) == ["IDLE"]  # three repetitions of 50 cm at 60 cm/s: 2.5 s, one warning


def test_the_closed_loop_and_an_emptied_reach_run_as_asked() -> None:
    rig = reach_rig()
    assert rig.cmd("MODE,2") == ["OK"]
    assert rig.cmd("MOVE,100,80,0,0") == ["OK"]  # the wheel-speed loop drives: no open-loop reach
    rig.cmd("STOP")
    rig.cmd("MODE,0")
    assert rig.cmd("CAL,8,0,0,0") == ["OK"]  # knot 0 drops the rest: 0 = no reach
    assert rig.cmd("MOVE,100,80,0,0") == ["OK"]


def test_the_reach_is_a_config_key() -> None:
    robot = load_robot("omni4")
    reach = ReachSpec(courses_deg=(0.0, 45.0), speed=(0.9, 0.5))
    assert build_config(robot)["reach"] == [[0.0], [0.0]]  # the presets carry none
    spec = robot.calibration
    assert spec is not None
    cfg = build_config(robot.model_copy(update={"calibration": spec.model_copy(update={"reach": reach})}))
    assert cfg["reach"] == [[0.0, 45.0], [90.0, 50.0]]


def test_acceptance_robot_on_wood_lands_at_its_reach_instead_of_falling_short() -> None:
    """docs/calibration.md, the reach: after wood's own calibration the acceptance robot's 1 m MOVEs at
    0.81 m/s on courses 30 and 60 fall 12 % short one way (the drivers' current limit, WARN 17). With
    the reach the calibration drove for those tables the controller runs them at the reach and they
    land, with WARN 18 alone; the axis course keeps its speed."""
    spec = load_calibration(DATA / "omni4_acceptance_wood_calibration.yaml").for_surface("wood")
    reach = ReachSpec(courses_deg=(0.0, 15.0, 30.0, 45.0), speed=(0.9, 0.81, 0.66, 0.78))
    nominal = load_robot("omni4")
    with sim_client(nominal, "wood", true_robot=perturbed_robot(nominal, ACCEPTANCE), seed=3) as client:
        client.upload_calibration(spec.model_copy(update={"reach": reach}))
        assert client.takes_reach is True
        for course in (30.0, 60.0):
            got = sim_move(client, course, 0.81)
            assert got.warnings == {codes.W_REACH}
            assert got.distance == pytest.approx(1.0, abs=0.03)
        axis = sim_move(client, 0.0, 0.9)
        assert axis.warnings == set() and axis.distance == pytest.approx(1.0, abs=0.03)


def test_a_controller_without_the_reach_takes_the_rest(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """Older firmware and the UNO's answer CAL table 8 with ERROR 38: the tables go in, the client says
    once that MOVEs beyond the reach run as asked."""
    old_cal = Controller._cal

    def older(self: Controller, table: int, index: int, x: int, y: int) -> bool:
        return table != codes.CAL_REACH and old_cal(self, table, index, x, y)

    monkeypatch.setattr(Controller, "_cal", older)
    robot = load_robot("omni4")
    spec = robot.calibration
    assert spec is not None
    reach = ReachSpec(courses_deg=(0.0, 45.0), speed=(0.9, 0.5))
    with sim_client(robot, "wood") as client:
        client.upload_calibration(spec)  # no reach: nothing to say
        assert client.takes_reach is False and not caplog.records
        with caplog.at_level("WARNING", logger="omnibot.client"):
            client.upload_calibration(spec.model_copy(update={"reach": reach}))
        assert [r.getMessage() for r in caplog.records] == [
            "the controller does not know the calibrated reach (CAL table 8): MOVEs faster than it run "
            "as asked and may fall short"
        ]
        assert client.status().state == codes.STATE_IDLE


def test_rejected_reach_knots() -> None:
    rig = make_rig()
    for bad in ("CAL,8,0,91,50", "CAL,8,0,-1,50", "CAL,8,0,0,-5", "CAL,8,1,0,50"):
        assert rig.cmd(bad) == [ERROR_38], bad
    assert rig.send("CAL,8,0,10,50;CAL,8,1,10,40\n") == ["OK", ERROR_38]  # courses must increase
