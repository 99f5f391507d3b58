"""Runnable demonstrations built on the public API (``omnibot tour``, ``omnibot demo``).

The command line takes the directions tour (``run_tour``, its ``DIRECTIONS``, table and figure) and
seed 000's job (``run_demo``) from this face, each loaded on first use with only its own module::

    from omnibot.demos import DIRECTIONS, format_table, plot_tour, run_demo, run_tour

``format_table`` is the tour's; the job's table (``seed000.format_table``) stays on its module.
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.demos.directions import DIRECTIONS, DirectionRun, format_table, plot_tour, run_tour
    from omnibot.demos.seed000 import run_demo

_EXPORTS = {
    "directions": ("DIRECTIONS", "DirectionRun", "format_table", "plot_tour", "run_tour"),
    "seed000": ("run_demo",),
}

__all__ = [
    "DIRECTIONS",
    "DirectionRun",
    "directions",
    "format_table",
    "plot_tour",
    "run_demo",
    "run_tour",
    "seed000",
]

if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
