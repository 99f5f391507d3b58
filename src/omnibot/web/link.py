"""The robot link thread: the one thread that runs the runtime (which owns the client), fed by the
web server through queues.

::

    web server (asyncio thread)                     link thread (runs the Runtime)
      ws message -> parse_message() -> submit() --> inbox (queue.Queue, at most INBOX_MAX)
                                                      every period (autorepeat_rate, Pacer):
                                                        drain inbox: drive / joy -> the page source,
                                                          estop / resume -> the estop lock, teach
                                                        runtime cycle: sources (page 100, repeat 10,
                                                          any other) -> arbiter -> VEL -> sinks
                                                        pump: TEL -> StateTracker, WARN -> log
      broadcaster <- outbox (queue.Queue) <-------- state frame (who drives and why; the latest
                                                    scan's points, at most every SCAN_PERIOD), log
                                                    frames (every runtime notice)

The client is not thread-safe, so nothing else touches it once :meth:`RobotLink.start` ran. Driving
from the page has the teleop deadman (a :class:`~omnibot.teleop.DeadmanSource`): the page
repeats its input while a key is held or the stick is dragged, and the robot stops (repeated zero
VEL, then the VEL watchdog) when the input says "let go", when the page goes away, or when no input
came for ``input_timeout``. The page outranks the repeat: it takes over and hands back. The emergency
stop is the runtime's top lock: STOP at once, nothing drives (a repeat ends) until the page sends
``resume``. A robot with a scanner on ``sim://`` has the simulator's scanner as the runtime's
(:attr:`Runtime.scanner <omnibot.runtime.runtime.Runtime.scanner>`, unless a front end gave it one):
the state frame carries the latest scan's returns as world points (``scan``, see
:func:`~omnibot.web.scanview.scan_points`). On shutdown the link leaves the controller as it was found
(:func:`omnibot.client.session.leave`: STOP, telemetry off, its MODE back) and closes the client.
"""

from __future__ import annotations

import contextlib
import logging
import queue
import threading
import time
from collections.abc import Callable
from typing import Any

from omnibot.client import ErrorEvent, Event, ResetEvent, RobotClient, WarnEvent, leave
from omnibot.errors import ControllerError, LinkError
from omnibot.estimation import SlipModel
from omnibot.lidar import SimScanSource
from omnibot.motion import Pose2D, Twist
from omnibot.protocol import codes
from omnibot.robot import RobotDescription
from omnibot.runtime import Cycle, EstimatorWhenMissing, Runtime, RuntimeRecording
from omnibot.runtime import EStop as EStopLock
from omnibot.teleop import (
    Deadman,
    DeadmanSource,
    Pacer,
    Phase,
    TeleopConfig,
    TwistLimits,
)
from omnibot.transport import find_device
from omnibot.web.driving import PAGE_PRIORITY, drive_limits, drive_state, page_sample
from omnibot.web.inbox import Inbox, PageGone, Request
from omnibot.web.messages import EStop, Resume, Teach
from omnibot.web.scanview import ScanView
from omnibot.web.state import StateTracker
from omnibot.web.teach import NOT_AVAILABLE, TeachRepeat

log = logging.getLogger("omnibot.web")

TEL_PERIOD = 0.05
SONAR_PERIOD = 0.1


