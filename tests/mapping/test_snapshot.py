"""The map's scanner noise: the hit range within which a return marks its cell."""

from __future__ import annotations

import math

import pytest

from omnibot.mapping.snapshot import RangeNoise


def test_hit_range_from_the_scanner_noise() -> None:
    assert RangeNoise().hit_range == pytest.approx(2.0)  # 1 % of range: 2 cm at 2 m
    assert RangeNoise(std=0.005, fraction=0.01).hit_range == pytest.approx(1.5)
    assert RangeNoise(fraction=0.0).hit_range == math.inf
    assert RangeNoise(range=4.0).hit_range == 4.0
    assert RangeNoise(std=0.03, fraction=0.0).hit_range == 0.0
