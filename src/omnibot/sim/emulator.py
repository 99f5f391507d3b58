"""``omnibot sim --pty``: the simulated controller on a pseudo-terminal, in real time.

The first line on stdout is the pty's device path, so any serial program (pyserial, minicom, the
omnibot client with ``--port /dev/pts/N``) can open it. The path is printed only once the emulator can
answer in real time: the arguments are checked, the truth file is open and the physics kernels are
loaded from numba's cache, or, on a first start with no cache, their Python twins chosen while a
process of its own compiles them (:mod:`omnibot.sim.jit`), so the first HELLO is answered at once. Bytes are paced to the baud rate in both directions. SIGINT, SIGTERM or SIGHUP (not
under ``nohup``) end it cleanly: the pty is closed, the truth file flushed and closed. Started by
:func:`spawn_pty_emulator` (``omnibot demo``), it also ends when that parent is gone (killed by
SIGKILL, the parent could not end it: it would serve nobody for ever).

With several ``--robot`` options (:func:`run_pty_fleet`) the robots share one world and one clock
(:class:`~omnibot.sim.fleet.Fleet`), each on its own pty: a line ``NAME PATH`` per robot, so a fleet
can be driven from separate processes on one machine.

A robot whose description has a ``scanner`` gets a second pty serving an emulated Slamtec RPLIDAR
(:class:`~omnibot.lidar.rplidar_device.RplidarDevice`) fed by the simulator's scanner, at the
RPLIDAR's own baud rate (A1 115200, A2 256000) and in the same real-time loop as the controller:
a line ``scanner PATH`` after the controller's path (``NAME/scanner PATH`` after a fleet's lines),
so the rplidar driver or Slamtec's tools read the simulated scanner as they read the real one
(docs/lidar.md). The first line stays the controller's path (or a fleet's ``NAME PATH`` lines).
"""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import tempfile
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import IO, Any, TextIO, cast

from omnibot.errors import ConfigError
from omnibot.lidar import A1, RplidarDevice, ScanningSim, model_named
from omnibot.motion import Pose2D
from omnibot.robot import RobotDescription
from omnibot.signals import ending_signals
from omnibot.sim.device import SimDevice
from omnibot.sim.simulator import Simulator
from omnibot.sim.truth import TruthRecorder
from omnibot.transport import DEFAULT_BAUD
from omnibot.transport.pty_bridge import PtyBridge, serve_together


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
    wrap: Callable[[Any], Any] | None = None,
) -> int:
    """Serve the simulated robot on a new pty until ``stop`` is set or SIGINT/SIGTERM/SIGHUP; its status.
    ConfigError (before the pty exists) for a bad baud rate or a truth file that cannot be written.
    ``wrap(device)``: what the pty serves instead of the simulated device (``omnibot sim --log``'s
    recorder, :class:`omnibot.logs.device.RecordedDevice`: the bytes both ways and the truth)."""
    from omnibot.sim import jit

    if baud < 0:
        raise ConfigError(f"expected a baud rate >= 0 (0: unpaced), got {baud}", key="--baud")
    stop = stop or threading.Event()
    try:
        recorder = TruthRecorder(truth) if truth is not None else None
    except OSError as exc:
        raise ConfigError(f"cannot write {truth}: {exc.strerror}", key="--truth") from None
    previous: dict[signal.Signals, Any] = {}

    def _on_signal(signum: int, frame: FrameType | None) -> None:
        stop.set()

    try:
        jit.active.choose()  # loaded (or their twins chosen) before the pty: no first step stalls
        sim_device = SimDevice(robot, seed=seed, surface=surface, world=world, truth_recorder=recorder)
        device: Any = sim_device if wrap is None else wrap(sim_device)
        lidar = scanner_device(sim_device.sim, sim_device.tick)
        bridges = [PtyBridge(device, baud=baud)]
        try:
            if lidar is not None:
                bridges.append(PtyBridge(lidar, baud=lidar.model.baud))
            _end_with_parent(stop)
            if threading.current_thread() is threading.main_thread():
                for sig in _ending_signals():
                    previous[sig] = signal.signal(sig, _on_signal)
            print(bridges[0].path, file=out)
            if lidar is not None:
                print("scanner", bridges[1].path, file=out)
            out.flush()
            serve_together(bridges, _stepping(device.step, [lidar]), stop)
        finally:
            for bridge in bridges:
                bridge.close()
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if recorder is not None:
            recorder.close()
    return 0


def scanner_device(sim: Simulator, tick: float) -> RplidarDevice | None:
    """An emulated RPLIDAR fed with every scan of ``sim``'s scanner while a host has a scan running
    (the simulator measures only then), stepped with ticks of ``tick`` s; None when the robot has
    no scanner. The model is the description's (``rplidar-a1``,
    ``rplidar-a2``; another model is served as an A1); the nodes per second are the scanner's rays x
    rate, at most the model's standard-scan rate (each revolution is resampled to fit)."""
    spec = getattr(sim.robot, "scanner", None)
    if spec is None or getattr(sim, "scanner", None) is None:
        return None
    try:
        model = model_named(str(spec.model))
    except ConfigError:
        model = A1
    rate = min(float(spec.rays) * float(spec.rate_hz), model.sample_rate)
    scanning = cast(ScanningSim, sim)

    def listen(on: bool) -> None:  # the simulator measures only while a host has a scan running
        if on:
            scanning.add_scan_listener(device.feed)
        else:
            scanning.remove_scan_listener(device.feed)

    device = RplidarDevice(model, tick=tick, sample_rate=rate, start_time=sim.time, on_scanning=listen)
    return device


