"""The plain-Python kinematics (omnibot.robot.rows) against numpy's LAPACK: the same wheel rows bit for
bit, singular values and pseudo-inverses to rounding, rank-deficient layouts refused and inverted
least-norm."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.errors import KinematicsError
from omnibot.robot import kinematics, load_robot, preset_names, rows

PRESETS = preset_names()


@pytest.mark.parametrize("preset", PRESETS)
def test_the_rows_are_the_arrays_bit_for_bit(preset: str) -> None:
    robot = load_robot(preset)
    wheels = robot.wheels
    J = kinematics.wheel_rows(
        [w.position for w in wheels],
        [w.drive_angle for w in wheels],
        [w.gamma for w in wheels],
        [w.radius for w in wheels],
    )
    assert J.tolist() == [list(r) for r in robot.inverse_rows]
    traction, roller = kinematics.contact_rows(
        np.array([w.position[0] for w in wheels]),
        np.array([w.position[1] for w in wheels]),
        np.array([w.drive_angle for w in wheels]),
        np.array([w.gamma for w in wheels]),
    )
    plain = rows.robot_contact_rows(robot)
    assert (traction.tolist(), roller.tolist()) == ([list(r) for r in plain[0]], [list(r) for r in plain[1]])


def test_contact_rows_broadcast_over_any_shape() -> None:
    x = np.linspace(-0.2, 0.2, 6).reshape(2, 3)
    traction, roller = kinematics.contact_rows(x, 0.1, 0.3, np.array([0.0, math.pi / 4, -math.pi / 4]))
    assert traction.shape == roller.shape == (2, 3, 3)
    assert traction[1, 2].tolist() == list(rows.contact_row(float(x[1, 2]), 0.1, 0.3, -math.pi / 4).traction)
    empty = kinematics.contact_rows(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0))
    assert empty[0].shape == empty[1].shape == (0, 3)


@pytest.mark.parametrize("preset", PRESETS)
def test_the_least_squares_inverse_is_lapacks_to_rounding(preset: str) -> None:
    robot = load_robot(preset)
    J = np.array(robot.inverse_rows)
    np.testing.assert_allclose(
        np.array(robot.forward_rows), np.linalg.pinv(J), rtol=0, atol=1e-15 * np.abs(J).max()
    )
    np.testing.assert_allclose(
        rows.singular_values(robot.inverse_rows), np.linalg.svd(J, compute_uv=False), rtol=1e-14
    )
    np.testing.assert_array_equal(kinematics.forward_matrix(robot), np.array(robot.forward_rows))


@pytest.mark.parametrize("shape", [(3, 3), (4, 3), (6, 3), (2, 3), (5, 2)])
def test_svd_and_pseudo_inverse_of_ill_conditioned_matrices(shape: tuple[int, int]) -> None:
    rng = np.random.default_rng(7)
    for _ in range(50):
        A = rng.normal(size=shape) * np.logspace(0, -6, shape[1])  # condition numbers up to 1e6
        u, s, v = rows.svd(A.tolist())
        np.testing.assert_allclose(np.array(u) @ np.diag(s) @ np.array(v).T, A, atol=1e-14)
        np.testing.assert_allclose(np.array(v).T @ np.array(v), np.eye(shape[1]), atol=1e-14)
        assert list(s) == sorted(s, reverse=True)
        expected = np.linalg.pinv(A)
        np.testing.assert_allclose(
            rows.pseudo_inverse(A.tolist()), expected, atol=1e-9 * np.abs(expected).max()
        )


def test_a_rank_deficient_layout_is_refused_and_inverted_least_norm() -> None:
    # three wheels pushing along x (rank 2): y is not reachable
    J = [(1.0, 0.0, 0.1), (1.0, 0.0, -0.1), (1.0, 0.0, 0.0)]
    with pytest.raises(KinematicsError, match="constrain only 2 of the 3"):
        rows.check_holonomic(J)
    np.testing.assert_allclose(rows.pseudo_inverse(J), np.linalg.pinv(np.array(J)), atol=1e-14)
    assert rows.singular_values(J)[2] == pytest.approx(0.0, abs=1e-15)
    with pytest.raises(KinematicsError, match="constrain only 2 of the 3"):
        rows.check_holonomic([(1.0, 0.0, 0.0), (0.0, 1.0, 0.0)])  # two wheels
    assert rows.pseudo_inverse([(0.0, 0.0, 0.0)]) == ((0.0,), (0.0,), (0.0,))


def test_forward_recovers_a_rigid_motion_and_reports_the_residual() -> None:
    robot = load_robot("mecanum4")
    twist = (0.3, -0.2, 0.7)
    speeds = rows.apply(robot.inverse_rows, twist)
    fitted, residual = rows.forward(robot.inverse_rows, speeds)
    assert fitted == pytest.approx(twist, abs=1e-14)
    assert residual == pytest.approx([0.0] * 4, abs=1e-13)
    slipped = [speeds[0] + 1.0, *speeds[1:]]
    numpy_fit = kinematics.forward(robot.wheel_matrix, slipped)
    np.testing.assert_allclose(
        rows.forward(robot.inverse_rows, slipped).residual, numpy_fit.residual, atol=1e-14
    )
    with pytest.raises(KinematicsError, match="expected 4 wheel speeds"):
        rows.forward(robot.inverse_rows, speeds[:3])
