"""Plotting helpers (matplotlib, Agg backend); models never import this package.

Other packages take ``new_figure`` and ``save`` from this face (``from omnibot.plots import
new_figure, save``); they load matplotlib on first use, not with ``import omnibot.plots``.
``unavailable`` says whether matplotlib (the ``[plots]`` extra) is installed, for commands whose
figures are a by-product of their run.
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.plots.available import unavailable
    from omnibot.plots.figure import new_figure, save

_EXPORTS = {"available": ("unavailable",), "figure": ("new_figure", "save")}

__all__ = ["available", "figure", "new_figure", "save", "unavailable"]

if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
