"""TUM files and evo's APE/RPE on cases computed by hand."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from omnibot.errors import ConfigError
from omnibot.mapping.trajectory import Trajectory, read_tum, score_trajectory, write_tum
from omnibot.motion import Pose2D


def line(n: int = 41, step: float = 0.1, dt: float = 0.1) -> Trajectory:
    """n poses along x, ``step`` m apart, facing +x."""
    x = step * np.arange(n)
    return Trajectory(np.arange(n, dtype=np.float64) * dt, np.column_stack((x, np.zeros(n), np.zeros(n))))


def test_tum_round_trip_and_the_planar_quaternion(tmp_path: Path) -> None:
    t = Trajectory.from_poses(
        [0.0, 0.5, 1.25], [Pose2D(1, 2, 0.0), Pose2D(-1.5, 0.25, 2.0), Pose2D(0, 0, -3.0)]
    )
    write_tum(tmp_path / "a.tum", t)
    first = (tmp_path / "a.tum").read_text().splitlines()[2].split()
    assert [float(v) for v in first] == pytest.approx(
        [0.5, -1.5, 0.25, 0, 0, 0, math.sin(1.0), math.cos(1.0)]
    )
    back = read_tum(tmp_path / "a.tum")
    assert np.allclose(back.stamps, t.stamps) and np.allclose(back.poses, t.poses)
    p = back.pose(1)
    assert (p.x, p.y, p.theta) == pytest.approx((-1.5, 0.25, 2.0))


def test_tum_files_of_other_tools_read_with_their_yaw(tmp_path: Path) -> None:
    # a 3D quaternion with a little roll: the yaw is kept, the roll dropped
    roll, yaw = 0.02, 0.7
    cr, sr, cy, sy = math.cos(roll / 2), math.sin(roll / 2), math.cos(yaw / 2), math.sin(yaw / 2)
    q = (cy * sr, sy * sr, sy * cr, cy * cr)  # qx, qy, qz, qw of yaw * roll
    (tmp_path / "b.tum").write_text(f"# from elsewhere\n\n1.0 0.5 0.25 0.1 {q[0]} {q[1]} {q[2]} {q[3]}\n")
    t = read_tum(tmp_path / "b.tum")
    assert t.poses[0] == pytest.approx([0.5, 0.25, yaw], abs=1e-4)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("1 2 3\n", "line 1: expected 8 numbers"),
        ("# c\n1 0 0 0 0 0 0 1\n1 x 0 0 0 0 0 1\n", "line 3: expected 8 numbers"),
        ("1 0 0 0 0 0 0 2\n", "quaternion norm 2"),
        ("1 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n", "line 2: timestamp 0.5 does not increase"),
        ("# nothing\n", "no poses"),
    ],
)
def test_bad_tum_files_are_one_config_error_naming_the_file(tmp_path: Path, text: str, message: str) -> None:
    (tmp_path / "bad.tum").write_text(text)
    with pytest.raises(ConfigError, match=r"bad\.tum") as err:
        read_tum(tmp_path / "bad.tum")
    assert message in str(err.value)


def test_a_constant_offset_is_its_own_ape_and_no_rpe() -> None:
    truth = line()
    est = Trajectory(truth.stamps, truth.poses + np.array([0.03, 0.04, 0.0]))
    e = score_trajectory(est, truth)
    assert (e.ape_rmse, e.ape_mean, e.ape_max) == pytest.approx((0.05, 0.05, 0.05))
    assert e.rpe_max == pytest.approx(0.0, abs=1e-12) and e.pairs == 41 and e.length == pytest.approx(4.0)
    assert not e.aligned


def test_a_10_percent_scale_error_by_hand() -> None:
    truth = line()
    est = Trajectory(truth.stamps, truth.poses * (1.1, 1.0, 1.0))
    e = score_trajectory(est, truth)
    errors = 0.1 * truth.poses[:, 0]  # 0 .. 0.4 m
    assert e.ape_rmse == pytest.approx(math.sqrt(np.mean(errors**2)))
    assert e.ape_mean == pytest.approx(0.2) and e.ape_max == pytest.approx(0.4)
    # every 1 m of truth is 1.1 m of estimate: 0.1 m error per pair
    assert (e.rpe_rmse, e.rpe_mean, e.rpe_max) == pytest.approx((0.1, 0.1, 0.1))


def test_association_by_timestamp_drops_unmatched_poses() -> None:
    truth = line()
    est = Trajectory(truth.stamps[::2] + 0.004, truth.poses[::2] + np.array([0.0, 0.02, 0.0]))
    e = score_trajectory(est, truth)
    assert e.pairs == 21 and e.ape_max == pytest.approx(0.02)
    with pytest.raises(ValueError, match="associate"):
        score_trajectory(Trajectory(truth.stamps + 100.0, truth.poses), truth)


def test_alignment_removes_a_rigid_transform_only_when_asked() -> None:
    n = 60
    a = np.linspace(0, 1.5 * math.pi, n)
    truth = Trajectory(
        np.arange(n, dtype=np.float64) * 0.1, np.column_stack((np.cos(a), np.sin(a), a + math.pi / 2))
    )
    turn = 0.3
    c, s = math.cos(turn), math.sin(turn)
    xy = truth.poses[:, :2] @ np.array([[c, s], [-s, c]]) + (0.5, -0.2)
    est = Trajectory(truth.stamps, np.column_stack((xy, truth.poses[:, 2] + turn)))
    raw = score_trajectory(est, truth)
    aligned = score_trajectory(est, truth, align=True)
    assert raw.ape_rmse > 0.3 and aligned.aligned
    assert aligned.ape_rmse == pytest.approx(0.0, abs=1e-9)
    assert raw.rpe_rmse == pytest.approx(0.0, abs=1e-9)  # relative motion is the same either way


def test_rpe_is_nan_on_a_path_shorter_than_its_delta() -> None:
    truth = line(5)
    e = score_trajectory(truth, truth)
    assert e.ape_rmse == 0.0 and math.isnan(e.rpe_rmse)
