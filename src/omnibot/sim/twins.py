"""The compiled kernels' plain-Python twins: the same code, run by CPython, with the same numbers.

A numba dispatcher keeps the function it compiles (``py_func``), but that function calls the other
kernels by their global names, which are dispatchers again (calling one compiles it). A twin is
that function rebuilt over a copy of the globals of the module that defines it, in which every
dispatcher (its own module's, or one imported from another) is replaced by its own twin, numba's ``prange`` by ``range`` and ``math`` by :data:`LIBM`. It runs 10-50 times
slower than the compiled kernel, and with no compiling at all: the simulator runs on the twins
while the compiled kernels are built in a process of their own (:mod:`omnibot.sim.jit`).

Bit for bit: the kernels do IEEE double arithmetic in the order written (numba compiles them
without ``fastmath``, so nothing is reassociated or fused), and numba calls the C library's
``sin``, ``cos``, ``tanh``, ``atan2``, ``asin``, ``sqrt``, ``floor`` as CPython's
``math`` does, with the same results. The one exception is ``math.hypot``: CPython (3.10 and later)
computes it with its own, more accurate algorithm, numba calls the C library's ``hypot``; they
differ in the last bit for about one argument pair in 600. :data:`LIBM` is ``math`` with the C
library's ``hypot`` (numpy's, which calls it). ``np.argsort`` may order equal keys differently
(numba's quicksort is not numpy's); the only kernel that sorts,
:func:`~omnibot.sim.kernels.scan_index`, sorts edges by distance for a search whose result does not
depend on the order of equal distances. ``tests/sim/test_twins.py`` runs the seeded scenes of ``tests/sim/step_trace.py`` on the
twins against the same recorded floats as the compiled step.

Where the arithmetic fails the two may differ: a float division by zero raises ZeroDivisionError
compiled (numba's Python error model), but in a twin only when both operands are Python floats; on
numpy scalars (an array's elements) it gives inf or nan with a RuntimeWarning. The kernels divide
only by quantities their callers keep away from zero.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import FunctionType, ModuleType, SimpleNamespace
from typing import Any

import numpy as np
from numba.extending import is_jitted


def _libm_hypot(x: float, y: float) -> float:
    """The C library's hypot (numba's ``math.hypot``), not CPython's."""
    return float(np.hypot(x, y))


LIBM = SimpleNamespace(**{name: getattr(math, name) for name in dir(math) if not name.startswith("_")})
"""``math`` as numba compiles it: the module's functions, ``hypot`` the C library's."""
LIBM.hypot = _libm_hypot


def python_twins(module: ModuleType) -> dict[str, Callable[..., Any]]:
    """Every numba-compiled function in ``module``'s namespace (its own and those it imported), by
    name, as a plain Python function whose calls of compiled functions go to their twins.

    A twin runs over a copy of the globals of the module that defines its function, so a kernel
    imported from another module finds its own names, and the kernels it calls (by the names it
    imported them under) are twins too, across as many modules as the calls go."""
    twins = _twins_of(_reachable_kernels(vars(module)))
    return {name: twins[id(value)] for name, value in vars(module).items() if is_jitted(value)}


def _reachable_kernels(namespace: dict[str, Any]) -> list[Any]:
    """The compiled functions of ``namespace`` and, transitively, of their modules' namespaces."""
    found: dict[int, Any] = {}
    pending = [value for value in namespace.values() if is_jitted(value)]
    while pending:
        kernel = pending.pop()
        if id(kernel) not in found:
            found[id(kernel)] = kernel
            pending.extend(value for value in kernel.py_func.__globals__.values() if is_jitted(value))
    return list(found.values())


def _twins_of(kernels: list[Any]) -> dict[int, Callable[..., Any]]:
    """Each kernel's twin by the kernel's id: one copy of globals per defining module, whose
    compiled functions are then replaced by their twins."""
    copies: dict[int, dict[str, Any]] = {}
    twins: dict[int, Callable[..., Any]] = {}
    for kernel in kernels:
        code, own = kernel.py_func, kernel.py_func.__globals__
        twin_globals = copies.setdefault(id(own), {**own, "math": LIBM, "prange": range})
        twins[id(kernel)] = FunctionType(
            code.__code__, twin_globals, code.__name__, code.__defaults__, code.__closure__
        )
    for twin_globals in copies.values():
        twin_globals.update(
            {name: twins[id(value)] for name, value in twin_globals.items() if is_jitted(value)}
        )
    return twins


__all__ = ["LIBM", "python_twins"]
