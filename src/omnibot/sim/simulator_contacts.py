"""The simulator's contacts with walls, obstacles and other robots, and the collision events they raise.

Collisions use a penalty force: each contact pushes along its normal with a spring-damper whose
stiffness is set from the simulation step (natural frequency 0.25/dt for the effective mass at the
contact point, critically damped), so the response is stiff yet stable for any robot mass, plus a
little wall friction (the compiled step applies it: :mod:`omnibot.sim.kernels.step`). The robot
sinks at most millimetres into a wall. A collision event is reported when the robot starts touching
a wall or obstacle (after 0.25 s without touching it, so one bump that bounces is one event).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import SimulationSetupError
from omnibot.motion import Pose2D
from omnibot.sim.clock import SimClock
from omnibot.sim.kernels import layout
from omnibot.sim.truth import CollisionEvent, CollisionListener
from omnibot.sim.world import Contact, World

FloatArray = NDArray[np.float64]

CONTACT_OMEGA_DT = 0.25
"""Contact spring natural frequency times dt (well inside the explicit-integration limit of 2)."""
CONTACT_DAMPING = 1.0
WALL_FRICTION = 0.2
CONTACT_RELEASE = 0.25
"""Seconds without touching after which touching the same wall again is a new collision event."""


class Contacts:
    """:class:`~omnibot.sim.simulator.Simulator`'s contact test at a pose (the compiled step does it
    while stepping, in the same rows), the contacts of the last step and its collision events."""

    world: World
    clock: SimClock
    collisions: list[CollisionEvent]
    _collision_listeners: list[CollisionListener]
    _touching: dict[str, int]
    _outline: FloatArray
    _pose_row: FloatArray
    _sf: FloatArray
    _si: NDArray[np.int64]
    _contact_out: FloatArray
    _contact_speed: FloatArray
    _new_contact: NDArray[np.int64]

    @property
    def contacts(self) -> list[Contact]:
        """Contacts found at the start of the last step."""
        return self.world.contact_list(self._contact_out[: self._si[layout.I_COUNT]])

    def on_collision(self, fn: CollisionListener) -> None:
        """Call ``fn(event)`` for every new collision (also appended to :attr:`collisions`)."""
        self._collision_listeners.append(fn)

    def _check_clear(self) -> None:
        """Refuse a start pose whose outline overlaps the world."""
        x, y, th = self._pose_row.tolist()
        touching = self._find_contacts(x, y, th)
        if touching >= 0:
            raise SimulationSetupError(
                f"start pose {Pose2D(x, y, th).text()} overlaps {self.world.contact_owners[touching]} "
                f"of world '{self.world.name}'"
            )

    def _collisions_found(self) -> None:
        """Collision events for the contacts the last step's test flagged as new (in row order)."""
        count = int(self._si[layout.I_COUNT])
        rows = self._contact_out[:count]
        sf = self._sf
        pose = Pose2D(float(sf[layout.F_AT_X]), float(sf[layout.F_AT_Y]), float(sf[layout.F_AT_TH]))
        for a, contact in enumerate(self.world.contact_list(rows)):
            if self._new_contact[a]:
                self._collide(contact, float(self._contact_speed[a]), pose)

    def _find_contacts(self, x: float, y: float, th: float) -> int:
        """Test the outline at (x, y, th) against the world; returns the owner id of the first contact or -1.

        Fills the contact rows and the broad-phase clearance (as the compiled step does).
        """
        count, clearance = self.world.contacts_at(self._outline, x, y, th, self._contact_out)
        sf = self._sf
        sf[layout.F_CLEAR_X], sf[layout.F_CLEAR_Y], sf[layout.F_CLEAR] = x, y, clearance
        self._si[layout.I_COUNT] = count
        return int(self._contact_out[0, 5]) if count else -1

    def touch(self, contact: Contact, speed: float) -> None:
        """A contact with something outside the world (a fleet's other robot) at this step: a
        :class:`CollisionEvent` when the robot starts touching ``contact.owner``, as for walls."""
        if not self._still_touching(contact.owner, self.clock.ticks_us()):
            self._collide(contact, speed)

    def _still_touching(self, owner: str, now_us: int) -> bool:
        """Whether ``owner`` was touched within CONTACT_RELEASE before ``now_us`` (now its last touch)."""
        last = self._touching.get(owner)
        self._touching[owner] = now_us
        return last is not None and now_us - last <= CONTACT_RELEASE * 1e6

    def _collide(self, contact: Contact, speed: float, pose: Pose2D | None = None) -> None:
        """A collision event for ``contact`` (the robot at ``pose``, else where it is now), to the listeners."""
        event = CollisionEvent(
            self.clock.now(),
            contact.point[0],
            contact.point[1],
            contact.normal,
            contact.depth,
            speed,
            contact.owner,
            Pose2D(*self._pose_row.tolist()) if pose is None else pose,
        )
        self.collisions.append(event)
        for fn in self._collision_listeners:
            fn(event)


__all__ = ["CONTACT_DAMPING", "CONTACT_OMEGA_DT", "CONTACT_RELEASE", "WALL_FRICTION", "Contacts"]
