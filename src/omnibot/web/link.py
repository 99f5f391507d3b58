"""The robot link thread: the one thread that owns the client, fed by the web server through queues.

::

    web server (asyncio thread)                     link thread (owns RobotClient)
      ws message -> parse_message() -> submit() --> inbox (queue.Queue, at most INBOX_MAX)
                                                      every period (autorepeat_rate, Pacer):
                                                        drain inbox: drive / joy / estop / resume / teach
                                                        Deadman -> client.vel(..., vel_timeout)
                                                        pump: TEL -> StateTracker, WARN -> log
      broadcaster <- outbox (queue.Queue) <-------- state frame (and log frames)

The client is not thread-safe, so nothing else touches it once :meth:`RobotLink.start` ran. Driving
from the page has the teleop deadman: the page repeats its input while a key is held or the stick
is dragged, and the robot stops (repeated zero VEL, then the VEL watchdog) when the input says
"let go", when the page goes away, or when no input came for ``input_timeout``. The emergency stop
sends STOP at the next period and ignores driving until the page sends ``resume``. On shutdown
the link leaves the controller as it was found (:func:`omnibot.client.session.leave`: STOP,
telemetry off, its MODE back) and closes the client.
"""

from __future__ import annotations

import contextlib
import logging
import math
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from omnibot.client.client import RobotClient
from omnibot.client.events import ErrorEvent, Event, ResetEvent, WarnEvent
from omnibot.client.session import leave
from omnibot.errors import ControllerError, LinkError
from omnibot.motion import Pose2D, Twist
from omnibot.protocol import codes
from omnibot.robot.description import RobotDescription
from omnibot.teleop.config import TeleopConfig
from omnibot.teleop.deadman import Deadman, Sample
from omnibot.teleop.mapping import (
    JoyState,
    TwistLimits,
    axes_tuple,
    fractions_to_twist,
    joy_to_command,
    limit_twist,
)
from omnibot.teleop.pacing import Pacer
from omnibot.transport.device import find_device
from omnibot.web.messages import Drive, EStop, Joy, Resume, Teach
from omnibot.web.state import StateTracker
from omnibot.web.teach import NOT_AVAILABLE, TeachRepeat

log = logging.getLogger("omnibot.web")

TEL_PERIOD = 0.05
SONAR_PERIOD = 0.1
INBOX_MAX = 256
"""Requests waiting for the link thread; beyond it :meth:`RobotLink.submit` drops them (the server
answers the page with an error), so a flood cannot grow memory or delay the link thread by more than
one bounded batch a period."""
DRIVE_RATE_MAX = math.pi
"""rad/s at full turn from the page (keys, slider): half a turn a second, whatever the robot could do."""


@dataclass(frozen=True)
class PageGone:
    """A page disconnected: whatever it was driving is let go."""


Request = Drive | Joy | EStop | Resume | Teach | PageGone


