"""Arbitration as twist_mux does it: priorities, a timeout per source, locks that override."""

from __future__ import annotations

import pytest

from omnibot.motion import Twist
from omnibot.runtime.arbiter import PRIORITY_MAX, Arbiter, EStop, deadman_lock

FWD, LEFT = Twist(0.2, 0.0, 0.0), Twist(0.0, 0.2, 0.0)


def make() -> tuple[Arbiter, EStop, list[bool]]:
    estop = EStop()
    held = [False]
    arbiter = Arbiter([estop.lock, deadman_lock("autonomy deadman", 20, lambda: held[0])])
    arbiter.add("follower", 10, 0.05)
    arbiter.add("pad", 200, 0.5)
    return arbiter, estop, held


def test_the_higher_priority_takes_over_and_keeps_the_robot_until_its_timeout() -> None:
    arbiter, _, held = make()
    held[0] = True
    d = arbiter.decide(0.0, {"follower": FWD, "pad": None})
    assert (d.source, d.twist) == ("follower", FWD) and d.reason == "follower (priority 10)"
    d = arbiter.decide(0.1, {"follower": FWD, "pad": LEFT})
    assert (d.source, d.twist) == ("pad", LEFT) and d.reason == "pad (priority 200) over follower"
    # the pad falls silent: it still holds the robot (nothing is sent) until its timeout
    d = arbiter.decide(0.5, {"follower": FWD, "pad": None})
    assert (d.source, d.twist) == ("pad", None)
    d = arbiter.decide(0.61, {"follower": FWD, "pad": None})
    assert (d.source, d.twist) == ("follower", FWD)
    # a source silent longer than its own timeout is not active
    d = arbiter.decide(0.7, {"follower": None, "pad": None})
    assert d.source == "" and d.reason == "no source active"


def test_locks_mask_sources_at_or_below_their_priority() -> None:
    arbiter, estop, held = make()
    d = arbiter.decide(0.0, {"follower": FWD, "pad": None})
    assert d.source == "" and d.lock == "autonomy deadman" and not d.estop
    assert d.reason == "follower held by autonomy deadman not held"
    d = arbiter.decide(0.01, {"follower": FWD, "pad": LEFT})
    assert d.source == "pad"  # the deadman lock (20) does not hold a person's pad (200)
    held[0] = True
    estop.press("page")
    d = arbiter.decide(1.0, {"follower": FWD, "pad": LEFT})
    assert d.source == "" and d.twist is None and d.estop and d.lock == "estop"
    assert d.reason == "pad held by emergency stop (page)"
    d = arbiter.decide(2.0, {"follower": None, "pad": None})
    assert d.estop and d.reason == "emergency stop (page)"  # visible with nobody asking too
    estop.resume()
    d = arbiter.decide(2.01, {"follower": FWD, "pad": None})
    assert d.source == "follower"


def test_bad_sources_are_refused() -> None:
    arbiter, _, _ = make()
    with pytest.raises(ValueError, match="already arbitrated"):
        arbiter.add("pad", 1, 0.1)
    with pytest.raises(ValueError, match=r"priority must be 0\.\.255"):
        arbiter.add("x", PRIORITY_MAX + 1, 0.1)
    with pytest.raises(ValueError, match="timeout > 0"):
        arbiter.add("y", 1, 0.0)
