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
