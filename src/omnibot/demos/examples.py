"""Seed 000's motion examples driven on a client (:class:`Demo`), each a :class:`Segment` with what was
commanded, and the odometry the demo keeps from the controller's telemetry (:class:`Recorder`); the
whole job: :mod:`omnibot.demos.seed000`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

from omnibot.client import Event, RangeEvent, RobotClient, Telemetry, WarnEvent
from omnibot.demos.truth import TruthSource
from omnibot.estimation import WheelOdometry
from omnibot.motion import Pose2D
from omnibot.progress import Progress
from omnibot.protocol import codes
from omnibot.robot import RobotDescription

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