def _stepping(step: Callable[[], None], lidars: list[RplidarDevice | None]) -> Callable[[], None]:
    """``step`` and then every scanner device's step: one tick of the whole emulator."""
    scanners = [lidar for lidar in lidars if lidar is not None]
    if not scanners:
        return step

    def both() -> None:
        step()
        for lidar in scanners:
            lidar.step()

    return both


PARENT_ENV = "OMNIBOT_SIM_PARENT"
"""Set by :func:`spawn_pty_emulator` to its PID: the emulator ends once its parent is another."""
PARENT_POLL = 0.5
"""s between two looks at the parent."""


def _end_with_parent(stop: threading.Event) -> None:
    """With :data:`PARENT_ENV` set, set ``stop`` once this process's parent is no longer that PID
    (it died: the orphan was handed to init or a subreaper)."""
    parent = os.environ.get(PARENT_ENV, "")
    if not parent.isdigit():
        return

    def watch() -> None:
        while not stop.wait(PARENT_POLL):
            if os.getppid() != int(parent):
                stop.set()

    threading.Thread(target=watch, name="omnibot-parent-watch", daemon=True).start()


def _ending_signals() -> list[signal.Signals]:
    """The signals that end the emulator cleanly: SIGINT, and those that end any omnibot process."""
    return [signal.SIGINT, *ending_signals()]


@dataclass(frozen=True)
class FleetMember:
    """One robot of ``omnibot sim --pty`` with several ``--robot``: ``PRESET_OR_FILE?name=R&pose=X,Y,THETA&seed=N``."""

    robot: str
    name: str
    seed: int
    pose: Pose2D | None = None


MEMBER_OPTIONS = ("name", "pose", "seed")


def parse_member(text: str, index: int, seed: int) -> FleetMember:
    """A ``--robot`` of a fleet: the preset or file, then the robot's own options as in a ``sim://``
    URL (``name`` default ``r1``, ``r2``... by position, ``seed`` default ``seed + index``, ``pose``
    default the world's start). ConfigError naming ``--robot`` for anything else."""
    from omnibot.sim.fleet_link import parse_pose

    target, _, query = text.partition("?")
    options: dict[str, str] = {}
    for piece in query.split("&") if query else []:
        key, _, value = piece.partition("=")
        if key not in MEMBER_OPTIONS:
            raise ConfigError(
                f"unknown option {key!r} in --robot {text!r}: a robot of a fleet takes "
                f"{', '.join(MEMBER_OPTIONS)} (world, surface and baud are the fleet's: --world ...)",
                key="--robot",
            )
        if key in options:
            raise ConfigError(f"option {key!r} given twice in --robot {text!r}", key="--robot")
        options[key] = value
    if not target:
        raise ConfigError(f"--robot {text!r} names no robot (e.g. omni4?name=r1&pose=1,1,0)", key="--robot")
    try:
        own_seed = int(options.get("seed", seed + index))
        if own_seed < 0:
            raise ValueError(own_seed)
    except ValueError:
        raise ConfigError(f"expected seed=N (N >= 0) in --robot {text!r}", key="--robot") from None
    try:
        pose = parse_pose(options["pose"]) if "pose" in options else None
    except ConfigError as exc:
        raise ConfigError(f"{str(exc).removeprefix('pose: ')} in --robot {text!r}", key="--robot") from None
    return FleetMember(target, options.get("name") or f"r{index + 1}", own_seed, pose)


