"""The creep geometry in plain Python (omnibot.estimation.creep): what SlipModel's arrays are, against
numpy's least-norm share computed the way the model did before."""

from __future__ import annotations

import numpy as np
import pytest

from omnibot.estimation.creep import creep_rows
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
