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
"""

from __future__ import annotations

import bisect
import csv
import math
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from omnibot.client import ClientRecording, Event, Hello, RangeEvent, RobotClient, Telemetry, WarnEvent
from omnibot.errors import ConfigError
from omnibot.estimation import WheelOdometry
from omnibot.motion import Pose2D
from omnibot.progress import Progress, notice, progress_bar
from omnibot.protocol import codes
from omnibot.robot import RobotDescription
from omnibot.sim import spawn_pty_emulator
from omnibot.transport import find_simulator

CIRCLE_STEP = 0.02
SPIN_STEP = 0.03
SPIN_SPEED = 0.60
COURSE_STEP = math.radians(10)
COMPENSATING_CURVATURE = -COURSE_STEP / SPIN_STEP  # 1/m: the body turns back what the course advances
SEED_CURVATURE = -4.0  # 1/m: seed 000's C = -40 in 1/(1000 cm)
SPIN_TIME = 1.5
APPROACH_SPEED = 0.60
ESTOP_DISTANCE = 0.25


def spin_commanded(curvature: float) -> str:
    """What a straight-while-spinning run of ``curvature`` (1/m) asks for over ``SPIN_TIME``: the body's
    turn and the path's bend, both in degrees like the achieved line they stand beside (the rate is
    given in brackets, in deg/s)."""
    rate = SPIN_SPEED * curvature  # rad/s: W = V C
    bend = SPIN_TIME * (rate + COURSE_STEP * SPIN_SPEED / SPIN_STEP)
    return (
        f"body turns {math.degrees(rate * SPIN_TIME):+.0f} deg ({math.degrees(rate):.0f} deg/s for "
        f"{SPIN_TIME:g} s), path bend {math.degrees(bend):+.0f} deg"
    )


def wrap(angle: float) -> float:
    """``angle`` wrapped into [-pi, pi), rad."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


@dataclass
class Segment:
    """One example: what was asked, what happened."""

    name: str
    commands: str
    commanded: str
    achieved: str = ""
    start: Pose2D | None = None
    end: Pose2D | None = None
    start_odo: Pose2D | None = None
    end_odo: Pose2D | None = None
    t0: float = 0.0
    t1: float = 0.0
    rows: tuple[int, int] = (0, 0)
    """Ground-truth rows (indexes into the truth file) recorded during the segment."""
    events: list[str] = field(default_factory=list)
    failed: bool = False
    """The example did not do what it is for (no emergency stop in the sonar approach)."""


class TruthFile:
    """The emulator's ``--truth`` CSV, read as it grows (it is flushed every 100 ms)."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def rows(self) -> list[tuple[float, float, float, float]]:
        """Every row so far: (t, x, y, theta)."""
        try:
            with self.path.open(newline="") as f:
                return [
                    (float(r["t"]), float(r["x"]), float(r["y"]), float(r["theta"]))
                    for r in csv.DictReader(f)
                    if r.get("theta")
                ]
        except (OSError, ValueError):
            return []

    def latest(self) -> Pose2D | None:
        """The last row's pose, None while the file has none."""
        rows = self.rows()
        return Pose2D(*rows[-1][1:]) if rows else None


