"""The leak check's own parts (tests/conftest.py): the children it finds are the ones a scan of every
process finds, whichever thread started them, zombies included."""

from __future__ import annotations

import os
import subprocess
import threading

import pytest

from tests.conftest import _children, _children_by_scan


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="no /proc")
def test_children_are_found_from_any_thread_until_reaped() -> None:
    before = _children()
    assert before == _children_by_scan(os.getpid())
    started, done = threading.Event(), threading.Event()
    procs: list[subprocess.Popen[bytes]] = []

    def start_one() -> None:  # a thread that lives on with its child
        procs.append(subprocess.Popen(["sleep", "30"]))
        started.set()
        done.wait(30)

    worker = threading.Thread(target=start_one)
    worker.start()
    try:
        assert started.wait(30)
        reaped = subprocess.Popen(["true"])
        reaped.wait()  # reaped: not a child any more
        zombie = subprocess.Popen(["true"])
        os.waitid(os.P_PID, zombie.pid, os.WEXITED | os.WNOWAIT)  # exited, not yet reaped: still a child
        found = _children() - before
        assert found == {procs[0].pid, zombie.pid}
        assert found == _children_by_scan(os.getpid()) - before
        zombie.wait()
    finally:
        done.set()
        worker.join()
        procs[0].kill()
        procs[0].wait()
    assert _children() == before
