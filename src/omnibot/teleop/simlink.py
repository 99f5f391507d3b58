"""The simulated device behind a link, if there is one: ground truth for status lines and the dashboard.

``sim://`` opens a :class:`~omnibot.transport.lockstep.LockstepLink` to a
:class:`~omnibot.sim.device.SimDevice`; wrappers (``spy+``, ``faults+``) keep the link they wrap in
``.inner``. Reading the simulator's pose is only safe from the thread that owns the client.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from omnibot.transport.base import Link

if TYPE_CHECKING:
    from omnibot.sim.device import SimDevice


def sim_device(link: Link) -> SimDevice | None:
    """The SimDevice behind ``link`` (through wrappers), None for a real link."""
    seen: Link | None = link
    for _ in range(8):
        if seen is None:
            return None
        device = getattr(seen, "device", None)
        if device is not None and hasattr(device, "sim"):
            return device  # type: ignore[no-any-return]
        seen = getattr(seen, "inner", None)
    return None
