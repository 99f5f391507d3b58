"""The runtime: the one loop that owns the client (see the package docstring for its cycle)."""

from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Callable, Iterable
from typing import Protocol

from omnibot import collector
from omnibot.client import (
    ClientRecording,
    ErrorEvent,
    Event,
    Pending,
    ResetEvent,
    RobotClient,
    Telemetry,
    WarnEvent,
)
from omnibot.errors import ControllerError, LinkError
from omnibot.estimation import Estimator, SlipModel
from omnibot.motion import Estimate
from omnibot.runtime.arbiter import Arbiter, Lock
from omnibot.runtime.core import log
from omnibot.runtime.cycle import NOBODY, Cycle, Decision, Level, Notice
from omnibot.runtime.listening import KEEP, Listening
from omnibot.runtime.pacing import LinkPacer, Pacer
from omnibot.runtime.sending import Sending
from omnibot.runtime.sources import Proposal, Source
from omnibot.runtime.wakeup import GAP, Wakeup
from omnibot.scan import Scan

PREDICT_MAX = 0.1
"""s: the estimate is extrapolated to the cycle's time by at most this much (older: held)."""
OPEN_LOOP_TEXT = (
    "open loop{why}: the wheels get the calibrated powers for a speed, so the robot goes as fast as the "
    "floor lets it, not at the speed asked"
)


Sink = Callable[[Cycle], object]
"""Anything called with each completed :class:`Cycle` (a function, a bound method, an object with
``__call__``); see :mod:`omnibot.runtime.sinks`."""


class Scanner(Protocol):
    """Where a runtime's scans come from (a :class:`~omnibot.lidar.reader.ScanSource`)."""

    def poll(self) -> list[Scan]:
        """The scans completed since the last call; an error when the scanner failed."""
        ...


class RuntimeRecording(Protocol):
    """Where a command records its runtimes (its ``--log`` / ``--foxglove`` recording,
    :class:`omnibot.logs.recording.Recording`): handed in, so the runtime knows nothing of logs."""

    def attach_runtime(self, runtime: Runtime) -> None:
        """Record ``runtime`` (called by :meth:`Runtime.start`, before it listens to the client)."""


class Recording(ClientRecording, RuntimeRecording, Protocol):
    """A command's recording of the clients it opens and the runtimes it runs, for a library that
    does both (the dashboard opens its robot and runs its runtime)."""


