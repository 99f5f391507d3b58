"""The kernels' plain-Python twins: they call no compiled function and give the compiled step's
numbers bit for bit (the recorded trace of :mod:`tests.sim.step_trace`)."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest
from numba.extending import is_jitted

from omnibot.sim import jit, kernels
from omnibot.sim.twins import LIBM, python_twins

from .step_trace import SCENES, assert_as_recorded


@pytest.fixture
def on_the_twins(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """The simulator runs the twins for one test."""
    jit.active.choose()
    twins = python_twins(kernels)
    for name in jit.CALLED:
        monkeypatch.setattr(jit.active, name, twins[name])
    yield


def test_every_compiled_kernel_has_a_twin_that_calls_only_twins() -> None:
    twins = python_twins(kernels)
    compiled = {name for name, value in vars(kernels).items() if is_jitted(value)}
    assert set(twins) == compiled and set(jit.CALLED) <= compiled
    for twin in twins.values():
        assert not is_jitted(twin)
        called = [twin.__globals__[name] for name in twin.__code__.co_names if name in twin.__globals__]
        assert not any(is_jitted(f) for f in called), twin.__name__
        assert twin.__globals__["math"] is LIBM


def test_libm_hypot_is_the_c_librarys_where_pythons_differs() -> None:
    """Numba's math.hypot is the C library's; CPython's is its own and differs in the last bit."""
    rng = np.random.default_rng(1)
    pairs = rng.normal(0.0, 1.0, (20000, 2)) * 10.0 ** rng.integers(-3, 3, (20000, 1))
    compiled = kernels._segment_distance  # hypot of the offset from a degenerate segment's point
    ours = [compiled(x, y, 0.0, 0.0, 0.0, 0.0) for x, y in pairs.tolist()]
    assert [LIBM.hypot(x, y) for x, y in pairs.tolist()] == ours
    assert [math.hypot(x, y) for x, y in pairs.tolist()] != ours


@pytest.mark.usefixtures("on_the_twins")
@pytest.mark.parametrize("scene", sorted(SCENES))
def test_the_twins_give_the_recorded_numbers_bit_for_bit(scene: str) -> None:
    assert_as_recorded(scene)