class Recorder:
    """Listens to the client: telemetry -> odometry; RANGE/WARN -> the current segment's events."""

    def __init__(self, robot: RobotDescription) -> None:
        self.odometry = WheelOdometry(robot) if len(robot.encoders.motors) == robot.n_wheels else None
        self.segment: Segment | None = None
        self.odo_trail: list[tuple[float, float]] = []
        self.ranges: list[float] = []
        self.estop = False

    def start_at(self, pose: Pose2D) -> None:
        """Odometry in the world frame from ``pose`` (the true start): its trail starts there, with no
        leg from the origin where the odometry stood before it knew the start."""
        if self.odometry is not None:
            self.odometry.pose = pose
            self.odo_trail = [(pose.x, pose.y)]

    def __call__(self, event: Event) -> None:
        """Take one client event: telemetry into odometry, RANGE and WARN into the current segment."""
        if isinstance(event, Telemetry) and event.encoders is not None and self.odometry is not None:
            pose = self.odometry.update(event.encoders, event.heading)
            self.odo_trail.append((pose.x, pose.y))
        elif isinstance(event, RangeEvent):
            if event.distance is not None:
                self.ranges.append(event.distance)
            if self.segment is not None and len(self.segment.events) < 4:
                self.segment.events.append(
                    f"RANGE {100 * event.distance:.0f} cm" if event.distance is not None else "RANGE none"
                )
        elif isinstance(event, WarnEvent):
            self.estop |= event.code == codes.W_SONAR_STOP
            if self.segment is not None:
                self.segment.events.append(f"WARN {event.code}")