class Runtime(Listening, Sending):
    """Owns ``client``: one cycle per :meth:`step`, :meth:`run` loops them on ``pacer``.

    ``estimator`` turns telemetry into the state sources and sinks see (None: no state, e.g. plain
    teleop). ``vel_timeout`` is the VEL watchdog of a source without its own ``watchdog``.
    ``wait_replies``: send each VEL and wait for its reply (a refusal is known within the cycle; for
    loops of 20 Hz); otherwise VEL is submitted and its reply collected at the next cycle (100 Hz
    loops: no round trip inside the cycle). A source's own ``wait_reply`` attribute overrides it. Either way a refused command or a latched emergency stop
    becomes a :class:`Notice` every sink (every front end) and the refused source are handed.

    Between cycles a source may push a fresh proposal in (a DDS listener's ``cmd_vel``): it wakes
    the loop, whose :meth:`wait` then reacts (:meth:`react`: asks it, arbitrates, sends) and waits for
    the cycle that was due (:mod:`omnibot.runtime.wakeup`: also what such an event means in lockstep).

    ``wheel_loop``: when the runtime starts, the controller's wheel-speed loop (MODE bit 1) is closed
    on the motor encoders (True: every VEL, whoever sends it, is then a velocity the wheels hold
    whatever the floor), opened (False: the user asked for open loop) or left as found (None). A
    robot without encoders on every motor stays open loop, and every front end is told so once.
    :attr:`closed_loop` says what was done. ``slip``: the floor's calibrated wheel slip; on the closed
    loop each VEL then asks the wheels for their creep on top (:meth:`SlipModel.commanded
    <omnibot.estimation.slip.SlipModel.commanded>`), that of the source's planned acceleration
    (``body_accel``) included, so the body, not only its wheels, goes at the twist asked. ``recording``: the command's ``--log`` / ``--foxglove`` recording, which records the
    runtime from its start (:class:`RuntimeRecording`); None records nothing.
    """

    def __init__(
        self,
        client: RobotClient,
        *,
        period: float = 0.01,
        estimator: Estimator | None = None,
        sources: Iterable[Source] = (),
        sinks: Iterable[Sink] = (),
        locks: Iterable[Lock] = (),
        pacer: Pacer | None = None,
        vel_timeout: float = 0.25,
        wait_replies: bool = False,
        wheel_loop: bool | None = True,
        slip: SlipModel | None = None,
        recording: RuntimeRecording | None = None,
    ) -> None:
        self.client = client
        self.recording = recording
        self.wheel_loop = wheel_loop
        self.slip = slip
        self.closed_loop: bool | None = None
        """The wheel-speed loop is closed (True), open (False), or was left as found (None)."""
        self.period = period
        self.estimator = estimator
        self.arbiter = Arbiter(list(locks))
        self.sources: dict[str, Source] = {}
        self.sinks: list[Sink] = list(sinks)
        self.pacer: Pacer = pacer or LinkPacer(client, period)
        self.vel_timeout = vel_timeout
        self.wait_replies = wait_replies
        self.decision: Decision = NOBODY
        self.wakeup = Wakeup()
        """Raised by sources between cycles (any thread): the wait ends, :meth:`react` runs."""
        self._init_counts()
        self._init_hooks()
        self._offset = math.inf
        self._offset_time = 0.0
        self._telemetry: deque[Telemetry] = deque(maxlen=KEEP)
        self._events: deque[Event] = deque(maxlen=KEEP)
        self._notices: list[Notice] = []
        self._pending: list[tuple[Pending, str]] = []
        self._last_error: dict[str, str] = {}
        self._listening = False
        self.scanner: Scanner | None = None
        """The robot's range scanner, polled once per cycle: its scans go to every sink on
        :attr:`Cycle.scans <omnibot.runtime.cycle.Cycle.scans>` (one source, many readers: the SLAM, the
        log, ROS 2, the page). Whoever sets it closes it; one that fails is dropped, with a notice."""
        for source in sources:
            self.add_source(source)

    # ------------------------------------------------------------------ composition

    def add_source(self, source: Source) -> None:
        """Add a command source (arbitrated from the next cycle on); a source with a
        ``wake_with(wake)`` method is handed its wake function (:mod:`omnibot.runtime.wakeup`)."""
        self.arbiter.add(source.name, source.priority, source.timeout)
        self.sources[source.name] = source
        wake_with = getattr(source, "wake_with", None)
        if callable(wake_with):
            wake_with(self.wakeup.waker(source.name))
            self._wakers.add(source.name)

    def remove_source(self, name: str) -> None:
        """Remove the source ``name`` (no-op if unknown; its wakes are ignored from now on)."""
        self.arbiter.remove(name)
        self.sources.pop(name, None)
        self._wakers.discard(name)

    def add_sink(self, sink: Sink) -> None:
        """Add a sink: called with every completed cycle."""
        self.sinks.append(sink)

    def remove_sink(self, sink: Sink) -> None:
        """Remove a sink (no-op if unknown)."""
        if sink in self.sinks:
            self.sinks.remove(sink)

    def add_lock(self, lock: Lock) -> None:
        """Add a lock that masks sources at or below its priority while engaged."""
        self.arbiter.locks.append(lock)

    # ------------------------------------------------------------------ listening

    def start(self) -> None:
        """Listen to telemetry and events (idempotent; :meth:`step` calls it)."""
        if self._listening:
            return
        self._listening = True
        if self.recording is not None:
            self.recording.attach_runtime(self)  # the command's --log / --foxglove: the recorder's sink
        self.client.on_telemetry(self._on_telemetry)
        self.client.add_listener(self._on_event, WarnEvent, ErrorEvent, ResetEvent)
        self._set_wheel_loop()

    def _set_wheel_loop(self) -> None:
        """Close (or open) the controller's wheel-speed loop as :attr:`wheel_loop` asks."""
        want, client = self.wheel_loop, self.client
        if want is None or client.link.closed:
            return
        if want and client.limits.has_encoders is False:
            self.closed_loop = False
            robot = client.limits.robot or "the robot"
            self.notify("warn", OPEN_LOOP_TEXT.format(why=f" ({robot} has no encoder on every motor)"))
            return
        try:
            client.mode(closed_loop=want)
        except (ControllerError, LinkError, ValueError) as exc:
            self.closed_loop = False
            self.notify(
                "warn", OPEN_LOOP_TEXT.format(why=f" (the controller refused its wheel-speed loop: {exc})")
            )
            return
        self.closed_loop = want
        if not want:
            self.notify("info", OPEN_LOOP_TEXT.format(why=" as asked"))

    def close(self) -> None:
        """Stop listening (the client stays open: whoever opened it closes it)."""
        if not self._listening:
            return
        self._listening = False
        self.client.remove_listener(self._on_telemetry)
        self.client.remove_listener(self._on_event)
        self._pending.clear()

    # ------------------------------------------------------------------ the cycle

    def estimate_now(self) -> Estimate | None:
        """The estimate extrapolated to now on the link clock (telemetry age, at most PREDICT_MAX)."""
        if self.estimator is None:
            return None
        now = self.client.clock.now()
        est = self.estimator.estimate
        offset = self._offset if math.isfinite(self._offset) else 0.0
        horizon = min(max(0.0, now - (est.t + offset)), PREDICT_MAX)
        e = est.predict(est.t + horizon)
        return Estimate(now, e.x, e.y, e.theta, e.vx, e.vy, e.w, e.slipping, e.standstill)

    def step(self, now: float | None = None) -> Cycle:
        """One cycle: collect, estimate, ask the sources, arbitrate, send, fan out (``now``: the cycle
        clock's time, default the pacer's)."""
        self.start()
        if self._wakers:
            self.wakeup.take()  # what woke the loop until now, the sources' proposals below take
        self._collect()
        now = self.pacer.now() if now is None else now
        cycle = Cycle(self.cycles, now, self.client.clock.now(), self.estimate_now())
        self.cycles += 1
        cycle.telemetry, cycle.events = list(self._telemetry), list(self._events)
        cycle.scans = self._scans()
        self._telemetry.clear()
        self._events.clear()
        cycle.notices, self._notices = self._notices, []
        cycle.latched = self.latched
        cycle.latch_reason = self.latch_reason
        cycle.decision = self.decision  # the previous cycle's, while sources are asked
        proposals: dict[str, Proposal | None] = {}
        for name, source in list(self.sources.items()):
            proposals[name] = source.propose(cycle)
        decision = self.arbiter.decide(now, {n: p.twist if p else None for n, p in proposals.items()})
        cycle.notices.extend(self._control_changed(decision))
        self.decision = cycle.decision = decision
        if decision.twist is not None:
            proposal = proposals.get(decision.source)
            cycle.sent = self._send(decision.source, decision.twist, proposal is not None and proposal.fresh)
        cycle.latched = self.latched
        cycle.latch_reason = self.latch_reason
        cycle.notices.extend(self._notices)
        self._notices = []
        for sink in list(self.sinks):
            try:
                sink(cycle)
            except Exception as exc:  # a broken view must not stop the robot loop
                log.exception("a runtime sink failed; it is removed")
                self.remove_sink(sink)
                self._notices.append(Notice("error", f"a view failed and was removed: {exc}"))
        return cycle

    def _control_changed(self, decision: Decision) -> list[Notice]:
        """The notice of a change of who is in control (none when ``decision`` changes nothing)."""
        if (decision.source, decision.lock) == (self.decision.source, self.decision.lock):
            return []
        level: Level = "warn" if decision.lock else "info"
        text = f"in control: {decision.reason}" if decision.source else f"nobody drives: {decision.reason}"
        log.log(logging.WARNING if decision.lock else logging.INFO, "%s", text)
        return [Notice(level, text, kind="control")]

    def react(self) -> Decision | None:
        """Take what woke the loop (:mod:`omnibot.runtime.wakeup`): ask the woken sources, and only
        them, for a proposal, arbitrate among every source, and send when a woken source drives.

        The woken sources are handed a cycle record of the moment (``now`` the pacer's clock, the
        estimate predicted to it, the previous decision; the index of the cycle to come, no
        telemetry, events or notices: those go with that cycle, as does the notice of a change of
        who is in control). A source that is not woken keeps its last proposal in arbitration, so a
        person's pad or the page's stick above the woken source still holds the robot (nothing is
        sent: the winner sends on its own cycle), and a lock still masks it. Sinks see the cycles
        only. Returns the decision (None when no source of the runtime's had woken it)."""
        names = [name for name in sorted(self.wakeup.take()) if name in self.sources]
        now = self.pacer.now()
        self.wakeup.hold_until = now + GAP
        if not names:
            return None
        self.reactions += 1
        self._collect()
        cycle = Cycle(self.cycles, now, self.client.clock.now(), self.estimate_now())
        cycle.decision = self.decision
        cycle.latched, cycle.latch_reason = self.latched, self.latch_reason
        proposals = {name: self.sources[name].propose(cycle) for name in names}
        decision = self.arbiter.decide(now, {n: p.twist if p else None for n, p in proposals.items()})
        self._notices.extend(self._control_changed(decision))
        self.decision = decision
        if decision.twist is not None and decision.source in proposals:
            proposal = proposals[decision.source]
            self._send(decision.source, decision.twist, proposal is not None and proposal.fresh)
        return decision

    def wait(self) -> None:
        """Wait for the next cycle on the pacer; meanwhile react to every wake of a source
        (:meth:`react`). Without a source that wakes, the pacer's plain wait."""
        if not self._wakers:
            self.pacer.wait()
            return
        while self.pacer.wait(self.wakeup) is False:
            self.react()

    def _scans(self) -> list[Scan]:
        """The scanner's new scans (none without one; a scanner that fails is told and dropped)."""
        scanner = self.scanner
        if scanner is None:
            return []
        try:
            return list(scanner.poll())
        except Exception as exc:  # a scanner lost must not stop the robot loop
            self.scanner = None
            self._notices.append(Notice("error", f"the scanner failed and is no longer read: {exc}"))
            return []

    def run(self, until: Callable[[], bool] | None = None, duration: float | None = None) -> None:
        """Cycle until ``until()`` is true or ``duration`` s of the cycle clock passed. The command's
        start is over: the garbage collector released (:func:`omnibot.collector.release`)."""
        collector.release()
        start = self.pacer.now()
        while not (until is not None and until()) and (
            duration is None or self.pacer.now() - start < duration
        ):
            self.step()
            if until is not None and until():
                break
            self.wait()
