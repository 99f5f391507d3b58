"""The kernels' plain-Python twins: they call no compiled function and give the compiled step's
numbers bit for bit (the recorded trace of :mod:`tests.sim.step_trace`)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from types import ModuleType

import numpy as np
import pytest
from numba import njit
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


def _module(name: str, source: str, **names: object) -> ModuleType:
    """A module of ``source`` run over ``names`` (its imports)."""
    module = ModuleType(name)
    vars(module).update(names, njit=njit, math=math)
    exec(source, vars(module))  # the test's own source
    return module


def test_a_twin_follows_the_kernels_imports_across_modules() -> None:
    """A kernel split across modules: each twin runs over its own module's globals (its constants),
    and the kernels it imported, directly or through another module, are twins too."""
    floor = _module("floor", "@njit\ndef rough(x):\n    return math.hypot(x, GAIN)\n", GAIN=3.0)
    wheel = _module(
        "wheel", "@njit\ndef grip(x):\n    return rough(x) * SCALE\n", SCALE=2.0, rough=floor.rough
    )
    step = _module("step", "@njit\ndef step(x):\n    return grip(x) + 1.0\n", grip=wheel.grip)
    twins = python_twins(step)
    assert set(twins) == {"step", "grip"}
    assert twins["step"](4.0) == LIBM.hypot(4.0, 3.0) * 2.0 + 1.0
    grip_twin = twins["step"].__globals__["grip"]
    assert grip_twin is twins["grip"] and not is_jitted(grip_twin)
    assert (
        not is_jitted(grip_twin.__globals__["rough"])
        and grip_twin.__globals__["rough"].__globals__["math"] is LIBM
    )
    assert vars(step)["grip"] is wheel.grip and vars(wheel)["rough"] is floor.rough  # the modules untouched


def test_libm_hypot_is_the_c_librarys_where_pythons_differs() -> None:
    """Numba's math.hypot is the C library's; CPython's is its own and differs in the last bit."""
    rng = np.random.default_rng(1)
    pairs = rng.normal(0.0, 1.0, (20000, 2)) * 10.0 ** rng.integers(-3, 3, (20000, 1))
    compiled = kernels.contacts.segment_distance  # hypot of the offset from a degenerate segment's point
    ours = [compiled(x, y, 0.0, 0.0, 0.0, 0.0) for x, y in pairs.tolist()]
    assert [LIBM.hypot(x, y) for x, y in pairs.tolist()] == ours
    assert [math.hypot(x, y) for x, y in pairs.tolist()] != ours


@pytest.mark.usefixtures("on_the_twins")
@pytest.mark.parametrize("scene", sorted(SCENES))
def test_the_twins_give_the_recorded_numbers_bit_for_bit(scene: str) -> None:
    assert_as_recorded(scene)
