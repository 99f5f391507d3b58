"""The network-safety guard: no DDS participant under pytest outside a private network namespace.

Tests that start DDS run in a subprocess under ``unshare -n`` with ``lo`` up, so no packet can leave
the machine. :func:`check_participant_allowed` refuses a participant when pytest is running (or its
child processes, which inherit ``PYTEST_CURRENT_TEST``) and any network interface other than ``lo``
exists
(read from ``/proc/self/net/dev``).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

NET_DEV = Path("/proc/self/net/dev")
"""This process's network namespace's interfaces (``/sys/class/net`` would show the host's after
``unshare -n`` without a fresh sysfs mount)."""


class UnsafeNetwork(RuntimeError):
    """A DDS participant was about to start where it could reach a real network under test."""


def interfaces(dev: Path = NET_DEV) -> list[str]:
    """The network interfaces of this process's network namespace."""
    try:
        lines = dev.read_text().splitlines()[2:]  # two header lines
    except OSError:
        return []
    return sorted(line.split(":", 1)[0].strip() for line in lines if ":" in line)


def under_pytest() -> bool:
    """This process is pytest or a child of it."""
    return "pytest" in sys.modules or "PYTEST_CURRENT_TEST" in os.environ


def in_private_namespace(dev: Path = NET_DEV) -> bool:
    """The only network interface is the loopback one (``unshare -n`` with ``lo`` up)."""
    return interfaces(dev) == ["lo"]


def check_participant_allowed(dev: Path = NET_DEV) -> None:
    """Raise :class:`UnsafeNetwork` under pytest outside a private network namespace."""
    if under_pytest() and not in_private_namespace(dev):
        raise UnsafeNetwork(
            "refusing to start a DDS participant under pytest outside a private network namespace "
            f"(interfaces: {', '.join(interfaces(dev)) or 'none'}); run it under `unshare -n` with lo up"
        )
