"""``omnibot demo``: seed 000's motion examples through the whole stack, commanded against achieved.

By default the robot is the simulated ``omni4`` in the ``room`` world, served by ``omnibot sim --pty``
in its own process, so every command really goes client -> text protocol -> pseudo-terminal (paced
to 115200 baud) -> firmware -> simulator, and the ground truth comes back from the emulator's
``--truth`` file. With ``--port`` the same program drives any link (a real board on a serial port,
``sim://omni4``, ``tcp://...``); without ground truth the achieved motion comes from wheel odometry
on the controller's telemetry.

The examples (seed 000, sections III and VI.C):

1. ``MOVE,2,40,0,0; DELTA,0,0,10,0,36;``: 37 moves of 2 cm, each course 10 degrees further: a
   closed circle with the heading held.
2. A straight line while spinning: ``MOVE,3,60,0,C; DELTA,0,0,10,0,INF;`` then ``STOP``. The body
   turns at W = V C / 1000 while every move's course advances 10 degrees; the path is straight when
   the two cancel, C = -(10 degrees in rad) * 1000 / 3 cm = -58. The seed prints C = -40, which
   leaves a bend of its own; both run, so the difference is measured, not argued.
3. ``ROTATE`` to face the nearest wall.
4. A sonar approach: ``SONAR,1,60,0,100,25`` then ``MOVE,INF,60,0,0``: RANGE events inside 1 m,
   and the emergency stop (``WARN,13``) where the echo falls below 25 cm plus the distance the robot
   needs to stop from its speed (docs/safety.md), released by ``STOP``. A robot without a sonar
   skips it (and the report says so); with one, no emergency stop means the demo did not do its job.

The examples are driven by :mod:`omnibot.demos.examples`; the ground truth comes from
:mod:`omnibot.demos.truth`; this module opens the link, runs them, and reports.
"""

from __future__ import annotations

import math
import tempfile
import time
from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager
from pathlib import Path
from typing import Any

from omnibot.client import Hello
from omnibot.demos.examples import Demo, Segment
from omnibot.demos.truth import ControllerClock, DemoRecording, TruthFile, TruthSource, world_bounds
from omnibot.errors import ConfigError
from omnibot.progress import notice, progress_bar
from omnibot.transport import find_simulator


def format_table(segments: list[Segment]) -> str:
    """Each example as a small block: commands, commanded, achieved, events."""
    lines = []
    for k, seg in enumerate(segments, 1):
        lines.append(f"{k}. {seg.name}   [{seg.commands}]   {seg.t1 - seg.t0:.2f} s")
        lines.append(f"     commanded: {seg.commanded}")
        lines.append(f"     achieved:  {seg.achieved}")
        if seg.events:
            lines.append(f"     events:    {', '.join(seg.events)}")
    return "\n".join(lines)


