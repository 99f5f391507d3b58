"""Python's cyclic garbage collector while a command starts: collected seldom, then what the start
built frozen out of its sight.

A command's start imports about a thousand modules and builds their classes, numba's registries,
pydantic's models and the simulator: some 160,000 objects that live as long as the process. With
CPython's default thresholds (700, 10, 10) the collector runs about 400 times while they are made,
young objects each time, now and then all of them: 0.25-0.35 s of the 1.5-1.9 s of CPU an
``omnibot ros2 --port sim://omni4`` start takes (BENCHMARKS.md, "Start-up"). So the process's own
command line (:func:`omnibot.cli.main` without ``argv``) starts under :func:`starting`: a collection
only every :data:`START_THRESHOLD` new objects. A command whose work is a loop ends its start with
:func:`release` as the loop begins (:meth:`omnibot.runtime.Runtime.run`, the pty bridges'
:func:`~omnibot.transport.pty_bridge.serve_together`): what the start built is frozen (``gc.freeze``:
never scanned again; the few thousand objects of its cyclic garbage stay with it) and the default
thresholds come back, so the loop neither rescans the start's objects nor waits on long collections.
A command that never releases keeps collecting, every :data:`START_THRESHOLD` objects, until it ends.

Collecting is all this changes: when objects are freed, never what a command does.
"""

from __future__ import annotations

import contextlib
import gc
import threading
from collections.abc import Iterator

START_THRESHOLD = 100_000
"""New container objects (net of those freed) between two collections while a command starts,
where CPython's default is 700: a start's 160,000 objects see two collections instead of 400."""


class _Hold:
    """The thresholds :func:`hold` replaced, to restore (None: not held), under a lock (the robots
    of ``omnibot ros2`` each run their loop in a thread)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.saved: tuple[int, ...] | None = None


_HOLD = _Hold()


def hold() -> None:
    """Collect every :data:`START_THRESHOLD` new objects until :func:`release` (nothing if held already)."""
    with _HOLD.lock:
        if _HOLD.saved is None:
            _HOLD.saved = gc.get_threshold()
            gc.set_threshold(START_THRESHOLD, *_HOLD.saved[1:])


def release() -> None:
    """The start is over: freeze every object there is now (``gc.freeze``) and restore the thresholds
    :func:`hold` found. Nothing unless held (a loop run by a test or a library is left alone)."""
    _restore(freeze=True)


def held() -> bool:
    """Whether a start holds the collector (:func:`hold` without :func:`release` yet)."""
    return _HOLD.saved is not None


@contextlib.contextmanager
def starting() -> Iterator[None]:
    """:func:`hold` for the block; at its end the thresholds restored if no loop released them (nothing
    frozen then: the command is over)."""
    hold()
    try:
        yield
    finally:
        _restore(freeze=False)


def _restore(*, freeze: bool) -> None:
    with _HOLD.lock:
        if _HOLD.saved is None:
            return
        if freeze:
            gc.freeze()
        gc.set_threshold(*_HOLD.saved)
        _HOLD.saved = None


__all__ = ["START_THRESHOLD", "held", "hold", "release", "starting"]