class Demo:
    """Runs the examples on a client; ``truth`` gives ground truth when there is one."""

    SEGMENTS = 5
    """Examples :meth:`run` drives (the progress bar's total)."""

    def __init__(
        self,
        client: RobotClient,
        robot: RobotDescription,
        truth: Callable[[], Pose2D | None],
        progress: Progress | None = None,
    ) -> None:
        self.client = client
        self.robot = robot
        self.truth = truth
        self.progress = progress
        self.recorder = Recorder(robot)
        self.segments: list[Segment] = []
        client.add_listener(self.recorder)

    def pose(self) -> Pose2D | None:
        """The true pose after the truth file's next flush (None without ground truth)."""
        self.client.sleep(0.15)  # the truth file is flushed every 100 ms
        return self.truth()

    def odo(self) -> Pose2D | None:
        """The encoder odometry's pose, None before the start is known."""
        return self.recorder.odometry.pose if self.recorder.odometry else None

    @contextmanager
    def segment(self, name: str, commands: str, commanded: str) -> Iterator[Segment]:
        """Run one example as a :class:`Segment`: its start and end poses and the events seen in between."""
        seg = Segment(name, commands, commanded)
        if self.progress is not None:
            self.progress.set_postfix_str(name)
        seg.start, seg.start_odo, seg.t0 = self.pose(), self.odo(), self.client.clock.now()
        first = self._truth_rows()
        self.recorder.segment = seg
        yield seg
        seg.t1 = self.client.clock.now()
        seg.end, seg.end_odo = self.pose(), self.odo()
        seg.rows = (first, self._truth_rows())
        self.recorder.segment = None
        self.segments.append(seg)
        if self.progress is not None:
            self.progress.update(1)

    def best(self, seg: Segment) -> tuple[Pose2D, Pose2D, str] | None:
        """Start and end pose from truth if there is any, else odometry, and which it was."""
        if seg.start and seg.end:
            return seg.start, seg.end, "truth"
        if seg.start_odo and seg.end_odo:
            return seg.start_odo, seg.end_odo, "odometry"
        return None

    def run(self) -> list[Segment]:
        """Drive every example (a skipped one says why) and return them in order; telemetry off at the end."""
        c = self.client
        c.stop()
        c.telemetry(0.02, codes.TEL_ENCODERS | codes.TEL_HEADING | codes.TEL_QUEUE)
        c.sleep(0.1)
        start = self.pose()
        if start is not None:
            self.recorder.start_at(start)

        self._circle()
        self._spins()
        self._face_wall()
        if not self.robot.sonars:
            self.segments.append(
                Segment(
                    "sonar approach, emergency stop",
                    "SONAR,1,60,0,100,25;MOVE,INF,60,0,0",
                    f"RANGE inside 1 m, WARN 13 below {100 * ESTOP_DISTANCE:.0f} cm",
                    achieved=f"skipped: {self.robot.name} has no sonar",
                )
            )
        else:
            self._sonar_approach()
        c.telemetry(0.0)
        return self.segments

    def _circle(self) -> None:
        """MOVE and DELTA 36 times: a circle of 2 cm steps, heading held."""
        c = self.client
        with self.segment(
            "circle, heading held",
            "MOVE,2,40,0,0;DELTA,0,0,10,0,36",
            "37 x 2 cm: a circle, then 2 cm on course 0 again; heading held",
        ) as seg:
            c.move(CIRCLE_STEP, 0.40)
            c.delta(course=COURSE_STEP, repeat=36)
            c.wait_idle(timeout=10)
        if got := self.best(seg):
            a, b, src = got
            # 36 of the moves close the polygon; the 37th repeats course 0: 2 cm along the start heading
            goal = (a.x + CIRCLE_STEP * math.cos(a.theta), a.y + CIRCLE_STEP * math.sin(a.theta))
            seg.achieved = (
                f"ends {100 * math.dist(goal, (b.x, b.y)):.1f} cm from the commanded end, "
                f"heading {math.degrees(wrap(b.theta - a.theta)):+.1f} deg ({src})"
            )

    def _spins(self) -> None:
        """Straight while spinning, at the seed's curvature and at the one that compensates."""
        c = self.client
        for label, curvature in (
            ("seed's C=-40", SEED_CURVATURE),
            ("compensated C=-58", COMPENSATING_CURVATURE),
        ):
            c_int = round(curvature * 10)  # the protocol's C is in 1/(1000 cm) = 0.1/m
            with self.segment(
                f"straight while spinning, {label}",
                f"MOVE,3,60,0,{c_int};DELTA,0,0,10,0,INF; {SPIN_TIME:g} s; STOP",
                spin_commanded(curvature),
            ) as seg:
                c.move(SPIN_STEP, SPIN_SPEED, 0.0, curvature)
                c.delta(course=COURSE_STEP, repeat=math.inf)
                c.sleep(SPIN_TIME)
                c.stop()
                c.sleep(0.3)
            if got := self.best(seg):
                a, b, src = got
                seg.achieved = (
                    f"{100 * math.dist((a.x, a.y), (b.x, b.y)):.0f} cm, body turned "
                    f"{math.degrees(b.theta - a.theta):+.0f} deg, path bend {self._bend(seg):+.0f} deg ({src})"
                )

    def _face_wall(self) -> None:
        """ROTATE the short way to face the nearest wall (turn around when no wall is known)."""
        c = self.client
        here = self.best_pose()
        heading = here.theta if here else 0.0
        target = self._face_nearest_wall(here)
        turn = wrap(target - heading)  # the short way: the heading is unwrapped after the spins
        aim = f"heading {math.degrees(wrap(target)):.0f} deg"
        if not self._walls_known():
            aim += " (turn around: no wall known; facing a wall needs a world with walls)"
        with self.segment("rotate to face the wall", f"ROTATE,{math.degrees(turn):.0f},90", aim) as seg:
            c.rotate(turn, math.radians(90))
            c.wait_idle(timeout=10)
        if got := self.best(seg):
            _, b, src = got
            seg.achieved = f"heading {math.degrees(wrap(b.theta)):.1f} deg ({src})"

    def _sonar_approach(self) -> None:
        c = self.client
        with self.segment(
            "sonar approach, emergency stop",
            "SONAR,1,60,0,100,25;MOVE,INF,60,0,0",
            f"RANGE inside 1 m, WARN 13 below {100 * ESTOP_DISTANCE:.0f} cm + the stop distance",
        ) as seg:
            c.sonar(1, 0.06, 0.0, 1.0, ESTOP_DISTANCE)
            c.move(math.inf, APPROACH_SPEED)
            deadline = c.clock.now() + 15.0
            while not self.recorder.estop and c.clock.now() < deadline:
                c.pump(0.05)
            c.sleep(0.3)
            status = c.status()
            seg.events.append(f"STATUS state {status.state}")
            c.stop()
            c.sonar(1, 0.0)
        last = self.recorder.ranges[-1] if self.recorder.ranges else None
        seg.failed = not self.recorder.estop
        seg.achieved = (
            ("stopped" if self.recorder.estop else "NO emergency stop")
            + (
                f", last echo {100 * last:.0f} cm"
                if last is not None
                else ", no echo: nothing ahead of the robot"
            )
            + (
                f", robot centre {gap:.0f} cm from the wall (truth)"
                if math.isfinite(gap := self._wall_gap())
                else ""
            )
        )

    def best_pose(self) -> Pose2D | None:
        """The true pose, else the odometry's (None when neither is known)."""
        return self.truth() or self.odo()

    def _bend(self, seg: Segment) -> float:
        """Change of the path's direction over the segment, degrees (from truth or odometry)."""
        pts = self._path_points(seg)
        if len(pts) < 6:
            return float("nan")
        n = len(pts) // 3
        (x0, y0), (x1, y1) = pts[0], pts[n]
        (x2, y2), (x3, y3) = pts[-n - 1], pts[-1]
        return math.degrees(wrap(math.atan2(y3 - y2, x3 - x2) - math.atan2(y1 - y0, x1 - x0)))

    def _truth_rows(self) -> int:
        return len(self.truth.rows()) if isinstance(self.truth, TruthSource) else 0

    def _path_points(self, seg: Segment) -> list[tuple[float, float]]:
        if isinstance(self.truth, TruthSource):
            return [(x, y) for _, x, y, _ in self.truth.rows()[seg.rows[0] : seg.rows[1]]]
        return []

    def _walls_known(self) -> bool:
        return isinstance(self.truth, TruthSource) and self.truth.bounds is not None

    def _face_nearest_wall(self, here: Pose2D | None) -> float:
        """Heading that points at the nearest wall of the room the truth comes from (else: backwards)."""
        if here is None or not isinstance(self.truth, TruthSource) or self.truth.bounds is None:
            return (here.theta if here else 0.0) + math.pi
        (xmin, ymin), (xmax, ymax) = self.truth.bounds
        gaps = {
            math.pi: here.x - xmin,
            0.0: xmax - here.x,
            -math.pi / 2: here.y - ymin,
            math.pi / 2: ymax - here.y,
        }
        return min(gaps, key=lambda k: gaps[k])

    def _wall_gap(self) -> float:
        here = self.truth()
        if here is None or not isinstance(self.truth, TruthSource) or self.truth.bounds is None:
            return float("nan")
        (xmin, ymin), (xmax, ymax) = self.truth.bounds
        return 100 * min(here.x - xmin, xmax - here.x, here.y - ymin, ymax - here.y)


