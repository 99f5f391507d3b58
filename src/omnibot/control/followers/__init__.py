"""Path followers, registered by name: ``seed002``, ``seed002-plain``, ``pure_pursuit``, ``tracker``.

See :mod:`omnibot.control.followers.base` for the interface and :func:`make_follower`.
"""

from omnibot.control.followers import pure_pursuit, seed002, tracker
from omnibot.control.followers.base import (
    FOLLOWERS,
    STOP,
    Command,
    Follower,
    State,
    follower_names,
    make_follower,
    register,
)

__all__ = [
    "FOLLOWERS",
    "STOP",
    "Command",
    "Follower",
    "State",
    "base",
    "follower_names",
    "make_follower",
    "pure_pursuit",
    "register",
    "seed002",
    "tracker",
]
