"""``omnibot sim --pty``: the simulated controller on a pseudo-terminal, in real time.

The first line on stdout is the pty's device path, so any serial program (pyserial, minicom, the
omnibot client with ``--port /dev/pts/N``) can open it. Bytes are paced to the baud rate in both
directions. SIGINT or SIGTERM end it cleanly: the pty is closed, the truth file flushed and closed.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import Any, TextIO

from omnibot.errors import LinkError
from omnibot.robot.description import RobotDescription
from omnibot.sim.device import SimDevice
from omnibot.sim.simulator import TruthRecorder
from omnibot.transport.lockstep import DEFAULT_BAUD
from omnibot.transport.pty_bridge import PtyBridge


def run_pty_emulator(
    robot: RobotDescription,
    *,
    seed: int = 0,
    surface: str | None = None,
    world: str | None = None,
    truth: Path | None = None,
    baud: int = DEFAULT_BAUD,
    stop: threading.Event | None = None,
    out: TextIO = sys.stdout,
) -> int:
    """Serve the simulated robot on a new pty until ``stop`` is set or SIGINT/SIGTERM; exit status."""
    stop = stop or threading.Event()
    recorder = TruthRecorder(truth) if truth is not None else None
    previous: dict[signal.Signals, Any] = {}

    def _on_signal(signum: int, frame: FrameType | None) -> None:
        stop.set()

    try:
        device = SimDevice(robot, seed=seed, surface=surface, world=world, truth_recorder=recorder)
        bridge = PtyBridge(device, baud=baud)
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                previous[sig] = signal.signal(sig, _on_signal)
        print(bridge.path, file=out, flush=True)
        try:
            bridge.run(stop)
        finally:
            bridge.close()
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if recorder is not None:
            recorder.close()
    return 0


@contextmanager
def spawn_pty_emulator(
    robot: str,
    *,
    seed: int = 0,
    world: str | None = None,
    truth: Path | None = None,
    surface: str | None = None,
) -> Iterator[str]:
    """Run ``omnibot sim --pty`` as a child process and yield its device path; on exit SIGINT it,
    wait for it (killing it if it hangs) and close its pipes. LinkError if it does not start."""
    argv = [sys.executable, "-m", "omnibot", "sim", "--pty", "--robot", robot, "--seed", str(seed)]
    argv += ["--world", world] if world else []
    argv += ["--surface", surface] if surface else []
    argv += ["--truth", str(truth)] if truth else []
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        path = proc.stdout.readline().strip()
        if not path:
            _, err = proc.communicate(timeout=10)
            raise LinkError(f"the pty emulator did not start: {err.strip()}")
        yield path
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        for stream in (proc.stdout, proc.stderr):
            if stream is not None:
                stream.close()