class RobotLink:
    """Owns ``client`` in a thread of its own; :meth:`submit` and :attr:`outbox` are the only ways in
    and out. ``start`` is where odometry starts on a link without ground truth (None: the origin);
    ``wall``/``sleep`` are the wall clock (tests may pass fakes)."""

    def __init__(
        self,
        client: RobotClient,
        robot: RobotDescription,
        config: TeleopConfig | None = None,
        *,
        teach: TeachRepeat | None = None,
        start: Pose2D | None = None,
        wall: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
        mode: int | None = None,
    ) -> None:
        self.client = client
        self.mode = mode
        """The MODE bits the controller was found in: put back on shutdown (None: text protocol only)."""
        self.robot = robot
        self.config = config or TeleopConfig()
        self.teach = teach
        self.limits = TwistLimits.from_limits(client.limits, self.config)
        self.drive_limits = TwistLimits(self.limits.speed, min(self.limits.rate, DRIVE_RATE_MAX))
        """Full scale of the page's keys, stick and turn slider."""
        self.inbox: queue.Queue[Request] = queue.Queue(maxsize=INBOX_MAX)
        self._estop_waiting = threading.Event()
        self._gone_waiting = threading.Event()
        self.outbox: queue.Queue[dict[str, Any]] = queue.Queue(maxsize=1000)
        self._wall, self._sleep = wall, sleep
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._device = find_device(client.link)
        truth = self._truth()
        self.tracker = StateTracker(robot, client.link.url, Pose2D(*truth) if truth else start)
        self.deadman = Deadman(self.config.input_timeout, self.config.stop_repeats)
        self.estop = False
        self.following = False
        self._sample: Sample | None = None
        self._source = ""
        self._twist: Twist | None = None
        self._configured: float | None = None
        self._reset = False

    # ------------------------------------------------------------------ other threads

    def submit(self, request: Request) -> bool:
        """Hand a validated request to the link thread (thread-safe); False when the inbox is full
        and it was dropped. An emergency stop or a page gone is never dropped: with the inbox full it
        is flagged and acted on after the requests waiting (so nothing queued before it undoes it)."""
        try:
            self.inbox.put_nowait(request)
        except queue.Full:
            if isinstance(request, EStop):
                self._estop_waiting.set()
                return True
            if isinstance(request, PageGone):
                self._gone_waiting.set()
                return True
            return False
        return True

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="omnibot-robot-link", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        """Stop the loop: the robot gets STOP and the client is closed (in the link thread)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
            if self._thread.is_alive():  # pragma: no cover - a link stuck in a blocking call
                log.error("the robot link thread did not stop within %s s", timeout)
            self._thread = None
        else:
            self.client.close()

    @property
    def pose(self) -> tuple[float, float, float] | None:
        """The pose the page shows: the simulator's truth, else odometry (before :meth:`start`, or
        from the link thread)."""
        return self._pose()

    @property
    def alive(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    # ------------------------------------------------------------------ link thread

    def _run(self) -> None:
        client = self.client
        try:
            self.setup()
            pacer = Pacer(client, self.config.period, wall=self._wall, sleep=self._sleep)
            while not self._stop.is_set():
                self.tick(pacer.now())
                try:
                    pacer.wait()
                except LinkError as exc:
                    self._link_error(exc)
                    self._sleep(self.config.period)
        except Exception as exc:  # pragma: no cover - reported, then the link ends
            log.exception("robot link failed")
            self._emit({"type": "log", "level": "error", "text": f"robot link stopped: {exc}"})
        finally:
            leave(client, self.mode)

    def setup(self) -> None:
        """Telemetry and sonars on (link thread; tests may call it directly with no thread)."""
        client = self.client
        if self._configured is None:
            client.on_telemetry(self.tracker)
            client.add_listener(self._on_event, WarnEvent, ErrorEvent, ResetEvent)
        self._reset = False
        try:
            client.telemetry(TEL_PERIOD, codes.TEL_MASK)
            for n in range(1, len(self.robot.sonars) + 1):
                client.sonar(n, SONAR_PERIOD)
        except (ControllerError, LinkError, ValueError) as exc:
            self._link_error(exc)
        self._configured = client.clock.now()

    def tick(self, now: float) -> None:
        """One period: handle the requests waiting, drive, emit a state frame (link thread)."""
        if self._reset:
            self._log("warn", "the controller restarted: telemetry and sonars set up again")
            self.setup()
        while True:
            try:
                request = self.inbox.get_nowait()
            except queue.Empty:
                break
            self._handle(request, now)
        if self._gone_waiting.is_set():
            self._gone_waiting.clear()
            self._sample = None
        if self._estop_waiting.is_set():
            self._estop_waiting.clear()
            self._estop()
        pose = self._pose()
        if self.teach is not None and not self.estop:
            self.following = self._call_teach(lambda t: t.tick(self.client, pose), False)
        if not self.estop and not self.following:
            action = self.deadman.update(now, self._sample)
            if action.twist is not None:
                self._send(action.twist)
            self._twist = action.twist
        drive = {
            "state": "estop" if self.estop else "following" if self.following else self.deadman.phase.value,
            "source": self._source,
            "twist": None
            if self._twist is None
            else [round(v, 3) for v in (self._twist.vx, self._twist.vy, self._twist.w)],
            "ended": self.deadman.last_end.value if self.deadman.last_end else None,
            "teach": self.teach is not None,
        }
        # truth only when the link is a simulator that gives it; else the tracker shows odometry as such
        self._emit(self.tracker.frame(self.client.clock.now(), self._truth(), drive))

    def _handle(self, request: Request, now: float) -> None:
        if isinstance(request, EStop):
            self._estop()
        elif isinstance(request, Resume):
            if self.estop:
                self.estop = False
                self._log("info", "emergency stop cleared: drive again with a fresh input")
        elif isinstance(request, Teach):
            self._teach(request.action)
        elif isinstance(request, PageGone):
            self._sample = None
        elif self.estop:
            return  # driving is ignored until resume
        elif isinstance(request, Drive):
            twist = fractions_to_twist(request.vx, request.vy, request.w, self.drive_limits)
            self._sample = Sample(twist, request.enable, now)
            self._source = request.source
        else:  # Joy: the Gamepad API's axes are up/left negative, ROS joy's positive
            joy = JoyState(
                axes_tuple([-a for a in request.axes]), tuple(int(b > 0.5) for b in request.buttons), now
            )
            cmd = joy_to_command(self.config, joy)
            self._sample = Sample(limit_twist(cmd.twist, self.limits), cmd.enabled, now)
            self._source = "gamepad"

    def _estop(self) -> None:
        self.estop = True
        self._sample = None
        self.deadman.reset()
        self._twist = None
        if self.following and self.teach is not None:
            self._call_teach(lambda t: t.command("stop", self.client, self._pose()), "")
            self.following = False
        try:
            self.client.stop()
            self._log("warn", "emergency stop: STOP sent; press Resume to drive again")
        except (ControllerError, LinkError) as exc:
            self._link_error(exc)

    def _teach(self, action: str) -> None:
        if self.teach is None:
            self._log("error", NOT_AVAILABLE)
            return
        text = self._call_teach(lambda t: t.command(action, self.client, self._pose()), "")
        if text:
            self._log("info", text)

    def _call_teach(self, call: Callable[[TeachRepeat], Any], default: Any) -> Any:
        assert self.teach is not None
        try:
            return call(self.teach)
        except Exception as exc:
            self._log("error", f"teach and repeat failed: {exc}")
            return default

    def _send(self, twist: Twist) -> None:
        client = self.client
        t0 = client.clock.now()
        try:
            client.vel(twist.vx, twist.vy, twist.w, self.config.vel_timeout)
        except (ControllerError, LinkError, ValueError) as exc:
            self._link_error(exc)
            return
        health = self.tracker.health
        health.rtt = client.clock.now() - t0
        if not health.ok:
            health.ok, health.error = True, ""
            self._log("info", "robot link back")

    def _link_error(self, exc: Exception) -> None:
        health = self.tracker.health
        health.errors += 1
        text = str(exc)
        if isinstance(exc, LinkError):
            health.ok = False
        if text != health.error:
            health.error = text
            self._log("error", text)

    def _on_event(self, event: Event) -> None:
        if isinstance(event, WarnEvent):
            self._log("warn", f"WARN {event.code}: {event.text}")
        elif isinstance(event, ErrorEvent):
            self._log("error", f"ERROR {event.code}: {event.text}")
        elif isinstance(event, ResetEvent) and self._configured is not None and event.time > self._configured:
            self._reset = True  # set telemetry and sonars up again at the next tick (not inside a pump)

    def _pose(self) -> tuple[float, float, float] | None:
        return self._truth() or (
            None
            if self.tracker.odometry is None
            else (
                self.tracker.odometry.pose.x,
                self.tracker.odometry.pose.y,
                self.tracker.odometry.pose.theta,
            )
        )

    def _truth(self) -> tuple[float, float, float] | None:
        if self._device is None:
            return None
        x, y, th = self._device.sim.pose
        return (float(x), float(y), float(th))

    def _log(self, level: str, text: str) -> None:
        self._emit({"type": "log", "level": level, "text": text})

    def _emit(self, frame: dict[str, Any]) -> None:
        try:
            self.outbox.put_nowait(frame)
        except queue.Full:  # nobody drains (no server): drop the oldest
            with contextlib.suppress(queue.Empty):
                self.outbox.get_nowait()
            self.outbox.put_nowait(frame)
