"""Numba's disk cache for kernels that call kernels of other files: each kernel's cache entry is
stamped with the contents of every file of :mod:`omnibot.sim.kernels` (and of the constants they
import from outside it, :data:`FROZEN`), not only its own.

Numba checks a cached function against its own source file alone, but a kernel compiles the kernels
it calls into itself: with the family split over several files, an edit of ``wheels.py`` would leave
:func:`~omnibot.sim.kernels.step.robot_step` (in ``step.py``) loading the old physics from the
cache. Importing this module (the package's ``__init__`` does, before any kernel is defined) puts
a locator ahead of numba's own: for a function of this package it is the locator numba would have
chosen (the same cache directory and file names), its stamp widened to the whole family. Any file
of the family changed, every kernel of it compiles again, as one ``kernels.py`` did.
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path
from typing import Any

from numba.core.caching import CacheImpl, _CacheLocator

_LOCATORS: list[Any] = CacheImpl._locator_classes
"""Numba's locator classes, tried in order for each cached function (a class attribute)."""

FAMILY = Path(__file__).resolve().parent
"""The folder whose Python files stamp each other's kernels."""

FROZEN = (FAMILY.parents[1] / "floor" / "contact.py",)
"""Files outside the family whose module-level constants the kernels import (the floor's speed
thresholds): numba freezes a global's value into the compiled code, so they stamp it too."""


def family_stamp(folder: Path = FAMILY, frozen: tuple[Path, ...] = FROZEN) -> str:
    """The SHA-256 of the family's Python files, in name order, then the ``frozen`` files, each with
    its name."""
    digest = hashlib.sha256()
    for path in [*sorted(folder.glob("*.py")), *frozen]:
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


@functools.cache
def _stamp_now() -> str:
    """:func:`family_stamp` of this package, once a process (numba asks for it as each kernel is
    defined, and takes a kernel's stamp then, as it does its own file's)."""
    return family_stamp(FAMILY)


class FamilyLocator(_CacheLocator):
    """Numba's own locator of a kernel of the family, with the family's stamp added to its own."""

    def __init__(self, inner: _CacheLocator) -> None:
        self._inner: Any = inner  # numba's locators are untyped
        self._py_file = getattr(inner, "_py_file", "")

    def ensure_cache_path(self) -> None:
        """The inner locator's (it makes the directory and checks it is writable)."""
        self._inner.ensure_cache_path()

    def get_cache_path(self) -> str:
        """The inner locator's: the cache files lie where numba would have put them."""
        return str(self._inner.get_cache_path())

    def get_source_stamp(self) -> tuple[Any, str]:
        """The kernel's own file's stamp and the family's."""
        return self._inner.get_source_stamp(), _stamp_now()

    def get_disambiguator(self) -> str:
        """The inner locator's (the kernel's line number)."""
        return str(self._inner.get_disambiguator())

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> FamilyLocator | None:
        """Numba's own choice of locator, wrapped, for a function defined in the family's folder."""
        if Path(py_file).resolve().parent != FAMILY:
            return None
        for other in _LOCATORS:
            inner = None if other is cls else other.from_function(py_func, py_file)
            if inner is not None:
                return cls(inner)
        return None


if FamilyLocator not in _LOCATORS:
    _LOCATORS.insert(0, FamilyLocator)

__all__ = ["FAMILY", "FROZEN", "FamilyLocator", "family_stamp"]
