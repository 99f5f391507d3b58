"""Classes composed of mixins, run on MicroPython as one class.

The controller and its motion executor are each one part per concern (``controller_*.py``,
``motion_*.py``), mixins over a class of the state they share. CPython finds a method of a base
through its method cache, whatever the classes. MicroPython looks a method up class by class at every
call, and, since these classes have properties, looks every attribute store up in all of them first:
on its unix port a command took up to 20 % longer through the mixins than through the one class they
were split from (``benchmarks/firmware_command_time.py``). :func:`flat` gives MicroPython that one
class back: every part's functions and properties in one class without bases, its dictionary filled
as the class statement fills one (its ``__module__`` and ``__qualname__`` first; MicroPython's
dictionaries grow only when full, and with one entry fewer the controller's class came out full, so
that a name it lacks, looked up on every attribute store, was searched through every entry: a store
took 270 ns against 115-160).
"""

import sys

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any, TypeVar

    T = TypeVar("T")

MICROPYTHON = sys.implementation.name == "micropython"
_NOT_COPIED = ("__module__", "__qualname__", "__dict__", "__weakref__", "__doc__")


def flat(cls: "type[T]") -> "type[T]":
    """``cls`` on CPython; on MicroPython, a class of the same name without bases that holds what
    ``cls`` and its bases define. A name defined by two of them is a TypeError: the parts' concerns do
    not overlap, so no lookup order has to decide between them."""
    if not MICROPYTHON:
        return cls
    own = cls.__dict__
    names: dict[str, Any] = {key: own[key] for key in ("__module__", "__qualname__") if key in own}
    _gather(cls, names, [])
    flattened: type[T] = type(cls.__name__, (), names)
    return flattened


def _gather(cls: type, names: "dict[str, Any]", seen: "list[type]") -> None:
    """Add the functions and properties of ``cls`` and its bases (each class once) to ``names``."""
    if cls is object or cls in seen:
        return
    seen.append(cls)
    for name, value in cls.__dict__.items():
        if name in _NOT_COPIED:
            continue
        if name in names:
            raise TypeError(f"{name} of {cls.__name__} is defined by another part too")
        names[name] = value
    for base in cls.__bases__:
        _gather(base, names, seen)
