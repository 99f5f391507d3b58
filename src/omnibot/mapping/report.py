"""What a mapping run leaves in its directory, and its scores in words.

:func:`write_outputs` writes a run's ``map.yaml`` + ``map.pgm`` (map_server's format),
``estimate.tum`` and ``odometry.tum``, and with the simulator's truth ``truth.tum``,
``report.json`` (APE/RPE of both trajectories, the map's precision and recall against the world's
own geometry) and ``map.png``; :func:`write_report` the same of any map and trajectories (a log's,
:mod:`omnibot.logs.slamscore`); :func:`score_lines` says a report's scores.
"""

from __future__ import annotations

import itertools
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from omnibot.mapping.feed import Track
from omnibot.mapping.snapshot import RangeNoise
from omnibot.motion import Pose2D

if TYPE_CHECKING:
    from omnibot.mapping.grid import OccupancyGrid
    from omnibot.mapping.session import MappingSink
    from omnibot.sim import World


@dataclass(frozen=True)
class MappingResult:
    """What :func:`write_outputs` wrote and measured."""

    files: list[Path]
    report: dict[str, Any]
    grid: OccupancyGrid | None = None
    """The map written."""


def write_outputs(
    out: Path,
    sink: MappingSink,
    *,
    truth: Track | None = None,
    world: World | None = None,
    resolution: float = 0.05,
    noise: RangeNoise | None = None,
    plot: bool = True,
) -> MappingResult:
    """Write the map, the trajectories and (with ``truth`` and ``world``) the scored report to ``out``."""
    if not sink.slam.keyframes():
        raise ValueError("no scan reached the SLAM: nothing to map")
    noise = noise or RangeNoise()
    grid = sink.grid(resolution, noise)
    estimate = sink.trajectory()
    report: dict[str, Any] = {
        "scans": sink.received,
        "scans_dropped": sink.dropped,
        "keyframes": len(sink.slam.keyframes()),
        "loop_closures": sink.slam.closures,
        "keyframes_degenerate": sum(1 for m in sink.slam.matches if m.unconstrained),
        "keyframes_anchored": sink.slam.anchored,
        "distance_m": path_length(estimate.poses),
        "map": {"hit_range_m": noise.hit_range},
    }
    tracks = {"estimate": estimate, "odometry": sink.odometry}
    if truth is not None:
        tracks["truth"] = truth
    return write_report(out, grid, tracks, report, world=world, plot=plot)


def write_report(
    out: Path,
    grid: OccupancyGrid,
    tracks: dict[str, Track],
    report: dict[str, Any],
    *,
    world: World | None = None,
    plot: bool = True,
) -> MappingResult:
    """What a scored run leaves in ``out``: ``grid`` as map.yaml + map.pgm, each of ``tracks``
    (``estimate``, ``odometry``, ``truth``) as NAME.tum, ``report`` (what the run adds) completed with
    the map's size, the trajectories' APE/RPE against ``truth`` and the map's precision and recall
    against ``world`` in report.json, and map.png."""
    from omnibot.mapping.mapfile import save_map
    from omnibot.mapping.trajectory import Trajectory, write_tum

    save_map(grid, out / "map.yaml")
    files = [out / "map.yaml", out / "map.pgm"]
    trajectories: dict[str, Trajectory] = {}
    for name, track in tracks.items():
        if len(track) == 0:
            continue
        trajectories[name] = Trajectory.from_poses(track.stamps, track.poses)
        path = out / f"{name}.tum"
        write_tum(path, trajectories[name])
        files.append(path)
    report["map"] = {
        "resolution": grid.resolution,
        **report.get("map", {}),
        "origin": [grid.origin.x, grid.origin.y, grid.origin.theta],
        "size_cells": list(grid.shape),
    }
    if "truth" in trajectories:
        report["trajectory"] = _scores(trajectories)
    if world is not None:
        from omnibot.mapping.score import score_map

        score = score_map(grid, world)
        report["map"]["precision"] = _number(score.precision)
        report["map"]["recall"] = _number(score.recall)
        report["map"]["tolerance_m"] = score.tolerance
    path = out / "report.json"
    path.write_text(json.dumps(report, indent=2) + "\n")
    files.append(path)
    if plot:
        files.append(_plot(out / "map.png", grid, tracks))
    return MappingResult(files, report, grid)


def score_lines(report: dict[str, Any]) -> list[str]:
    """A report's scores in words, one line each: the trajectories' APE, the map's precision and
    recall (what the report has of them)."""
    lines = []
    for name in ("estimate", "odometry"):
        scores = report.get("trajectory", {}).get(name)
        if scores is not None:
            lines.append(
                f"{name}: APE RMSE {_cm(scores['ape_rmse_m'])}, max {_cm(scores['ape_max_m'])} "
                "(from the simulator's truth)"
            )
    m = report["map"]
    if "precision" in m:
        lines.append(
            f"map: precision {_pct(m['precision'])}, recall {_pct(m['recall'])} within "
            f"{m['tolerance_m'] * 100:.0f} cm of the world's walls and furniture"
        )
    return lines


def _cm(v: float | None) -> str:
    return "n/a" if v is None else f"{v * 100:.1f} cm"


def _pct(v: float | None) -> str:
    return "n/a" if v is None else f"{v * 100:.1f} %"


def path_length(poses: list[Pose2D]) -> float:
    """m along ``poses``."""
    return sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in itertools.pairwise(poses))


def _scores(trajectories: dict[str, Any]) -> dict[str, Any]:
    from omnibot.mapping.trajectory import score_trajectory

    truth = trajectories["truth"]
    scores: dict[str, Any] = {}
    for name in ("estimate", "odometry"):
        if name in trajectories:
            errors = score_trajectory(trajectories[name], truth)
            scores[name] = {
                "ape_rmse_m": _number(errors.ape_rmse),
                "ape_max_m": _number(errors.ape_max),
                "rpe_rmse_m": _number(errors.rpe_rmse),
                "rpe_delta_m": errors.rpe_delta,
                "poses": errors.pairs,
            }
    return scores


def _number(v: float) -> float | None:
    """A float for JSON: None where it is not a number (JSON has no NaN)."""
    return v if math.isfinite(v) else None


def _plot(path: Path, grid: OccupancyGrid, tracks: dict[str, Track]) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 8 * grid.height / max(grid.width, 1e-9)))
    shade = np.where(grid.data < 0, 0.8, 1.0 - grid.data / 100.0)
    x0, y0 = grid.origin.x, grid.origin.y
    ax.imshow(
        shade, cmap="gray", vmin=0, vmax=1, origin="lower", extent=(x0, x0 + grid.width, y0, y0 + grid.height)
    )
    for name, color in (("truth", "tab:green"), ("odometry", "tab:red"), ("estimate", "tab:blue")):
        track = tracks.get(name)
        if track is not None and len(track):
            ax.plot([p.x for p in track.poses], [p.y for p in track.poses], color=color, lw=1, label=name)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="upper right")
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path