def plot(truth: TruthSource | None, odo_trail: list[tuple[float, float]], world: Any, path: Path) -> None:
    """Plot the walls, the true trail and the odometry trail to the image file ``path``."""
    from omnibot.plots import new_figure, save

    fig, axes = new_figure(1, 1, size=(7.5, 6.2))
    ax = axes[0][0]
    if world is not None:
        for x0, y0, x1, y1 in world.segments:
            ax.plot([x0, x1], [y0, y1], color="0.3", lw=1.5)
    if truth is not None:
        rows = truth.rows()
        if rows:
            ax.plot([r[1] for r in rows], [r[2] for r in rows], lw=1.6, label="ground truth (simulator)")
            for _t, x, y, th in rows[:: max(1, len(rows) // 60)]:
                ax.arrow(x, y, 0.05 * math.cos(th), 0.05 * math.sin(th), width=0.004, color="C3", alpha=0.6)
    if odo_trail:
        ax.plot(
            [p[0] for p in odo_trail], [p[1] for p in odo_trail], "--", lw=1.0, label="wheel odometry (TEL)"
        )
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title("omnibot demo: seed 000's examples (heading arrows in red)", fontsize=10)
    save(fig, str(path))


def _link(
    port: str | None, truth_file: TruthFile | None, robot: str, world: str, seed: int, surface: str | None
) -> AbstractContextManager[str]:
    """The link's URL for the time of the demo: a spawned ``omnibot sim --pty`` of ``robot`` writing
    its truth to ``truth_file`` when there is one, else ``port``."""
    if truth_file is None:
        return _given(port or "")
    from omnibot.sim import spawn_pty_emulator  # the simulator's modules only when it is driven

    return spawn_pty_emulator(
        robot, world=world, seed=seed, surface=surface, truth=truth_file.path, notice=notice
    )


def _world_map(world: str) -> Any:
    """The world the spawned simulator drives in (the simulator's modules only when it is driven)."""
    from omnibot.sim import load_world

    return load_world(world)


def run_demo(
    port: str | None,
    robot_name: str | None,
    out: Path,
    seed: int = 1,
    world: str = "room",
    surface: str | None = None,
    recording: DemoRecording | None = None,
) -> tuple[str, bool]:
    """Run the demo; returns the printed report and whether every example did what it should.

    ``port`` None: ``omnibot sim --pty`` of ``robot_name`` (default omni4) in ``world``, truth from its
    CSV. A ``sim://`` port: the in-process simulator, truth from it, in ``world`` unless the URL names
    its own (:func:`with_world`). Anything else (a real board):
    odometry only. The robot is the one on the link (``robot_name``, if given, must name it); the
    session leaves the controller stopped and in the MODE it was found in, however the demo ends;
    ``recording`` (``--log``) records it, with the truth (the emulator's file's, placed on the link's
    clock by the telemetry, once the emulator has closed it).
    """
    from omnibot.client import robot_session
    from omnibot.plots import unavailable

    if port is not None:
        port = with_world(port, world)
    with tempfile.TemporaryDirectory() as tmp:
        truth_file = TruthFile(Path(tmp) / "truth.csv") if port is None else None
        world_map = _world_map(world) if port is None else None
        context = _link(port, truth_file, robot_name or "omni4", world, seed, surface)
        started = time.monotonic()
        clock = ControllerClock()
        with context as url, robot_session(url, robot_name, recording=recording) as session:
            client, robot, hello = session.client, session.robot, session.hello
            client.add_listener(clock)
            sim = find_simulator(client.link)
            if sim is not None:
                world_map = sim.world
            truth = (
                TruthSource(truth_file, world_bounds(world_map) if world_map else None, sim)
                if truth_file or sim is not None
                else None
            )
            with progress_bar("demo", Demo.SEGMENTS, unit="example") as bar:
                demo = Demo(client, robot, truth if truth is not None else (lambda: None), bar)
                segments = demo.run()
        wall = time.monotonic() - started
        if recording is not None and truth_file is not None:  # whole: the emulator has ended
            recording.truth_rows(clock.place(truth_file.rows()))
        left_out = unavailable()  # the plot's matplotlib (the [plots] extra): the run kept without it
        written = _write_outputs(out, truth, demo.recorder.odo_trail, world_map, draw=left_out is None)
    return _report(hello, port, segments, written, wall, left_out)


def _report(
    hello: Hello,
    port: str | None,
    segments: list[Segment],
    written: list[str],
    wall: float,
    left_out: str | None = None,
) -> tuple[str, bool]:
    """The printed report (the controller, the link, the table, the files, the wall time, why the plot
    was left out and what was not done) and whether every example did what it should."""
    link = (
        "client -> text protocol -> pty (115200 baud) -> firmware -> simulator"
        if port is None
        else f"client -> {port}"
    )
    header = f"omnibot demo: {hello.name} ({hello.motors} motors, protocol {hello.version}) via {link}"
    failed = [seg.name for seg in segments if seg.failed]
    verdict = f"\nNOT DONE: {'; '.join(failed)}" if failed else ""
    files = "  ".join(written) or "no file"
    plot = f"\nthe trajectory plot left out: {left_out}" if left_out else ""
    table = format_table(segments)
    return f"{header}\n\n{table}\n\nwrote: {files}  ({wall:.1f} s){plot}{verdict}", not failed


def _write_outputs(
    out: Path, truth: TruthSource | None, odo_trail: list[tuple[float, float]], world_map: Any, draw: bool
) -> list[str]:
    """The trajectory plot (with ``draw``) and, with a truth, its CSV in ``out``; the files written."""
    png = out / "demo_trajectory.png"
    written = [str(png)] if draw else []
    try:
        out.mkdir(parents=True, exist_ok=True)
        if draw:
            plot(truth, odo_trail, world_map, png)
        if truth is not None:
            with (out / "demo_truth.csv").open("w") as f:
                f.write("t,x,y,theta\n")
                f.writelines(f"{t:.3f},{x:.4f},{y:.4f},{th:.4f}\n" for t, x, y, th in truth.rows())
            written.append(str(out / "demo_truth.csv"))
    except OSError as exc:
        raise ConfigError(f"cannot write in {out}: {exc.strerror or exc}", key="--out") from None
    return written


def with_world(port: str, world: str) -> str:
    """A ``sim://`` ``port`` that names no world (and is no fleet's robot) gets the demo's ``world``:
    its examples face a wall and approach it with the sonar, which the simulator's default empty
    floor does not have. Any other URL is returned as it is."""
    base, _, query = port.partition("?")
    if not base.split("+")[-1].startswith("sim://"):
        return port
    names = {option.partition("=")[0].rpartition(".")[2] for option in query.split("&") if option}
    if names & {"world", "fleet"}:
        return port
    return f"{port}{'&' if query else '?'}world={world}"


@contextmanager
def _given(port: str) -> Iterator[str]:
    yield port