class RobotLink:
    """Runs the runtime (the owner of ``client``) in a thread of its own; :meth:`submit` and
    :attr:`outbox` are the only ways in and out. ``start`` is where odometry starts on a link without
    ground truth (None: the origin); ``wall``/``sleep`` are the wall clock (tests may pass fakes).
    More sources and sinks may join :attr:`runtime` before :meth:`start` (``omnibot run``).
    ``surface``, the floor's name when known, keeps the stick's ramp within its grip
    (:meth:`~omnibot.teleop.TwistLimits.from_limits`)."""

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
        runtime: Runtime | None = None,
        wheel_loop: bool = True,
        slip: SlipModel | None = None,
        recording: RuntimeRecording | None = None,
        surface: str | None = None,
    ) -> None:
        self.client = client
        self.mode = mode
        """The MODE bits the controller was found in: put back on shutdown (None: text protocol only)."""
        self.robot = robot
        self.config = config or TeleopConfig()
        self.teach = teach
        self.limits = TwistLimits.from_limits(client.limits, self.config, robot, surface)
        self.drive_limits = drive_limits(self.limits)
        """Full scale of the page's keys, stick and turn slider."""
        self.inbox = Inbox()
        """The page's requests, waiting for the link thread (web/inbox.py)."""
        self.outbox: queue.Queue[dict[str, Any]] = queue.Queue(maxsize=1000)
        self._wall, self._sleep = wall, sleep
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._device = find_device(client.link)
        truth = self._truth()
        self.tracker = StateTracker(robot, client.link.url, Pose2D(*truth) if truth else start)
        self.page = DeadmanSource("page", self.config, priority=PAGE_PRIORITY, limits=self.limits)
        """The page's stick, keys and browser gamepad."""
        self.estop_lock = EStopLock()
        self.runtime = runtime or Runtime(
            client,
            period=self.config.period,
            vel_timeout=self.config.vel_timeout,
            wheel_loop=wheel_loop,
            slip=slip,
            recording=recording,
        )
        self.scanner: SimScanSource | None = self._lend_scanner()
        """The simulator's scanner when this link gave the runtime one (closed with the link)."""
        self._scans = ScanView()
        self.runtime.add_source(self.page)
        self.runtime.add_lock(self.estop_lock.lock)
        self.runtime.error_hooks.append(self._command_failed)
        self._source = ""
        self._twist: Twist | None = None
        self._configured: float | None = None
        self._reset = False
        self.ended: str | None = None
        """Why the link thread ended by itself (the link lost and not reopened); None otherwise."""

    def _lend_scanner(self) -> SimScanSource | None:
        """The simulator's scanner, given to the runtime, when the robot has one and the runtime none."""
        if self.robot.scanner is None or self.runtime.scanner is not None or self._device is None:
            return None
        self.runtime.scanner = scanner = SimScanSource(self._device.sim)
        return scanner

    @property
    def deadman(self) -> Deadman:
        """The page's deadman (its phase says whether the page drives)."""
        return self.page.deadman

    @property
    def estop(self) -> bool:
        """True while the page's emergency stop is engaged (until Resume)."""
        return self.estop_lock.engaged

    @property
    def following(self) -> bool:
        """True while a taught path is being followed."""
        return self.teach is not None and self.teach.following

    # ------------------------------------------------------------------ other threads

    def submit(self, request: Request) -> bool:
        """Hand a validated request to the link thread (thread-safe); False when the inbox is full
        and it was dropped. An emergency stop or a page gone is never dropped: with the inbox full it
        is flagged and acted on after the requests waiting (so nothing queued before it undoes it)."""
        return self.inbox.offer(request)

    def start(self) -> None:
        """Start the link thread."""
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
            self.runtime.close()
            self._close_scanner()
            self.client.close()

    def _close_scanner(self) -> None:
        if self.scanner is not None:
            if self.runtime.scanner is self.scanner:
                self.runtime.scanner = None
            self.scanner.close()
            self.scanner = None

    @property
    def pose(self) -> tuple[float, float, float] | None:
        """The pose the page shows: the simulator's truth, else odometry (before :meth:`start`, or
        from the link thread)."""
        return self._pose()

    @property
    def alive(self) -> bool:
        """Whether the link thread runs."""
        return self._thread is not None and self._thread.is_alive()

    @property
    def lost(self) -> str | None:
        """Why the link thread, once started, no longer runs (:attr:`ended`, or that it stopped);
        None while it runs."""
        if self.alive:
            return None
        return self.ended or "its thread stopped"

    # ------------------------------------------------------------------ link thread

    def _run(self) -> None:
        client = self.client
        try:
            self.setup()
            pacer = Pacer(client, self.config.period, wall=self._wall, sleep=self._sleep)
            self.runtime.pacer = pacer
            while not self._stop.is_set():
                self.tick(pacer.now())
                try:
                    self.runtime.wait()  # the pacer's wait, reacting to sources that wake (cmd_vel)
                except LinkError as exc:
                    self._link_error(exc)
                    if client.broken or client.link.closed:  # the port is gone and did not come back
                        self.ended = str(exc)
                        self._log("error", f"robot link ended: {exc}")
                        break
                    self._sleep(self.config.period)
        except Exception as exc:  # pragma: no cover - reported, then the link ends
            log.exception("robot link failed")
            self.ended = str(exc)
            self._emit({"type": "log", "level": "error", "text": f"robot link stopped: {exc}"})
        finally:
            self.runtime.close()
            self._close_scanner()
            leave(client, self.mode)

    def setup(self) -> None:
        """Telemetry and sonars on, the teach hook joined (link thread; tests may call it directly with
        no thread)."""
        client = self.client
        if self._configured is None:
            client.on_telemetry(self.tracker)
            client.add_listener(self._on_event, WarnEvent, ErrorEvent, ResetEvent)
            self.runtime.start()
            if self.teach is not None:
                self.teach.attach(self.runtime, self._pose())
            EstimatorWhenMissing.add(self.runtime, self.robot)  # the achieved twist
        self._reset = False
        try:
            client.telemetry(TEL_PERIOD, codes.TEL_MASK)
            for n in range(1, len(self.robot.sonars) + 1):
                client.sonar(n, SONAR_PERIOD)
        except (ControllerError, LinkError, ValueError) as exc:
            self._link_error(exc)
        self._configured = client.clock.now()

    def tick(self, now: float) -> None:
        """One period: handle the requests waiting, one runtime cycle, a state frame (link thread)."""
        if self._reset:
            self._log("warn", "the controller restarted: telemetry and sonars set up again")
            self.setup()
        for request in self.inbox.take():
            self._handle(request, now)
        cycle = self.runtime.step(now)
        self._after(cycle)

    def _after(self, cycle: Cycle) -> None:
        for notice in cycle.notices:
            self._log(notice.level, notice.text)
        if cycle.sent is not None:
            health = self.tracker.health
            if self.runtime.rtt is not None:
                health.rtt = self.runtime.rtt
            if not health.ok:
                health.ok, health.error = True, ""
                self._log("info", "robot link back")
        decision = cycle.decision
        self._twist = self.page.twist if decision.source == self.page.name else cycle.sent
        ended = self.deadman.last_end.value if self.deadman.last_end else None
        drive = drive_state(
            cycle, self._drive_phase(), self._source, self._twist, ended, self.teach is not None
        )
        # truth only when the link is a simulator that gives it; else the tracker shows odometry as such
        now = self.client.clock.now()
        frame = self.tracker.frame(now, self._truth(), drive)
        if (scan := self._scans.frame(cycle.scans, now, self._pose())) is not None:
            frame["scan"] = scan
        self._emit(frame)

    def _drive_phase(self) -> str:
        """What the page shows of the driving: estop, the page's deadman phase, following, idle."""
        page = self.page.deadman.phase
        if self.estop:
            return "estop"
        if page is not Phase.IDLE:
            return str(page.value)
        return "following" if self.following else "idle"

    def _handle(self, request: Request, now: float) -> None:
        if isinstance(request, EStop):
            self._estop()
        elif isinstance(request, Resume):
            if self.estop:
                self.estop_lock.resume()
                self._log("info", "emergency stop cleared: drive again with a fresh input")
        elif isinstance(request, Teach):
            self._teach(request.action)
        elif isinstance(request, PageGone):
            self.page.sample = None
        elif self.estop:
            return  # driving is ignored until resume
        else:
            self.page.sample, self._source = page_sample(
                request, self.config, self.limits, self.drive_limits, now
            )

    def _estop(self) -> None:
        self.estop_lock.press("page")
        self.page.reset()
        self._twist = None
        try:
            self.client.stop()
            self._log("warn", "emergency stop: STOP sent; press Resume to drive again")
        except (ControllerError, LinkError) as exc:
            self._link_error(exc)

    def _teach(self, action: str) -> None:
        if self.teach is None:
            self._log("error", NOT_AVAILABLE)
            return
        try:
            text = self.teach.command(action, self._pose())
        except Exception as exc:
            self._log("error", f"teach and repeat failed: {exc}")
            return
        if text:
            self._log("info", text)

    def _command_failed(self, source: str, exc: BaseException) -> None:
        health = self.tracker.health
        health.errors += 1
        if isinstance(exc, LinkError):
            health.ok = False
            health.error = str(exc)

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
        estimator = self.tracker.estimator
        if (truth := self._truth()) is not None or estimator is None:
            return truth
        e = estimator.estimate
        return (e.x, e.y, e.theta)

    def _truth(self) -> tuple[float, float, float] | None:
        if self._device is None:
            return None
        p = self._device.sim.pose
        return (p.x, p.y, p.theta)

    def _log(self, level: str, text: str) -> None:
        self._emit({"type": "log", "level": level, "text": text})

    def _emit(self, frame: dict[str, Any]) -> None:
        try:
            self.outbox.put_nowait(frame)
        except queue.Full:  # nobody drains (no server): drop the oldest
            with contextlib.suppress(queue.Empty):
                self.outbox.get_nowait()
            self.outbox.put_nowait(frame)