Bounds = tuple[tuple[float, float], tuple[float, float]]


class DemoRecording(ClientRecording, Protocol):
    """``--log``'s recording as the demo uses it (:class:`omnibot.logs.recording.Recording`): the
    clients it opens and, on the pty emulator, the truth of the emulator's file."""

    def truth_rows(self, rows: Sequence[tuple[float, float, float, float]]) -> int:
        """Ground truth rows ``t, x, y, theta`` on the link's clock into the log."""


class ControllerClock:
    """The controller's clock placed on the link's by its TELs (the pty emulator's truth file is timed
    by the emulator's simulated time, which is its firmware's clock)."""

    def __init__(self) -> None:
        self.pairs: list[tuple[float, float]] = []
        """(controller time, link time minus controller time) of each TEL (a demo's few thousand)."""

    def __call__(self, event: Event) -> None:
        """A client listener: each TEL's pair of times (a clock that went back is a restart: anew)."""
        if isinstance(event, Telemetry):
            if self.pairs and event.controller_time < self.pairs[-1][0]:
                self.pairs.clear()
            self.pairs.append((event.controller_time, event.time - event.controller_time))

    def link_time(self, controller_time: float) -> float | None:
        """The link time of an instant on the controller's clock, by the TELs sent either side of it:
        their offsets interpolated (a TEL's delay on the line, a few ms, is the error; an emulator
        that falls behind the wall clock, as a loaded one does, moves the offset, so it is taken at
        each instant, not once); before the first or after the last TEL, that TEL's; None without."""
        pairs = self.pairs
        if not pairs:
            return None
        i = bisect.bisect_left(pairs, (controller_time,))
        if i == 0 or i == len(pairs):
            return controller_time + pairs[min(i, len(pairs) - 1)][1]
        (c0, o0), (c1, o1) = pairs[i - 1], pairs[i]
        share = (controller_time - c0) / (c1 - c0) if c1 > c0 else 0.0
        return controller_time + o0 + share * (o1 - o0)

    def place(
        self, rows: Sequence[tuple[float, float, float, float]]
    ) -> list[tuple[float, float, float, float]]:
        """``rows`` (t, x, y, theta) with ``t`` on the link's clock (none without a TEL)."""
        placed = [(self.link_time(t), x, y, th) for t, x, y, th in rows]
        return [(t, x, y, th) for t, x, y, th in placed if t is not None]


