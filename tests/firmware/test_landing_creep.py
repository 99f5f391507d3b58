"""The floor's creep in the closed-loop landing (landing.py): the creep terms against the host's slip
model (``ramp`` on a MOVE's ramp too), CAL table 9, and the client's upload of it (older
controllers included)."""

from __future__ import annotations

import numpy as np
import pytest

from omnibot.client import CalibrationRejected, RobotClient, commands
from omnibot.estimation import SlipModel, SlipParameters
from omnibot.firmware.config import build_config
from omnibot.firmware.controller import Controller
from omnibot.firmware.landing import Landing
from omnibot.protocol import codes
from omnibot.protocol.messages import Cal
from omnibot.robot import load_robot
from tests.firmware.conftest import make_rig


@pytest.mark.parametrize("robot", ["omni4", "omni3", "mecanum4"])
def test_the_creep_is_the_host_slip_models(robot: str) -> None:
    description = load_robot(robot)
    params = SlipParameters(roll=0.012, combined=0.04)
    cfg = build_config(description, slip=params)
    assert cfg["slip"] == [0.012, 0.04, 1.0, 0.0]
    land = Landing(cfg)
    host = SlipModel(description, params)
    out = [0.0] * description.n_wheels
    for twist in ((0.3, 0.0, 0.0), (0.2, -0.4, 0.0), (0.0, 0.0, 2.0), (0.1, 0.25, -1.2)):
        assert land.overturn(*twist, out)
        assert out == pytest.approx(list(host.wheel_correction(twist)), abs=1e-6)
    assert not Landing(build_config(description)).overturn(0.3, 0.0, 0.0, out)  # no coefficients: none
    assert Landing({**cfg, "slip": [0.012, 0.04, 1.0]}).slip == [
        0.012,
        0.04,
        1.0,
        0.0,
    ]  # before the ramp term


@pytest.mark.parametrize("robot", ["omni4", "omni3", "mecanum4"])
def test_a_moves_ramp_creeps_as_the_host_models_it(robot: str) -> None:
    """On a MOVE's ramp the drag creeps more by ``ramp`` times the plan's rate squared (the host's
    ramp term at the body's acceleration); a ROTATE's rate, an angular one, adds none."""
    description = load_robot(robot)
    params = SlipParameters(roll=0.004, combined=0.02, ramp=0.0008)
    land = Landing(build_config(description, slip=params))
    host = SlipModel(description, params)
    out = [0.0] * description.n_wheels
    land.rate = 1.25  # m/s^2 along the MOVE: (0.6, 0.8) per unit of its speed
    assert land.overturn(0.18, 0.24, 0.0, out)
    ramping = host.wheel_correction((0.18, 0.24, 0.0), (0.75, 1.0, 0.0))
    assert out == pytest.approx(list(ramping), abs=1e-6)
    assert np.abs(ramping - host.wheel_correction((0.18, 0.24, 0.0))).max() > 0.01 * np.abs(ramping).max()
    land.rotate = True
    assert land.overturn(0.18, 0.24, 0.0, out)
    assert out == pytest.approx(list(host.wheel_correction((0.18, 0.24, 0.0))), abs=1e-6)


def test_cal_table_9_sets_the_floors_creep() -> None:
    rig = make_rig()
    land = rig.ctrl.executor.landing
    assert land.slip == [0.0, 0.0, 1.0, 0.0]
    assert rig.cmd("CAL,9,0,0,1551;CAL,9,1,0,408;CAL,9,2,0,10300;CAL,9,3,0,770") == ["OK"] * 4
    assert land.slip == pytest.approx([0.01551, 0.0408, 1.03, 0.00077])
    bad = f"ERROR,{codes.E_CALIBRATION},{codes.TEXTS[codes.E_CALIBRATION]}"
    for command in (
        "CAL,9,0,0,-1",
        "CAL,9,2,0,5000",
        "CAL,9,2,0,20000",
        "CAL,9,3,0,-1",
        "CAL,9,4,0,1",
        "CAL,9,0,1,5",
    ):
        assert rig.cmd(command) == [bad], command
    assert land.slip == pytest.approx([0.01551, 0.0408, 1.03, 0.00077])


def test_the_client_uploads_the_floors_creep(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    params = SlipParameters(roll=0.015514, combined=0.040821, scale=1.0, ramp=0.000768)
    assert commands.slip(params) == [
        Cal(codes.CAL_SLIP, 0, 0, 1551),
        Cal(codes.CAL_SLIP, 1, 0, 408),
        Cal(codes.CAL_SLIP, 2, 0, 10000),
        Cal(codes.CAL_SLIP, 3, 0, 768),
    ]
    with RobotClient.open("sim://omni4?seed=1") as client:
        assert client.upload_slip(params)
        device = client.link.device  # type: ignore[attr-defined]
        assert device.controller.executor.landing.slip == pytest.approx([0.01551, 0.0408, 1.0, 0.000768])
    # older firmware and the UNO's answer ERROR 38: said once, nothing else fails
    old_cal = Controller._cal

    def older(self: Controller, table: int, index: int, x: int, y: int) -> bool:
        return table != codes.CAL_SLIP and old_cal(self, table, index, x, y)

    monkeypatch.setattr(Controller, "_cal", older)
    with (
        RobotClient.open("sim://omni4?seed=1") as client,
        caplog.at_level("WARNING", logger="omnibot.client"),
    ):
        assert not client.upload_slip(params)
        assert client.status().state == codes.STATE_IDLE
    assert [r.getMessage() for r in caplog.records] == [
        "the controller does not know the floor's creep (CAL table 9): not uploaded"
    ]


def test_a_controller_older_than_the_ramp_term_takes_none_and_refuses_one(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    old_cal = Controller._cal

    def older(self: Controller, table: int, index: int, x: int, y: int) -> bool:
        return not (table == codes.CAL_SLIP and index == 3) and old_cal(self, table, index, x, y)

    monkeypatch.setattr(Controller, "_cal", older)
    with RobotClient.open("sim://omni4?seed=1") as client:
        assert client.upload_slip(
            SlipParameters(roll=0.0068, combined=0.027)
        )  # no ramp: as that controller does
        with pytest.raises(CalibrationRejected, match=r"creep under a ramp \(CAL table 9, index 3\)"):
            client.upload_slip(SlipParameters(roll=0.0036, ramp=0.00077))
