"""Which kernels the simulator runs: the compiled ones, or their Python twins while those compile.

Compiling the kernels (:mod:`omnibot.sim.kernels`) takes 18-22 s of CPU, most of it
:func:`~omnibot.sim.kernels.robot_step`; from numba's disk cache they load in a few tenths of a
second. The simulator calls them through :data:`active` (``jit.active.robot_step(...)``), whose
first use in a process looks in the cache:

* the cache holds every kernel a simulator calls (:data:`~omnibot.sim.kernels.SIMULATOR_KERNELS`):
  they are loaded, and :data:`active` holds the compiled kernels from then on;
* it does not: :data:`active` holds their twins (:mod:`omnibot.sim.twins`: the same code run by
  CPython, the same numbers bit for bit; one robot's step takes about 0.1 ms instead of 6 us, a
  tenth of real time at 1 kHz), and a process of its own (``python -m omnibot.sim.jit``) compiles
  every kernel into the cache. When it ends, a thread here loads them and switches :data:`active`
  over between two calls; nothing else changes.

So a first start on a fresh install answers at once, in real time, while the compiling happens on
another core. The compiler runs in a process, not a thread, because numba's compiler holds the
GIL: a busy loop beside a compiling thread kept 38 % of its speed, with pauses up to 0.7 s. It runs
in a session of its own and is left to finish when the command that started it ends, so that the
cache gets filled and the next start is warm. Processes starting cold together compile once: the
compiling process holds a lock on the kernels package's ``__init__.py`` (``make setup`` takes it
too), the others wait and then load what the first compiled. Should the compiling process fail, the thread compiles the
kernels itself (the twins run meanwhile).
"""

from __future__ import annotations

import fcntl
import logging
import os
import subprocess
import sys
import tempfile
import threading
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from numba.core import event

from omnibot import collector
from omnibot.sim import kernels
from omnibot.sim.twins import python_twins

logger = logging.getLogger(__name__)

CALLED: tuple[str, ...] = (*(k.py_func.__name__ for k in kernels.KERNELS), "physics_step_parallel")
"""The kernels :data:`active` holds: every kernel the simulator's modules call."""

COMPILED, PYTHON = "compiled", "python"


class _NotCached(Exception):
    """A kernel that :func:`load_cached` would have had to compile."""


class _RefuseToCompile(event.Listener):
    """Numba's compile event, refused in one thread (its START comes after the cache was looked in)."""

    def __init__(self, thread: int) -> None:
        self.thread = thread

    def on_start(self, event: event.Event) -> None:
        if threading.get_ident() == self.thread:
            raise _NotCached

    def on_end(self, event: event.Event) -> None:
        pass


def load_cached() -> bool:
    """Load every kernel of :data:`~omnibot.sim.kernels.SIMULATOR_KERNELS` from numba's cache, with
    the argument types the simulator passes; False, compiling nothing, at the first one not there."""
    with event.install_listener("numba:compile", _RefuseToCompile(threading.get_ident())):
        try:
            _load_simulator_kernels()
        except _NotCached:
            return False
    return True


def _load_simulator_kernels() -> None:
    """Load (or compile) the simulator's kernels with the argument types it passes."""
    for kernel, call in kernels.warm_up_calls():
        if kernel in kernels.SIMULATOR_KERNELS:
            call()


def fill_cache() -> None:
    """Compile every kernel into numba's cache (or load those already there) while holding the lock
    on the kernels package's ``__init__.py``: what ``make setup`` and the compiling process of a
    cold start run."""
    with open(kernels.__file__, "rb") as source:
        fcntl.flock(source, fcntl.LOCK_EX)  # released when the file closes
        kernels.warm_up()


