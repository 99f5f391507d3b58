"""Whether figures can be drawn here: matplotlib comes with the ``[plots]`` extra (and with ``[slam]``).

A command whose figures are a by-product of its run (calibration's report, the demo's trajectory,
the tour's directions) writes everything else without them and says which extra draws them, rather
than losing the run to an ImportError at its end; a figure the user asked for by name (``--plot
FILE``) is checked before the robot moves instead (:func:`omnibot.cliargs.check_plot`).
"""

from __future__ import annotations

import importlib


def unavailable() -> str | None:
    """``None`` when matplotlib imports; else the one line naming the extra that installs it."""
    from omnibot.extras import missing_extra

    try:
        importlib.import_module("matplotlib")
    except ModuleNotFoundError as exc:
        line = missing_extra(exc) if exc.name == "matplotlib" else None
        if line is None:  # one of matplotlib's own modules missing: a broken install, shown as it is
            raise
        return line
    return None
