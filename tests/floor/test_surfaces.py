"""Floor surfaces: the four materials, plausible numbers, name lookup."""

from __future__ import annotations

import pytest

from omnibot.errors import ConfigError
from omnibot.floor.surfaces import SURFACES, Surface, get_surface


def test_the_four_surfaces_exist_with_a_justification() -> None:
    assert set(SURFACES) >= {"wood", "carpet", "concrete", "linoleum"}
    for name, s in SURFACES.items():
        assert s.name == name
        assert s.source, f"{name} needs a one-line source"


@pytest.mark.parametrize("surface", list(SURFACES.values()), ids=list(SURFACES))
def test_numbers_are_physically_plausible(surface: Surface) -> None:
    assert 0.3 <= surface.mu <= 1.0  # rubber on floors
    assert 0.001 <= surface.slip_velocity <= 0.1  # m/s
    assert 0.5 <= surface.rolling_multiplier <= 8.0


def test_carpet_rolls_harder_than_every_hard_floor() -> None:
    # how much harder is fitted to seed 000's "up to 20 %" (tests/sim/test_realism.py)
    carpet = SURFACES["carpet"].rolling_multiplier
    for hard in ("wood", "linoleum", "concrete"):
        assert carpet > SURFACES[hard].rolling_multiplier


def test_get_surface_by_name_or_object() -> None:
    assert get_surface("wood") is SURFACES["wood"]
    ice = Surface("ice", mu=0.1, slip_velocity=0.02, rolling_multiplier=1.0)
    assert get_surface(ice) is ice


def test_unknown_surface_suggests_the_nearest_name() -> None:
    with pytest.raises(ConfigError, match="did you mean 'carpet'"):
        get_surface("carpt")
    with pytest.raises(ConfigError, match="expected one of"):
        get_surface("lava")


def test_invalid_numbers_are_rejected() -> None:
    with pytest.raises(ConfigError):
        Surface("bad", mu=-0.1, slip_velocity=0.02, rolling_multiplier=1.0)
    with pytest.raises(ConfigError):
        Surface("bad", mu=0.5, slip_velocity=0.0, rolling_multiplier=1.0)
