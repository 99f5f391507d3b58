"""The network-safety guard: no DDS participant under pytest outside a private network namespace.

Tests that start DDS run in a subprocess under ``unshare -n`` with ``lo`` up, so no packet can leave
the machine. :func:`check_participant_allowed` refuses a participant when pytest is running (or its
child processes, which inherit ``PYTEST_CURRENT_TEST``) and any network interface other than ``lo``
exists (read from ``/proc/self/net/dev``), unless the namespace is a *test network*
(:func:`in_test_network`): every IPv4 route leads into the documentation range 192.0.2.0/24 (or is
multicast on the link), with no gateway, and no IPv6 address but link-local ones, as in the hosts
:class:`TwoHosts` makes: two namespaces joined by a veth pair, both made inside one private
namespace, so the pair is all the network there is.
"""

from __future__ import annotations

import ipaddress
import os
import shutil
import socket
import struct
import subprocess
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any

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


TEST_NET = ipaddress.IPv4Network("192.0.2.0/24")
"""The documentation range (RFC 5737): the only addresses of a test network."""
MULTICAST = ipaddress.IPv4Network("224.0.0.0/4")


def routes(path: Path) -> list[tuple[str, ipaddress.IPv4Network, bool]]:
    """The IPv4 routes of ``path`` (``/proc/self/net/route``): interface, destination, via a gateway."""
    found = []
    for line in path.read_text().splitlines()[1:]:
        fields = line.split()
        if len(fields) < 8:
            continue
        dest, gateway, mask = (
            socket.inet_ntoa(struct.pack("<I", int(f, 16))) for f in fields[1:3] + fields[7:8]
        )
        found.append((fields[0], ipaddress.IPv4Network(f"{dest}/{mask}", strict=False), gateway != "0.0.0.0"))
    return found


def in_test_network(dev: Path = NET_DEV) -> bool:
    """Interfaces besides ``lo``, and nothing they reach but 192.0.2.0/24 (and multicast on the link):
    no gateway, no IPv6 address but link-local ones (``route`` and ``if_inet6`` beside ``dev``)."""
    if [name for name in interfaces(dev) if name != "lo"] == []:
        return False
    try:
        table = routes(dev.with_name("route"))
        inet6 = dev.with_name("if_inet6")
        ipv6 = inet6.read_text().split() if inet6.exists() else []
    except (OSError, ValueError):
        return False
    for iface, net, via in table:
        if iface != "lo" and (via or not (net.subnet_of(TEST_NET) or net.subnet_of(MULTICAST))):
            return False
    addresses = ipv6[::6]  # address, index, prefix, scope, flags, interface
    return all(a == "0" * 31 + "1" or a.startswith("fe80") for a in addresses)


def check_participant_allowed(dev: Path = NET_DEV) -> None:
    """Raise :class:`UnsafeNetwork` under pytest outside a private network namespace (or a test
    network's host)."""
    if under_pytest() and not in_private_namespace(dev) and not in_test_network(dev):
        raise UnsafeNetwork(
            "refusing to start a DDS participant under pytest outside a private network namespace "
            f"(interfaces: {', '.join(interfaces(dev)) or 'none'}); run it under `unshare -n` with lo up"
        )


class TwoHosts:
    """Two "hosts" for fleet tests and benchmarks: two network namespaces joined by a veth pair,
    ``192.0.2.1`` and ``192.0.2.2`` (/24), made from inside a private namespace (``unshare -n``; the
    caller's, checked) by root. ``multicast=False`` turns multicast off on the link (a network where
    discovery needs static peers). :meth:`run` starts a process on a host; leaving the ``with``
    ends every process started so, then the hosts (the namespaces go with their last process)."""

    ADDRESSES = ("192.0.2.1", "192.0.2.2")

    def __init__(self, multicast: bool = True) -> None:
        self.multicast = multicast
        self._holders: list[subprocess.Popen[str]] = []
        self._started: list[subprocess.Popen[Any]] = []

    def __enter__(self) -> TwoHosts:
        if not in_private_namespace():
            raise UnsafeNetwork(
                "the test hosts are made inside a private network namespace only (unshare -n)"
            )
        if shutil.which("nsenter") is None:
            raise UnsafeNetwork("nsenter is missing: no test hosts")
        try:
            self._make()
        except BaseException:
            self.close()
            raise
        return self

    def _make(self) -> None:
        for _ in self.ADDRESSES:
            holder = subprocess.Popen(
                ["unshare", "-n", "sh", "-c", "echo ready; exec sleep 3600"],
                stdout=subprocess.PIPE,
                text=True,
            )
            self._holders.append(holder)
            assert holder.stdout is not None
            if holder.stdout.readline().strip() != "ready":
                raise UnsafeNetwork("a test host's namespace could not be made")
            self._in(
                len(self._holders) - 1,
                "for f in all default; do echo 1 > /proc/sys/net/ipv6/conf/$f/disable_ipv6; done",
            )
        subprocess.run(["ip", "link", "add", "veth0", "type", "veth", "peer", "name", "veth1"], check=True)
        for host, address in enumerate(self.ADDRESSES):
            subprocess.run(
                ["ip", "link", "set", f"veth{host}", "netns", str(self._holders[host].pid)], check=True
            )
            setup = [
                "ip link set lo up",
                f"ip addr add {address}/24 dev veth{host}",
                f"ip link set veth{host} {'multicast on' if self.multicast else 'multicast off'} up",
            ]
            if self.multicast:
                setup.append(f"ip route add {MULTICAST} dev veth{host}")
            self._in(host, " && ".join(setup))

    def _in(self, host: int, command: str) -> None:
        subprocess.run(["nsenter", "-t", str(self._holders[host].pid), "-n", "sh", "-c", command], check=True)

    def run(
        self, host: int, argv: Sequence[str], env: Mapping[str, str] | None = None, **popen: Any
    ) -> subprocess.Popen[Any]:
        """Start ``argv`` on ``host`` (0 or 1); ended, if still running, when the hosts are."""
        process = subprocess.Popen([*self.prefix(host), *argv], env=env, **popen)
        self._started.append(process)
        return process

    def prefix(self, host: int) -> list[str]:
        """The command line prefix that runs a program on ``host`` (for a process on the other
        host to start one there: it ends it itself)."""
        return ["nsenter", "-t", str(self._holders[host].pid), "-n"]

    def close(self) -> None:
        """End every process started on the hosts, then the hosts."""
        for process in [*self._started, *self._holders]:
            if process.poll() is None:
                process.kill()
            process.wait()
            for stream in (process.stdout, process.stderr):
                if stream is not None:
                    stream.close()
        self._started.clear()
        self._holders.clear()

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()