class ActiveKernels:
    """The kernels the simulator calls, by name (:data:`CALLED`): compiled, or their twins until the
    compiled ones are ready. Chosen on first use (:meth:`choose`)."""

    if TYPE_CHECKING:  # each kernel's signature, for the type checker (instance attributes at run time)
        outline_contacts = staticmethod(kernels.outline_contacts)
        robot_step = staticmethod(kernels.robot_step)
        fleet_step = staticmethod(kernels.fleet_step)
        cone_distance = staticmethod(kernels.cone_distance)
        scan_index = staticmethod(kernels.scan_index)
        scan_rays = staticmethod(kernels.scan_rays)
        scan_measure = staticmethod(kernels.scan_measure)
        scan_revolution = staticmethod(kernels.scan_revolution)
        scan_index_around = staticmethod(kernels.scan_index_around)
        pose_log = staticmethod(kernels.pose_log)
        physics_step = staticmethod(kernels.physics_step)
        contact_speeds = staticmethod(kernels.contact_speeds)
        surface_probe = staticmethod(kernels.surface_probe)
        robot_before = staticmethod(kernels.robot_before)
        robot_after = staticmethod(kernels.robot_after)
        gyro_update = staticmethod(kernels.gyro_update)
        gyro_measure = staticmethod(kernels.gyro_measure)
        tracking_update = staticmethod(kernels.tracking_update)
        physics_step_parallel = staticmethod(kernels.physics_step_parallel)

    def __init__(self) -> None:
        self._choosing = threading.Lock()
        self._settled = threading.Event()
        self._error: BaseException | None = None
        self.kind = ""
        """:data:`COMPILED` or :data:`PYTHON` once chosen, "" before."""

    def __getattr__(self, name: str) -> Callable[..., Any]:
        # reached only before the choice: it makes every kernel an attribute of the instance
        if name not in CALLED:
            raise AttributeError(f"{type(self).__name__} has no kernel {name!r}")
        self.choose()
        return cast(Callable[..., Any], self.__dict__[name])

    def choose(self) -> str:
        """The compiled kernels when numba's cache holds them (loaded now), else their twins and a
        process compiling them (:mod:`omnibot.sim.jit`); the kind chosen (the first call chooses; a
        later one gives the kind in use)."""
        with self._choosing:
            if self.kind:
                return self.kind
            if load_cached():
                self._use(COMPILED, _compiled())
                self._settled.set()
                return COMPILED
            self._use(PYTHON, python_twins(kernels))
            threading.Thread(target=self._compile_meanwhile, name="omnibot-kernels", daemon=True).start()
            return PYTHON

    def wait(self, timeout: float | None = None) -> bool:
        """Whether the compiled kernels are in use, waiting up to ``timeout`` s (None: for ever) for
        a compile under way to end (False at once before the choice). Raises what compiling raised."""
        if self.kind:
            self._settled.wait(timeout)
        if self._error is not None:
            raise self._error
        return self.kind == COMPILED

    def _use(self, kind: str, implementation: Mapping[str, Callable[..., Any]]) -> None:
        self.__dict__.update({name: implementation[name] for name in CALLED})
        self.kind = kind

    def _compile_meanwhile(self) -> None:
        """The thread of a cold start: the compiling process, then the switch to what it compiled."""
        try:
            try:
                status, said = _compile_in_own_process()
                failure = f"exit status {status}: {said or 'it said nothing'}" if status else ""
            except OSError as exc:
                failure = f"not started: {exc}"
            if failure:
                logger.warning(
                    "compiling the simulator's kernels in a process of their own failed (%s); compiling "
                    "them here",
                    failure,
                )
            _load_simulator_kernels()
            self._use(COMPILED, _compiled())
        except Exception as exc:  # the twins keep running: slower, the same numbers
            logger.error("the simulator's kernels did not compile (%s): it runs them as Python", exc)
            self._error = exc
        finally:
            self._settled.set()

    def _forget(self) -> None:
        """In a child forked before the switch (the thread did not follow it): choose again."""
        if self.kind == PYTHON:
            for name in CALLED:
                self.__dict__.pop(name, None)
            self.kind = ""
            self._choosing = threading.Lock()
            self._settled = threading.Event()


def _compiled() -> dict[str, Callable[..., Any]]:
    return {name: getattr(kernels, name) for name in CALLED}


def _compile_in_own_process() -> tuple[int, str]:
    """Run ``python -m omnibot.sim.jit`` (:func:`fill_cache`) on this very omnibot and wait for it;
    its exit status and the last line it wrote on stderr."""
    package_root = str(Path(__file__).resolve().parents[2])
    path = [package_root, *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))]
    with tempfile.TemporaryFile("w+") as err:
        process = subprocess.Popen(
            [sys.executable, "-P", "-m", __name__],  # -P: nothing ahead of package_root
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=err,
            env={**os.environ, "PYTHONPATH": os.pathsep.join(path)},
            start_new_session=True,  # finishes the cache if this process ends first
        )
        status = process.wait()
        err.seek(0)
        lines = [line.strip() for line in err.read().splitlines() if line.strip()]
    return status, lines[-1] if lines else ""


active = ActiveKernels()
"""The kernels the simulator calls (``jit.active.robot_step(...)``)."""
os.register_at_fork(after_in_child=active._forget)

__all__ = ["CALLED", "COMPILED", "PYTHON", "ActiveKernels", "active", "fill_cache", "load_cached"]


if __name__ == "__main__":  # the compiling process of a cold start, and make setup's
    with collector.starting():  # numba's compiler makes objects by the million: collected seldom
        fill_cache()
