"""Plots of follow runs: path, driven trajectory and the error along the path."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path as FsPath

import numpy as np

from omnibot.navigation.metrics import error_along_path
from omnibot.navigation.trace import FollowRun


def plot_run(run: FollowRun, target: str | FsPath, title: str = "") -> None:
    """Two panels: the path with the driven (and estimated) trajectory; cross-track error vs arc length."""
    plot_runs([run], target, title=title, labels=[run.follower])


def plot_runs(
    runs: Sequence[FollowRun], target: str | FsPath, *, title: str = "", labels: Sequence[str] | None = None
) -> None:
    """Several runs of the same path on one figure (e.g. with and without a feature)."""
    from omnibot.plots import new_figure, save

    if not runs:
        raise ValueError("nothing to plot")
    labels = list(labels) if labels is not None else [r.follower for r in runs]
    fig, axes = new_figure(1, 2, size=(12.0, 6.0))
    ax, ax_err = axes[0][0], axes[0][1]
    path = runs[0].path
    ax.plot(path.x, path.y, color="0.2", lw=2.5, alpha=0.35, label="path")
    ax.plot(path.x[:1], path.y[:1], "o", color="0.2", ms=5)
    for k, (run, label) in enumerate(zip(runs, labels, strict=True)):
        a = run.arrays()
        color = f"C{k}"
        driven = a["truth"] if run.has_truth else a["estimate"]
        source = "driven (ground truth)" if run.has_truth else "driven (odometry)"
        if len(driven):
            ax.plot(driven[:, 0], driven[:, 1], color=color, lw=1.4, label=f"{label}: {source}")
        if run.has_truth and len(a["estimate"]):
            est = a["estimate"]
            ax.plot(est[:, 0], est[:, 1], "--", color=color, lw=0.8, alpha=0.7, label=f"{label}: estimate")
        s, d = error_along_path(run)
        if len(s):
            rms = float(np.sqrt(np.mean(d**2)))
            ax_err.plot(
                s,
                100 * d,
                color=color,
                lw=1.0,
                label=f"{label}: RMS {100 * rms:.2f} cm, max {100 * d.max():.2f} cm",
            )
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), fontsize=7, ncol=2)
    ax.set_title(title or "path and driven trajectory", fontsize=10)
    ax_err.set_xlabel("position along the path (arc length of the closest point) [m]")
    ax_err.set_ylabel("cross-track error [cm]")
    ax_err.grid(True, alpha=0.3)
    ax_err.legend(loc="best", fontsize=7)
    ax_err.set_title("error along the path", fontsize=10)
    save(fig, str(target))
