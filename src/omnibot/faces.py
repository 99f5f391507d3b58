"""A package face that gives its names on first use (PEP 562): the package's ``__init__`` sets
``__getattr__ = lazy_names(__name__, {"module": ("Name", ...), ...})`` under ``if not
TYPE_CHECKING:`` and imports the same names under ``if TYPE_CHECKING:``, so type checkers see their
types and reject a name the face lacks (a module ``__getattr__`` would let them take any name).
Importing the package then loads nothing; a name loads only the module that defines it, looked up
there each time (so a stand-in a test puts on that module is the one found).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from importlib import import_module
from typing import Any


def lazy_names(package: str, exports: Mapping[str, tuple[str, ...]]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``package``: each name of ``exports`` (its submodule, relative to
    ``package``, to the names it defines) from that submodule; any other name an AttributeError."""
    module_of = {name: module for module, names in exports.items() for name in names}

    def attribute(name: str) -> Any:
        module = module_of.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(import_module(f"{package}.{module}"), name)

    return attribute
