"""The network guard: under pytest a DDS participant needs a namespace whose only interface is lo."""

from __future__ import annotations

from pathlib import Path

import pytest

from omnibot.ros2 import netns

HEADER = "Inter-|   Receive |  Transmit\n face |bytes packets|bytes packets\n"


def _net(tmp_path: Path, *names: str) -> Path:
    dev = tmp_path / "dev"
    dev.write_text(HEADER + "".join(f"  {name}: 0 0 0 0\n" for name in names))
    return dev


def test_refuses_with_a_real_interface(tmp_path: Path) -> None:
    root = _net(tmp_path, "lo", "eth0")
    assert netns.under_pytest()
    with pytest.raises(netns.UnsafeNetwork, match="eth0"):
        netns.check_participant_allowed(root)


def test_allows_loopback_only(tmp_path: Path) -> None:
    netns.check_participant_allowed(_net(tmp_path, "lo"))


def test_refuses_without_loopback(tmp_path: Path) -> None:
    with pytest.raises(netns.UnsafeNetwork):
        netns.check_participant_allowed(_net(tmp_path))


def test_this_test_process_is_not_allowed_unless_namespaced() -> None:
    if netns.in_private_namespace():
        pytest.skip("the suite itself runs in a private network namespace")
    with pytest.raises(netns.UnsafeNetwork):
        netns.check_participant_allowed()


def _routes(dev: Path, *rows: tuple[str, str, str, str]) -> None:
    """``/proc/self/net/route`` beside ``dev``: (interface, destination, gateway, mask) dotted."""

    def hexed(address: str) -> str:
        return f"{int.from_bytes(bytes(int(b) for b in address.split('.')), 'little'):08X}"

    head = "Iface\tDestination\tGateway \tFlags\tRefCnt\tUse\tMetric\tMask\t\tMTU\tWindow\tIRTT\n"
    lines = [f"{i}\t{hexed(d)}\t{hexed(g)}\t0001\t0\t0\t0\t{hexed(m)}\t0\t0\t0\n" for i, d, g, m in rows]
    dev.with_name("route").write_text(head + "".join(lines))


def test_a_test_networks_host_is_allowed_and_nothing_that_reaches_further(tmp_path: Path) -> None:
    """A host of TwoHosts (a veth in 192.0.2.0/24, multicast on the link, link-local IPv6 at most) is
    allowed; a default route, a gateway, another range or a global IPv6 address is not."""
    dev = _net(tmp_path, "lo", "veth0")
    link = ("veth0", "192.0.2.0", "0.0.0.0", "255.255.255.0")
    multicast = ("veth0", "224.0.0.0", "0.0.0.0", "240.0.0.0")
    _routes(dev, link, multicast)
    dev.with_name("if_inet6").write_text("fe80000000000000000000fffe000001 03 40 20 80 veth0\n")
    netns.check_participant_allowed(dev)
    assert netns.in_test_network(dev) and not netns.in_private_namespace(dev)
    for more in (
        ("veth0", "0.0.0.0", "192.0.2.254", "0.0.0.0"),  # a default route
        ("veth0", "198.51.100.0", "0.0.0.0", "255.255.255.0"),  # another range
        ("veth0", "192.0.0.0", "0.0.0.0", "255.255.0.0"),  # wider than the documentation range
    ):
        _routes(dev, link, more)
        with pytest.raises(netns.UnsafeNetwork, match="veth0"):
            netns.check_participant_allowed(dev)
    _routes(dev, link)
    dev.with_name("if_inet6").write_text("20010db8000000000000000000000001 03 40 00 80 veth0\n")
    assert not netns.in_test_network(dev)
    dev.with_name("route").unlink()
    assert not netns.in_test_network(dev)  # what cannot be read is not a test network
