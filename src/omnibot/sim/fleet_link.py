"""A fleet's robots on in-process links: ``sim://omni4?fleet=NAME&name=r1&pose=X,Y,THETA``.

Links opened in one process with the same ``fleet`` share one :class:`~omnibot.sim.fleet.Fleet`
(one world, one simulated clock); each link is one robot, with its own firmware, seed and preset.
Each is a :class:`FleetLink`, a :class:`~omnibot.transport.lockstep.LockstepLink` whose waits step
the whole fleet: simulated time advances for every robot together, and a robot whose client is
not reading keeps running its firmware (its replies and telemetry wait on its line).

Who may move time (deterministic with several threads)::

    a link's driver   the thread that last waited on it (a read with a timeout, clock.sleep)
    time advances     only while every driver of an open link is waiting on one of the fleet's
                      links, and none of those waits is over; then any waiting thread steps the
                      fleet, tick by tick, until a wait is over (its bytes arrived, its time came)

So several runtimes, one per robot, each in its own thread, step one fleet in lockstep: while one
thread computes between waits simulated time stands still, so what each robot's client sends
reaches its firmware at the same simulated time whatever the threads' timing, and a run is
deterministic for its seeds. One thread driving several robots (a test) moves time with any of
them. A thread that hands a link to another (it opened the session, a runtime thread drives it)
stops being its driver at that thread's first wait. A driver that has not waited for
:data:`GRACE` s of wall time while the others wait (it opened a client and went on to other work,
or to join the runtime threads) is taken to have left: it stops driving its links, with a warning,
and time moves on without it; should it wait again it drives again, from whatever simulated time it
finds (a run with such a pause between waits is not reproducible). So nothing hangs. Open every
robot's link before any thread waits (a robot joins at the fleet's time of its opening).

Closing a link takes its robot out of the world; the last one closed ends the fleet, so the name
may be used again with other options.
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass

from omnibot import motion
from omnibot.errors import ConfigError
from omnibot.motion import Pose2D
from omnibot.robot import RobotDescription
from omnibot.sim.device import SimDevice
from omnibot.sim.fleet import Fleet
from omnibot.sim.world import World, load_world
from omnibot.transport import DEFAULT_BAUD, LockstepLink

__all__ = ["GRACE", "FleetLink", "SharedFleet", "join_fleet", "open_fleets", "parse_pose"]

log = logging.getLogger(__name__)

GRACE = 2.0
"""Wall-clock seconds a driver may go without waiting, while the others wait, before it is taken to
have left its links (far longer than a runtime's work between two cycles)."""
_POLL = 0.1
"""Wall-clock seconds between looks at the drivers while time is held (a driver thread may end)."""


@dataclass
class _Wait:
    """One thread's wait on one link: until ``target_us`` (None: no limit) or, for a read, bytes."""

    link: FleetLink
    target_us: int | None
    for_bytes: bool

    def over(self, now_us: int) -> bool:
        return (
            self.link.closed
            or (self.target_us is not None and now_us >= self.target_us)
            or (self.for_bytes and bool(self.link._inbox))
        )


class SharedFleet:
    """A :class:`Fleet` shared by the links of one process under the name ``key``."""

    def __init__(self, key: str, world: World, base: World, origin: str) -> None:
        self.key = key
        self.fleet = Fleet(world)
        self.base = base
        """The world as named by the URLs (before a surface override), to compare later ones with."""
        self.origin = origin
        """The URL of the robot that made the fleet (named in errors)."""
        self.lock = threading.RLock()
        self._cond = threading.Condition(self.lock)
        self.links: list[FleetLink] = []
        self._waits: dict[threading.Thread, _Wait] = {}
        self.grace = GRACE
        """Wall-clock seconds before an idle driver is taken to have left (:data:`GRACE`)."""

    def __repr__(self) -> str:
        return f"SharedFleet({self.key!r}, {self.fleet!r})"

    # ------------------------------------------------------------------ time

    def wait(self, link: FleetLink, target_us: int | None, for_bytes: bool) -> None:
        """Block until ``target_us`` (fleet time) or, with ``for_bytes``, bytes reach ``link``'s host
        side, stepping the fleet whenever every driver waits (the caller holds :attr:`lock`)."""
        me = threading.current_thread()
        link.driver = me
        wait = _Wait(link, target_us, for_bytes)
        self._waits[me] = wait
        self._cond.notify_all()  # one more waiter: the others may be free to move time now
        held_at, held_us = time.monotonic(), self.fleet.ticks_us
        try:
            while not wait.over(self.fleet.ticks_us):
                if self._free():
                    self._tick()
                    if any(w.over(self.fleet.ticks_us) for w in self._waits.values() if w is not wait):
                        self._cond.notify_all()
                    continue
                self._cond.wait(_POLL)
                if self.fleet.ticks_us != held_us:
                    held_at, held_us = time.monotonic(), self.fleet.ticks_us
                elif time.monotonic() - held_at > self.grace:
                    self._release_idle()
                    held_at = time.monotonic()
        finally:
            del self._waits[me]

    def _drivers(self) -> set[threading.Thread]:
        return {ln.driver for ln in self.links if ln.driver is not None and ln.driver.is_alive()}

    def _free(self) -> bool:
        """Whether time may move: every driver waits and no wait is over."""
        now = self.fleet.ticks_us
        return all(d in self._waits for d in self._drivers()) and not any(
            w.over(now) for w in self._waits.values()
        )

    def _tick(self) -> None:
        links = self.links
        for ln in links:
            ln._feed()
        self.fleet.step()
        for ln in links:
            ln.steps += 1
            ln._drain()

    def _release_idle(self) -> None:
        """Drivers that have not waited for :attr:`grace` s stop driving their links."""
        for ln in self.links:
            if ln.driver is not None and ln.driver not in self._waits:
                log.warning(
                    "fleet %r: thread %r has not waited on robot %r's link for %g s while the others "
                    "wait; simulated time moves on without it (a run with such a pause is not reproducible)",
                    self.key,
                    ln.driver.name,
                    ln.name,
                    self.grace,
                )
                ln.driver = None

    # ------------------------------------------------------------------ membership

    def leave(self, link: FleetLink) -> None:
        """Take ``link``'s robot out of the world; the last one ends the fleet."""
        with self.lock:
            if link in self.links:
                self.links.remove(link)
                self.fleet.remove(link.name)
            self._cond.notify_all()  # a driver fewer: the others may be free to move time
            empty = not self.links
        if empty:
            with _registry_lock:
                if _fleets.get(self.key) is self and not self.links:
                    del _fleets[self.key]


class FleetLink(LockstepLink):
    """One robot of a :class:`SharedFleet`: a lockstep link whose waits step the whole fleet."""

    device: SimDevice

    def __init__(self, shared: SharedFleet, name: str, device: SimDevice, *, baud: int, url: str) -> None:
        super().__init__(device, baud=baud, url=url)
        self._lock = shared.lock  # one lock for the fleet: a write lands at a definite fleet time
        self.shared = shared
        self.name = name
        self.driver: threading.Thread | None = None
        """The thread that last waited on this link (None before any wait)."""

    @property
    def fleet(self) -> Fleet:
        """The fleet this robot is in."""
        return self.shared.fleet

    def _target(self, seconds: float) -> int:
        fleet = self.shared.fleet
        return fleet.ticks_us + self._ticks_for(seconds) * round(fleet.dt * 1e6)

    def advance(self, seconds: float) -> None:
        """Wait ``seconds`` of simulated time (whole ticks), the whole fleet moving with it."""
        self._check_open()
        with self._lock:
            if self._ticks_for(seconds):
                self.shared.wait(self, self._target(seconds), for_bytes=False)

    def _read(self, max_bytes: int, timeout: float | None, ends: bytes = b"", most: int = 0) -> bytes:
        """A read, gathered or not, waits on the fleet's time, which moves for every robot's driver
        (a lone lockstep link's gathering steps its own device): the bytes as they come."""
        with self._lock:
            self._collect()
            if not self._inbox and timeout != 0:
                target = None if timeout is None else self._target(timeout)
                self.shared.wait(self, target, for_bytes=True)
            chunk = bytes(self._inbox[:max_bytes])
            del self._inbox[:max_bytes]
            return chunk

    def _close(self) -> None:
        try:
            super()._close()
        finally:
            self.shared.leave(self)


_fleets: dict[str, SharedFleet] = {}
_registry_lock = threading.Lock()


def open_fleets() -> dict[str, SharedFleet]:
    """The fleets of this process by name (a copy)."""
    with _registry_lock:
        return dict(_fleets)


def join_fleet(
    key: str,
    robot: RobotDescription | str,
    *,
    name: str = "",
    seed: int = 0,
    pose: Pose2D | None = None,
    world: str | None = None,
    surface: str | None = None,
    baud: int = DEFAULT_BAUD,
    url: str = "",
) -> FleetLink:
    """Put a robot into fleet ``key`` (made on first use, in ``world`` with ``surface``) and return its
    link. ConfigError for a name taken, a pose overlapping a wall, an obstacle or another robot, or a
    world or surface other than the fleet's (a robot that names none takes the fleet's)."""
    base = load_world(world) if world else None
    with _registry_lock:
        shared = _fleets.get(key)
        if shared is None:
            base = base or load_world("empty")
            placed = base.with_floor(surface) if surface is not None and surface != base.floor else base
            shared = SharedFleet(key, placed, base, url)
            _fleets[key] = shared
        else:
            _same_room(shared, base, surface, url)
        try:
            with shared.lock:
                fleet = shared.fleet
                name = name or _free_name(fleet)
                device = fleet.add(name, robot, seed=seed, pose=pose)
                link = FleetLink(shared, name, device, baud=baud, url=url or f"sim://{device.robot.name}")
                shared.links.append(link)
                shared.links.sort(key=lambda ln: ln.name)
        except BaseException:
            if not shared.links:
                del _fleets[key]
            raise
    return link


def _same_room(shared: SharedFleet, base: World | None, surface: str | None, url: str) -> None:
    first = f"set by {shared.origin!r}" if shared.origin else "set by its first robot"
    if base is not None and base.spec != shared.base.spec:
        raise ConfigError(
            f"fleet {shared.key!r} is in world {shared.base.name!r} ({first}); {url!r} asks for world "
            f"{base.name!r}: the robots of a fleet share one world (leave world= out to take the fleet's)",
            key="world",
        )
    floor = shared.fleet.world.floor
    if surface is not None and surface != floor:
        raise ConfigError(
            f"fleet {shared.key!r} has a {floor} floor ({first}); {url!r} asks for surface {surface!r}: "
            "the robots of a fleet share one floor (leave surface= out to take the fleet's)",
            key="surface",
        )


def _free_name(fleet: Fleet) -> str:
    taken = set(fleet.names)
    return next(f"r{k}" for k in range(1, len(taken) + 2) if f"r{k}" not in taken)


def parse_pose(text: str, source: str = "") -> Pose2D:
    """``X,Y,THETA`` (m, m, degrees, as a world file's ``start``) as a :class:`Pose2D` (radians)."""
    x, y, theta = motion.parse_pose(
        text, "pose", prefix="pose=", where=f" in URL {source!r}" if source else ""
    )
    assert theta is not None  # the heading is required
    return Pose2D(x, y, theta)
