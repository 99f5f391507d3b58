"""The creep geometry in plain Python (omnibot.estimation.creep): what SlipModel's arrays are, against
numpy's least-norm share computed the way the model did before; the slip fit's residual as a
calibration file holds it (SlipError)."""

from __future__ import annotations

import numpy as np
import pytest

from omnibot.errors import ConfigError
from omnibot.estimation.creep import SlipError, creep_rows
from omnibot.estimation.slip import SlipModel
from omnibot.robot import kinematics, load_robot, preset_names


@pytest.mark.parametrize("preset", preset_names())
def test_the_creep_rows_are_the_models_and_lapacks_share(preset: str) -> None:
    robot = load_robot(preset)
    rows = creep_rows(robot)
    model = SlipModel(robot)
    for plain, array in ((rows.roll, model.roll_rows), (rows.rim, model.rim_rows), (rows.mix, model.mix)):
        assert np.array(plain).tolist() == array.tolist()
    traction, roller = kinematics.robot_contact_rows(robot)
    gamma = np.array([w.gamma for w in robot.wheels])
    radius = np.array([w.radius for w in robot.wheels])
    share = np.linalg.pinv(traction.T)
    np.testing.assert_allclose(rows.share, share, atol=1e-15 * np.abs(share).max() * 10)
    np.testing.assert_allclose(rows.mix, (share @ roller.T) / (radius * np.cos(gamma))[:, None], atol=1e-12)
    # the rolling rows are the roller rows plus the wheel's own turn, exactly as the arrays compute them
    expected = roller + (radius * np.sin(gamma) / (radius * np.cos(gamma)))[:, None] * traction
    assert np.array(rows.roll).tolist() == expected.tolist()


def test_a_slip_error_is_the_runs_rms_and_max() -> None:
    error = SlipError.of([0.001, 0.002, 0.002, 0.001])
    assert error.rms == pytest.approx(0.0015811, abs=1e-6) and (error.max, error.runs) == (0.002, 4)
    assert SlipError.from_mapping(error.as_dict()) == error


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"rms": 0.001, "max": 0.002}, "exactly rms, max, runs"),
        ({"rms": 0.001, "max": 0.002, "runs": 3, "mean": 0.001}, "exactly rms, max, runs"),
        ({"rms": "low", "max": 0.002, "runs": 3}, "must be numbers"),
        ({"rms": 0.001, "max": 0.002, "runs": 2.5}, "runs a count"),
        ({"rms": 0.0, "max": 0.002, "runs": 3}, "rms must be a fraction in (0, 1)"),
        ({"rms": 0.003, "max": 0.002, "runs": 3}, "max must be a fraction in [rms, 1)"),
        ({"rms": 0.001, "max": 0.002, "runs": 0}, "runs must be at least 1"),
        ([0.001, 0.002, 3], "expected a mapping"),
    ],
)
def test_a_bad_slip_error_is_a_config_error_naming_its_place(data: object, message: str) -> None:
    with pytest.raises(ConfigError, match=r"^surfaces\.wood\.odometry\.error: ") as info:
        SlipError.from_mapping(data, "surfaces.wood.odometry.error")
    assert message in str(info.value)
