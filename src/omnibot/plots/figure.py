"""A headless matplotlib figure factory: the Agg backend, never a window."""

from __future__ import annotations

from typing import Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
from matplotlib.figure import Figure


def new_figure(
    rows: int = 1, cols: int = 1, size: tuple[float, float] = (6.0, 5.0), **kwargs: Any
) -> tuple[Figure, Any]:
    """A figure with a grid of axes, drawn off-screen."""
    fig, axes = plt.subplots(rows, cols, figsize=size, squeeze=False, **kwargs)
    return fig, axes


def save(fig: Figure, path: str) -> None:
    """Write the figure and release it."""
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
