"""Arbitration between command sources, as ROS users know it from ``twist_mux``.

::

    every cycle, for each source (highest priority first):
      active  = it proposed a twist within its own ``timeout`` (s)
      masked  = an engaged lock has a priority >= the source's
    the highest-priority active source that is not masked drives; ties go to the one listed first

* **Priorities** (0-255 as in twist_mux): a higher one takes over from a lower one the moment it
  proposes, and keeps the robot until it has been silent for its ``timeout``; only then does a
  lower one get the robot back. A source that is active but silent this cycle sends nothing
  (the controller's VEL watchdog ends its last command), as twist_mux publishes nothing.
* **Locks** override: an engaged lock of priority P masks every source of priority <= P. The
  emergency stop is a lock of priority 255 (everything stops); a deadman lock is engaged while its
  button is *not* held (an autonomous source below it moves only while someone holds it).

The arbiter only decides; the runtime sends. :class:`Decision` says who drives and why, in words.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from omnibot.motion import Twist
from omnibot.runtime.cycle import Decision

PRIORITY_MAX = 255


@dataclass
class Lock:
    """A lock: while ``engaged()`` returns a reason (not None), sources of priority <= ``priority``
    cannot drive."""

    name: str
    priority: int
    engaged: Callable[[], str | None]


class EStop:
    """The emergency stop as a lock (priority 255): engaged by :meth:`press` until :meth:`resume`."""

    def __init__(self, name: str = "estop", priority: int = PRIORITY_MAX) -> None:
        self.pressed_by = ""
        self.lock = Lock(name, priority, self._engaged)

    def press(self, by: str) -> None:
        """Engage the stop; ``by`` says who pressed it (shown in the reason)."""
        self.pressed_by = by

    def resume(self) -> None:
        """Release the stop: sources may drive again (a person with a fresh input)."""
        self.pressed_by = ""

    @property
    def engaged(self) -> bool:
        """True while the stop is pressed."""
        return bool(self.pressed_by)

    def _engaged(self) -> str | None:
        return f"emergency stop ({self.pressed_by})" if self.pressed_by else None


def deadman_lock(name: str, priority: int, held: Callable[[], bool]) -> Lock:
    """A lock engaged while ``held()`` is False: sources up to ``priority`` move only while it is held."""
    return Lock(name, priority, lambda: None if held() else f"{name} not held")


@dataclass
class _Input:
    name: str
    priority: int
    timeout: float
    last: float = -float("inf")
    twist: Twist | None = None


class Arbiter:
    """Picks the source that drives each cycle (see the module docstring)."""

    def __init__(self, locks: Sequence[Lock] = ()) -> None:
        self.locks = list(locks)
        self._inputs: dict[str, _Input] = {}

    def add(self, name: str, priority: int, timeout: float) -> None:
        """Arbitrate a source: ``priority`` 0-255 (higher wins), active ``timeout`` s after a proposal."""
        if name in self._inputs:
            raise ValueError(f"a source named {name!r} is already arbitrated")
        if not 0 <= priority <= PRIORITY_MAX or not timeout > 0:
            raise ValueError(f"priority must be 0..255 and timeout > 0, got {priority}, {timeout}")
        self._inputs[name] = _Input(name, priority, timeout)

    def remove(self, name: str) -> None:
        """Stop arbitrating the source ``name`` (no-op if unknown)."""
        self._inputs.pop(name, None)

    def decide(self, now: float, proposals: dict[str, Twist | None]) -> Decision:
        """The decision at ``now`` given this cycle's proposals (None: the source had nothing to say)."""
        for name, twist in proposals.items():
            inp = self._inputs[name]
            inp.twist = twist
            if twist is not None:
                inp.last = now
        active = sorted(
            (i for i in self._inputs.values() if now - i.last <= i.timeout),
            key=lambda i: -i.priority,
        )
        locks = [(lock, why) for lock in self.locks if (why := lock.engaged()) is not None]
        for inp in active:
            blocking = [(lock, why) for lock, why in locks if lock.priority >= inp.priority]
            if blocking:
                lock, why = max(blocking, key=lambda lw: lw[0].priority)
                return Decision(
                    "", None, f"{inp.name} held by {why}", lock=lock.name, estop=lock.priority >= PRIORITY_MAX
                )
            others = [i.name for i in active if i is not inp]
            reason = f"{inp.name} (priority {inp.priority})"
            if others:
                reason += " over " + ", ".join(others)
            return Decision(inp.name, inp.twist, reason)
        if locks:
            lock, why = max(locks, key=lambda lw: lw[0].priority)
            return Decision("", None, why, lock=lock.name, estop=lock.priority >= PRIORITY_MAX)
        return Decision("", None, "no source active")
