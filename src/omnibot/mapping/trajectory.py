"""Planar trajectories in TUM format, and their errors against the truth computed with evo.

A TUM file has one pose a line, ``timestamp tx ty tz qx qy qz qw`` (s, m, unit quaternion), ``#``
comments allowed. omnibot writes planar poses (``tz = qx = qy = 0``, the yaw in ``qz``, ``qw``) and
reads any: the yaw is taken from the quaternion, z, roll and pitch are dropped.

Scoring (:func:`score_trajectory`, with evo's metrics):

* the estimate and the truth are associated by timestamps (evo's nearest-time association, pairs
  at most ``max_diff`` s apart);
* **APE**: the translation error of every associated pose, its RMSE, mean and max (m). Without
  alignment by default: in the simulator the map frame is the world frame at the start, so an
  estimate must be right in absolute terms. ``align=True`` first fits the estimate onto the truth
  with a rigid transform (Umeyama, no scale), e.g. for a SLAM whose map frame is its first pose;
  the result says when it was used;
* **RPE**: the translation error of the relative motion over every ``rpe_delta`` metres travelled
  (evo's ``delta_unit=m``, consecutive pairs of poses that far apart along the truth), RMSE, mean
  and max in m (so with the default 1 m, metres of error per metre travelled).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import ConfigError
from omnibot.motion import Pose2D

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Trajectory:
    """Timestamped planar poses: ``stamps`` (n,) s increasing, ``poses`` (n, 3) x, y, theta."""

    stamps: FloatArray
    poses: FloatArray

    def __post_init__(self) -> None:
        stamps = np.asarray(self.stamps, dtype=np.float64).reshape(-1)
        poses = np.asarray(self.poses, dtype=np.float64).reshape(-1, 3)
        if len(stamps) != len(poses):
            raise ValueError(f"a trajectory needs one stamp per pose, not {len(stamps)} and {len(poses)}")
        if len(stamps) > 1 and not (np.diff(stamps) > 0).all():
            raise ValueError("a trajectory's stamps must increase")
        object.__setattr__(self, "stamps", stamps)
        object.__setattr__(self, "poses", poses)

    @classmethod
    def from_poses(cls, stamps: Sequence[float], poses: Sequence[Pose2D]) -> Trajectory:
        """A trajectory of :class:`Pose2D`."""
        return cls(np.asarray(stamps, float), np.array([(p.x, p.y, p.theta) for p in poses], float))

    def __len__(self) -> int:
        return int(self.stamps.shape[0])

    def pose(self, i: int) -> Pose2D:
        """The i-th pose."""
        x, y, th = self.poses[i]
        return Pose2D(float(x), float(y), float(th))


def write_tum(path: str | Path, trajectory: Trajectory) -> None:
    """Write ``trajectory`` as a TUM file (planar: tz, qx, qy are 0)."""
    lines = ["# timestamp tx ty tz qx qy qz qw\n"]
    for t, (x, y, th) in zip(trajectory.stamps, trajectory.poses, strict=True):
        qz, qw = math.sin(th / 2), math.cos(th / 2)
        lines.append(f"{t:.9f} {float(x)!r} {float(y)!r} 0 0 0 {qz!r} {qw!r}\n")
    Path(path).write_text("".join(lines), encoding="ascii")


def read_tum(path: str | Path) -> Trajectory:
    """Read a TUM file; ConfigError naming the file and line for anything that is not one."""
    source = Path(path)
    try:
        text = source.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"cannot read trajectory {source}: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise ConfigError(f"cannot read trajectory {source}: not a text file") from None
    rows: list[tuple[float, float, float, float]] = []
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        words = line.replace(",", " ").split()
        try:
            values = [float(w) for w in words]
        except ValueError:
            values = []
        if len(values) != 8 or not all(math.isfinite(v) for v in values):
            raise ConfigError(
                f"invalid trajectory {source} line {number}: expected 8 numbers "
                f"'timestamp tx ty tz qx qy qz qw', got {line[:60]!r}"
            )
        t, x, y, _, qx, qy, qz, qw = values
        norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        if abs(norm - 1.0) > 1e-3:
            raise ConfigError(f"invalid trajectory {source} line {number}: quaternion norm {norm:.4g}, not 1")
        yaw = math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
        if rows and t <= rows[-1][0]:
            raise ConfigError(f"invalid trajectory {source} line {number}: timestamp {t} does not increase")
        rows.append((t, x, y, yaw))
    if not rows:
        raise ConfigError(f"invalid trajectory {source}: no poses")
    arr = np.array(rows)
    return Trajectory(arr[:, 0], arr[:, 1:])


@dataclass(frozen=True)
class TrajectoryErrors:
    """APE and RPE of an estimate against the truth (translation, m; see the module docstring)."""

    ape_rmse: float
    ape_mean: float
    ape_max: float
    rpe_rmse: float
    """nan when the path is shorter than ``rpe_delta``."""
    rpe_mean: float
    rpe_max: float
    rpe_delta: float
    """Path length each RPE pair spans, m."""
    pairs: int
    """Poses associated by timestamp."""
    aligned: bool
    """The estimate was rigidly aligned onto the truth first."""
    length: float
    """Length of the true path over the associated poses, m."""


def _evo(trajectory: Trajectory):  # type: ignore[no-untyped-def]  # evo is untyped
    from evo.core.trajectory import PoseTrajectory3D

    p = trajectory.poses
    xyz = np.column_stack((p[:, 0], p[:, 1], np.zeros(len(p))))
    wxyz = np.column_stack((np.cos(p[:, 2] / 2), np.zeros(len(p)), np.zeros(len(p)), np.sin(p[:, 2] / 2)))
    return PoseTrajectory3D(positions_xyz=xyz, orientations_quat_wxyz=wxyz, timestamps=trajectory.stamps)


def score_trajectory(
    estimate: Trajectory,
    truth: Trajectory,
    *,
    max_diff: float = 0.01,
    rpe_delta: float = 1.0,
    align: bool = False,
) -> TrajectoryErrors:
    """APE and RPE of ``estimate`` against ``truth`` with evo (see the module docstring)."""
    from evo.core import filters, metrics, sync
    from evo.core.units import Unit

    try:
        ref, est = sync.associate_trajectories(_evo(truth), _evo(estimate), max_diff=max_diff)
    except sync.SyncException as exc:
        raise ValueError(f"cannot associate the estimate with the truth: {exc}") from None
    if align:
        est.align(ref, correct_scale=False)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    a = ape.get_all_statistics()
    rpe = metrics.RPE(metrics.PoseRelation.translation_part, delta=rpe_delta, delta_unit=Unit.meters)
    try:
        rpe.process_data((ref, est))
        r = rpe.get_all_statistics()
    except (metrics.MetricsException, filters.FilterException):
        r = {"rmse": math.nan, "mean": math.nan, "max": math.nan}
    return TrajectoryErrors(
        ape_rmse=float(a["rmse"]),
        ape_mean=float(a["mean"]),
        ape_max=float(a["max"]),
        rpe_rmse=float(r["rmse"]),
        rpe_mean=float(r["mean"]),
        rpe_max=float(r["max"]),
        rpe_delta=rpe_delta,
        pairs=int(ref.num_poses),
        aligned=align,
        length=float(ref.path_length),
    )