class TruthSource:
    """Ground truth: the emulator's CSV file, or the in-process simulator of a ``sim://`` link."""

    def __init__(self, file: TruthFile | None, bounds: Bounds | None, simulator: Any = None) -> None:
        self.file = file
        self.bounds = bounds
        self._sim = simulator
        self._trail: list[tuple[float, float, float, float]] = []
        if simulator is not None:
            simulator.add_listener(
                lambda snap: self._trail.append((snap.t, snap.x, snap.y, snap.theta)), period=0.01
            )

    def rows(self) -> list[tuple[float, float, float, float]]:
        """Every true pose so far as ``(t, x, y, theta)``."""
        return self.file.rows() if self.file is not None else self._trail

    def __call__(self) -> Pose2D | None:
        """The true pose now (None without ground truth)."""
        if self._sim is not None:
            p = self._sim.pose
            return Pose2D(p.x, p.y, p.theta)
        return self.file.latest() if self.file is not None else None


def world_bounds(world: Any) -> Bounds | None:
    """The walls' bounding box (None for a world without walls)."""
    xs = [v for seg in world.segments for v in (seg[0], seg[2])]
    ys = [v for seg in world.segments for v in (seg[1], seg[3])]
    return ((min(xs), min(ys)), (max(xs), max(ys))) if xs else None


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
    return spawn_pty_emulator(
        robot, world=world, seed=seed, surface=surface, truth=truth_file.path, notice=notice
    )


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
    from omnibot.sim import load_world

    if port is not None:
        port = with_world(port, world)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        truth_file = TruthFile(Path(tmp) / "truth.csv") if port is None else None
        world_map = load_world(world) if port is None else None
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
        written = _write_outputs(out, truth, demo.recorder.odo_trail, world_map)
    return _report(hello, port, segments, written, wall)


def _report(
    hello: Hello, port: str | None, segments: list[Segment], written: list[str], wall: float
) -> tuple[str, bool]:
    """The printed report (the controller, the link, the table, the files, the wall time and what was
    not done) and whether every example did what it should."""
    link = (
        "client -> text protocol -> pty (115200 baud) -> firmware -> simulator"
        if port is None
        else f"client -> {port}"
    )
    header = f"omnibot demo: {hello.name} ({hello.motors} motors, protocol {hello.version}) via {link}"
    failed = [seg.name for seg in segments if seg.failed]
    verdict = f"\nNOT DONE: {'; '.join(failed)}" if failed else ""
    files = "  ".join(written)
    return f"{header}\n\n{format_table(segments)}\n\nwrote: {files}  ({wall:.1f} s){verdict}", not failed


def _write_outputs(
    out: Path, truth: TruthSource | None, odo_trail: list[tuple[float, float]], world_map: Any
) -> list[str]:
    """The trajectory plot and, with a truth, its CSV in ``out``; the files written."""
    png = out / "demo_trajectory.png"
    written = [str(png)]
    try:
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
