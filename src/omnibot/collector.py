"""Python's cyclic garbage collector while a command starts: collected seldom, then what the start
built frozen out of its sight.

A command's start imports about a thousand modules and builds their classes, numba's registries,
pydantic's models and the simulator: some 160,000 objects that live as long as the process. With
CPython's default thresholds (700, 10, 10) the collector runs about 400 times while they are made,
young objects each time, now and then all of them: 0.14-0.20 s of the 1.35 s of CPU an
``omnibot ros2 --port sim://omni4`` bridge took until it ended (BENCHMARKS.md, "Start-up"). So
the process's own command line (:func:`omnibot.cli.main` without ``argv``) runs under
:func:`starting`, and so does the kernels' compiling process (:mod:`omnibot.sim.jit`): a
collection only every :data:`START_THRESHOLD` new objects. A command whose work is a loop ends its start with
:func:`release` as the loop begins (:meth:`omnibot.runtime.Runtime.run`, the pty bridges'
:func:`~omnibot.transport.pty_bridge.serve_together`): what the start built is frozen (``gc.freeze``:
not scanned again while the process runs, so any of it that becomes cyclic garbage meanwhile waits,
at most the start's own size) and the default thresholds come back, so the loop neither rescans the
start's objects nor waits on long collections. A command that never releases collects every
:data:`START_THRESHOLD` objects until it ends, then releases.

The frozen objects stay frozen at the interpreter's exit: its last collection leaves them to the
operating system instead of taking the start's heap apart (numba's, cyclonedds', pydantic's
reference cycles: 0.3 s of CPU at the end of every bridge, measured). CPython does not promise to
finalise what is still alive at exit anyway, and omnibot closes what it opens (links, logs, nodes,
ptys) itself, so collecting is all this changes: when memory is given back, never what a command
does or writes.
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
    with _HOLD.lock:
        if _HOLD.saved is None:
            return
        gc.freeze()
        gc.set_threshold(*_HOLD.saved)
        _HOLD.saved = None


def held() -> bool:
    """Whether a start holds the collector (:func:`hold` without :func:`release` yet)."""
    return _HOLD.saved is not None


@contextlib.contextmanager
def starting() -> Iterator[None]:
    """:func:`hold` for the block, :func:`release` at its end if no loop released it (so that the
    thresholds restored do not set the collector on every object the command made at once)."""
    hold()
    try:
        yield
    finally:
        release()


__all__ = ["START_THRESHOLD", "held", "hold", "release", "starting"]