def run_pty_fleet(
    members: list[FleetMember],
    *,
    surface: str | None = None,
    world: str | None = None,
    baud: int = DEFAULT_BAUD,
    stop: threading.Event | None = None,
    out: TextIO = sys.stdout,
) -> int:
    """Serve several simulated robots in one world, one pty each, on one real-time clock, until
    ``stop`` or SIGINT/SIGTERM/SIGHUP; exit status. Prints ``NAME PATH`` per robot once all can answer.
    ConfigError (before any pty exists) for a bad baud rate, a name taken twice or a pose that
    overlaps a wall, an obstacle or another robot."""
    from omnibot.sim import jit
    from omnibot.sim.fleet import Fleet
    from omnibot.sim.world import load_world

    if baud < 0:
        raise ConfigError(f"expected a baud rate >= 0 (0: unpaced), got {baud}", key="--baud")
    stop = stop or threading.Event()
    room = load_world(world or "empty")
    fleet = Fleet(room.with_floor(surface) if surface is not None and surface != room.floor else room)
    for member in members:
        try:
            fleet.add(member.name, member.robot, seed=member.seed, pose=member.pose)
        except ConfigError as exc:
            text = str(exc).removeprefix(f"{exc.key}: ") if exc.key else str(exc)
            raise ConfigError(text, key="--robot") from None
    previous: dict[signal.Signals, Any] = {}

    def _on_signal(signum: int, frame: FrameType | None) -> None:
        stop.set()

    jit.active.choose()
    bridges: list[PtyBridge] = []
    lidars: list[tuple[str, RplidarDevice]] = []
    try:
        for name in fleet.names:
            bridges.append(PtyBridge(fleet.device(name), baud=baud))
        for name in fleet.names:
            lidar = scanner_device(fleet.device(name).sim, fleet.device(name).tick)
            if lidar is not None:
                lidars.append((name, lidar))
                bridges.append(PtyBridge(lidar, baud=lidar.model.baud))
        if threading.current_thread() is threading.main_thread():
            for sig in _ending_signals():
                previous[sig] = signal.signal(sig, _on_signal)
        for name, bridge in zip(fleet.names, bridges, strict=False):
            print(name, bridge.path, file=out)
        for (name, _), bridge in zip(lidars, bridges[len(fleet.names) :], strict=True):
            print(f"{name}/scanner", bridge.path, file=out)
        out.flush()
        serve_together(bridges, _stepping(fleet.step, [lidar for _, lidar in lidars]), stop)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        for bridge in bridges:
            bridge.close()
    return 0


START_TIMEOUT = 120.0
"""s :func:`spawn_pty_emulator` waits for the device path (about a second of CPU, with or without
numba's cache: :mod:`omnibot.sim.jit`; on a loaded machine the wall time can be many times that)."""


def _one_line(stderr: str) -> str:
    """What a child ``omnibot`` said on stderr, as one line (its ``omnibot: error:`` prefix dropped)."""
    lines = [line.strip().removeprefix("omnibot: error: ") for line in stderr.splitlines() if line.strip()]
    return "; ".join(lines).replace(":; ", ": ") or "it said nothing"


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
    started: Callable[[int], object] | None = None,
) -> Iterator[str]:
    """Run ``omnibot sim --pty`` as a child process and yield its device path; on exit SIGINT it,
    wait for it (killing it if it hangs) and close its files. ConfigError (the command could not
    start) if it does not start within ``start_timeout`` s. ``notice`` (e.g. a line on a terminal) hears what is being waited for when
    the start takes longer than a second; ``started`` hears the child's process id once it runs. The
    child's stderr goes to a temporary file (read for the error when it fails), so that however much
    it writes there it never blocks.

    The child runs in a session of its own, as an emulator started from another terminal does: it
    stands for the robot's controller, a processor of its own, so what the caller's session runs
    must not take its share of the CPU. With Linux's autogroup scheduling (a group per session) two
    busy loops in the caller's session left the emulator runnable but unscheduled for 0.4-2 s at a
    time on a loaded machine (BENCHMARKS.md, protocol throughput). A Ctrl-C at the terminal reaches
    the caller only, which then ends the child as above (after its own cleanup on the line)."""
    argv = [sys.executable, "-m", "omnibot", "sim", "--pty", "--robot", robot, "--seed", str(seed)]
    argv += ["--world", world] if world else []
    argv += ["--surface", surface] if surface else []
    argv += ["--truth", str(truth)] if truth else []
    with tempfile.TemporaryFile("w+") as err:
        env = {**os.environ, PARENT_ENV: str(os.getpid())}
        proc = subprocess.Popen(
            argv,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=err,
            text=True,
            env=env,
            start_new_session=True,
        )
        try:
            if started is not None:
                started(proc.pid)
            yield _device_path(proc, err, robot, notice, start_timeout)
        finally:
            _end_child(proc)


def _device_path(
    proc: subprocess.Popen[str],
    err: IO[str],
    robot: str,
    notice: Callable[[str], object] | None,
    start_timeout: float,
) -> str:
    """The device path the child ``omnibot sim --pty`` prints first (``notice`` hears it is awaited
    after a second); ConfigError when it prints none within ``start_timeout`` s or ends."""
    assert proc.stdout is not None
    ready, _, _ = select.select([proc.stdout], [], [], 1.0)
    if not ready:
        if notice is not None:
            notice(f"starting the simulated {robot} (omnibot sim --pty, up to {start_timeout:g} s)...")
        ready, _, _ = select.select([proc.stdout], [], [], max(start_timeout - 1.0, 0.0))
    # the emulator is the link: if it does not start, the command could not (ConfigError)
    if not ready:
        raise ConfigError(f"the pty emulator printed no device path within {start_timeout:g} s")
    path = proc.stdout.readline().strip()
    if not path:  # its stdout closed: it is ending
        proc.wait(timeout=10)
        err.seek(0)
        raise ConfigError(f"the pty emulator did not start: {_one_line(err.read())}")
    return path


def _end_child(proc: subprocess.Popen[str]) -> None:
    """SIGINT the child if it still runs, wait for it (killing it if it hangs) and close its stdout."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
    if proc.stdout is not None:
        proc.stdout.close()
