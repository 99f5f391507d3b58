"""``omnibot sim --pty``: the simulated controller on a pseudo-terminal, in real time.

The first line on stdout is the pty's device path, so any serial program (pyserial, minicom, the
omnibot client with ``--port /dev/pts/N``) can open it. The path is printed only once the emulator can
answer in real time: the arguments are checked, the truth file is open and the physics kernels are
compiled (or loaded from numba's cache), so a first start on a fresh install does not leave a HELLO
unanswered. Bytes are paced to the baud rate in both directions. SIGINT or SIGTERM end it cleanly:
the pty is closed, the truth file flushed and closed.
"""

from __future__ import annotations

import select
import signal
import subprocess
import sys
import tempfile
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import Any, TextIO

from omnibot.errors import ConfigError, LinkError
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
    log: Path | None = None,
) -> int:
    """Serve the simulated robot on a new pty until ``stop`` is set or SIGINT/SIGTERM; exit status.
    ConfigError (before the pty exists) for a bad baud rate or a truth file that cannot be written."""
    from omnibot.sim import kernels

    if baud < 0:
        raise ConfigError(f"expected a baud rate >= 0 (0: unpaced), got {baud}", key="--baud")
    stop = stop or threading.Event()
    try:
        recorder = TruthRecorder(truth) if truth is not None else None
    except OSError as exc:
        raise ConfigError(f"cannot write {truth}: {exc.strerror}", key="--truth") from None
    log_recorder = None
    if log is not None:
        from omnibot.logs.recorder import Recorder

        log_recorder = Recorder(log)  # --log: the bytes both ways and the truth (omnibot.logs.device)
    previous: dict[signal.Signals, Any] = {}

    def _on_signal(signum: int, frame: FrameType | None) -> None:
        stop.set()

    try:
        kernels.warm_up()  # compile before announcing the pty: a first step must not stall the link
        device: Any = SimDevice(robot, seed=seed, surface=surface, world=world, truth_recorder=recorder)
        if log_recorder is not None:
            from omnibot.logs.device import RecordedDevice

            device = RecordedDevice(device, log_recorder, robot)
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
        if log_recorder is not None:
            log_recorder.close()
    return 0


START_TIMEOUT = 120.0
"""s :func:`spawn_pty_emulator` waits for the device path (a first start on a fresh install compiles
the physics: seconds on a quiet machine, tens on a loaded one)."""


@contextmanager
def spawn_pty_emulator(
    robot: str,
    *,
    seed: int = 0,
    world: str | None = None,
    truth: Path | None = None,
    surface: str | None = None,
    notice: Callable[[str], object] | None = None,
    start_timeout: float = START_TIMEOUT,
) -> Iterator[str]:
    """Run ``omnibot sim --pty`` as a child process and yield its device path; on exit SIGINT it,
    wait for it (killing it if it hangs) and close its files. LinkError if it does not start within
    ``start_timeout`` s. ``notice`` (e.g. a line on a terminal) hears what is being waited for when
    the start takes longer than a second. The child's stderr goes to a temporary file (read for the
    error when it fails), so that however much it writes there it never blocks."""
    argv = [sys.executable, "-m", "omnibot", "sim", "--pty", "--robot", robot, "--seed", str(seed)]
    argv += ["--world", world] if world else []
    argv += ["--surface", surface] if surface else []
    argv += ["--truth", str(truth)] if truth else []
    with tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=err, text=True)
        try:
            assert proc.stdout is not None
            ready, _, _ = select.select([proc.stdout], [], [], 1.0)
            if not ready:
                if notice is not None:
                    notice(
                        f"starting the simulated {robot} (omnibot sim --pty; a first start compiles the "
                        f"physics, up to {start_timeout:.0f} s)..."
                    )
                ready, _, _ = select.select([proc.stdout], [], [], max(start_timeout - 1.0, 0.0))
            if not ready:
                raise LinkError(f"the pty emulator printed no device path within {start_timeout:g} s")
            path = proc.stdout.readline().strip()
            if not path:  # its stdout closed: it is ending
                proc.wait(timeout=10)
                err.seek(0)
                raise LinkError(f"the pty emulator did not start: {err.read().strip()}")
            yield path
        finally:
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            if proc.stdout is not None:
                proc.stdout.close()
