"""Shared test fixtures. Every test runs under a leak check.

``no_leaks`` (autouse) fails a test that leaves behind threads, child processes or open file
descriptors (ptys, sockets, files). It snapshots them before the test and compares after, giving
threads and children a short grace period to finish (a stopped helper may still be unwinding).
A test that leaks on purpose (e.g. a process-wide cache opened on first use) can opt out with
``@pytest.mark.allow_leaks("why")``.

``pytest -n N`` (pytest-xdist, as ``make test`` runs the suite) hands whole modules to the workers,
the costliest first, and leaves the tests marked ``serial`` to a pass of their own: ``tests/parallel.py``
says which and why.

Hypothesis runs derandomized (the same examples every run, no example database), so a property test
passes or fails the same way on every machine; a test's own ``@settings`` adds to this profile.
"""

from __future__ import annotations

import gc
import os
import signal
import sys
import threading
import time
from collections.abc import Generator, Iterator
from pathlib import Path

import pytest
from hypothesis import settings

from tests import cpu_times, parallel

settings.register_profile("omnibot", derandomize=True, database=None, deadline=None)
"""The same examples every run, none remembered between runs, and no time limit per example: an example
slower than hypothesis's 200 ms default on a loaded worker is not a failure (how fast code runs is a
benchmark's business, not a test's)."""
settings.load_profile("omnibot")

GRACE = 10.0
"""Seconds to wait for stragglers before calling it a leak: a deadline (the check ends as soon as they
are gone), generous because a loaded machine may not run a thread that is unwinding for a while."""


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--cpu-times",
        metavar="DIR",
        help="record each test's CPU and wall seconds in DIR (python -m tests.cpu_times DIR sums them per unit)",
    )


def pytest_configure(config: pytest.Config) -> None:
    if config.getoption("cpu_times"):
        config.pluginmanager.register(cpu_times.Recorder(Path(config.getoption("cpu_times"))), "cpu_times")
    config.addinivalue_line("markers", "allow_leaks(reason): skip the thread/process/fd leak check")
    config.addinivalue_line(
        "markers", "serial: needs the machine to itself; make test runs it after the parallel pass"
    )
    # A shell's background job (``pytest ... &``) starts with SIGINT ignored, and children inherit an
    # ignored signal: the commands under test would then never see the Ctrl-C the tests send them.
    # A handler here is reset to the default in every child, as a terminal's foreground job has it.
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.hookimpl(tryfirst=True)  # before -m selects on the marks
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    parallel.mark_serial(items)


@pytest.hookimpl(wrapper=True)
def pytest_collection() -> Generator[None, object, object]:
    """No garbage collection while the suite is collected: its imports and items (about a million
    objects) are what a collection would scan, again and again as they grow (nearly half the CPU of
    collecting, measured). Then the garbage of collecting freed at once and what is left frozen
    (modules, functions, items: they live for the session), so that no later collection scans it
    again; each test's own objects are collected as before. (xdist's controller collects nothing:
    it passes through here at once.)"""
    gc.disable()
    try:
        return (yield)
    finally:
        gc.collect()
        gc.freeze()
        gc.enable()


@pytest.hookimpl(tryfirst=True, optionalhook=True)  # before xdist's own choice; none without xdist
def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object | None:
    return parallel.scheduler(config, log) if config.getvalue("dist") == "load" else None


PROCESS_CACHES = ("/matplotlib/mpl-data/fonts/",)
"""Files libraries keep open for the life of the process by design (matplotlib's font cache)."""


def _open_fds() -> dict[int, str]:
    fds: dict[int, str] = {}
    for name in os.listdir("/proc/self/fd"):
        try:
            target = os.readlink(f"/proc/self/fd/{name}")
        except OSError:  # the directory's own fd, already closed again
            continue
        if not any(cache in target for cache in PROCESS_CACHES):
            fds[int(name)] = target
    return fds


def _children() -> set[int]:
    """Pids whose parent is this process (zombies included: not reaped is a leak too).

    Read from each of this process's threads' ``children`` list (Linux 3.5+): a few files, where a
    scan of every process's ``stat`` costs milliseconds per test on a busy machine (twice per test)."""
    me = os.getpid()
    try:
        tids = os.listdir(f"/proc/{me}/task")
        found: set[int] = set()
        for tid in tids:
            with open(f"/proc/{me}/task/{tid}/children", encoding="ascii") as f:
                found.update(int(pid) for pid in f.read().split())
        return found
    except OSError:  # a thread gone between the listing and the read, or no children files
        return _children_by_scan(me)


def _children_by_scan(me: int) -> set[int]:
    found = set()
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", encoding="ascii", errors="replace") as f:
                stat = f.read()
        except OSError:
            continue
        fields = stat[stat.rfind(")") + 2 :].split()  # after "pid (comm) "; fields[1] is the ppid
        if len(fields) > 1 and int(fields[1]) == me:
            found.add(int(entry))
    return found


def _settle_kernels() -> None:
    """A cold start's compiling of the simulator's kernels (:mod:`omnibot.sim.jit`: a thread waiting
    on a process) ends within the test that began it, not as its leak: that test waits for it."""
    jit = sys.modules.get("omnibot.sim.jit")
    if jit is not None:
        jit.active.wait()


def _leaks(threads: set[threading.Thread], fds: dict[int, str], children: set[int]) -> list[str]:
    found = [f"thread {t.name!r}" for t in threading.enumerate() if t not in threads and t.is_alive()]
    found += [f"fd {fd} -> {target}" for fd, target in _open_fds().items() if fds.get(fd) != target]
    found += [f"child process {pid}" for pid in sorted(_children() - children)]
    return found


@pytest.fixture(autouse=True)
def no_leaks(request: pytest.FixtureRequest) -> Iterator[None]:
    if request.node.get_closest_marker("allow_leaks") or not os.path.isdir("/proc/self/fd"):
        yield
        return
    threads = set(threading.enumerate())
    fds = _open_fds()
    children = _children()
    yield
    _settle_kernels()
    deadline = time.monotonic() + GRACE
    leaks = _leaks(threads, fds, children)
    while leaks and time.monotonic() < deadline:
        time.sleep(0.01)
        leaks = _leaks(threads, fds, children)
    if leaks:
        pytest.fail("test leaked: " + "; ".join(leaks), pytrace=False)
