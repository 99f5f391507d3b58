"""The simulated device behind a link, if there is one: ground truth for reports, status lines and the
dashboard.

``sim://`` opens a :class:`~omnibot.transport.lockstep.LockstepLink` whose ``device`` is a
:class:`~omnibot.sim.device.SimDevice` (``device.sim`` is its Simulator); the wrappers (``spy+``,
``faults+``) keep the link they wrap in ``.inner``. :func:`find_device` walks that chain, so every
caller sees the simulator behind any stack of wrappers. Links still know nothing of the simulator: a
device is recognised by having a ``sim``. Reading the simulator is only safe from the thread that owns
the client.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from omnibot.transport.base import Link

if TYPE_CHECKING:
    from omnibot.sim import SimDevice, Simulator

MAX_WRAPPERS = 16
"""Wrappers followed before giving up (a cycle of ``inner`` links would otherwise never end)."""


def find_device(link: Link) -> SimDevice | None:
    """The simulated device behind ``link`` (through ``spy+``/``faults+`` wrappers), None for a real
    link (serial, TCP, a pty)."""
    seen: object = link
    for _ in range(MAX_WRAPPERS):
        device = getattr(seen, "device", None)
        if device is not None and hasattr(device, "sim"):
            return device  # type: ignore[no-any-return]
        seen = getattr(seen, "inner", None)
        if seen is None:
            return None
    return None


def find_simulator(link: Link) -> Simulator | None:
    """The Simulator behind ``link`` (:func:`find_device`'s ``sim``), None for a real link."""
    device = find_device(link)
    return None if device is None else device.sim
