"""Whether figures can be drawn: matplotlib installed here, and the line naming its extra when not."""

from __future__ import annotations

import sys

import pytest

from omnibot.plots import unavailable


def test_matplotlib_installed_draws() -> None:
    assert unavailable() is None


def test_without_matplotlib_the_plots_extra_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import halted: ModuleNotFoundError
    why = unavailable()
    assert why is not None and "pip install 'omnibot[plots]'" in why and "'matplotlib'" in why


def test_a_missing_module_of_no_extra_is_not_hidden(monkeypatch: pytest.MonkeyPatch) -> None:
    """matplotlib present but broken (one of its own modules missing): the error, not a skipped plot."""

    def broken(name: str) -> None:
        raise ModuleNotFoundError(
            "No module named 'matplotlib._c_internal_utils'", name="matplotlib._c_internal_utils"
        )

    monkeypatch.setattr("omnibot.plots.available.importlib.import_module", broken)
    with pytest.raises(ModuleNotFoundError):
        unavailable()
