"""The web dashboard: a page that shows the robot live and drives it (docs/dashboard.md).

::

    browser --ws--> server.py (FastAPI, uvicorn thread) --messages.py: validate--> queue
                                                                                    |
    robot <--client-- link.py (robot link thread: deadman, VEL, telemetry) <-------+
                         |--> state.py (state frames) --> queue --> server.py broadcaster --> pages

Modules: ``dashboard`` (Dashboard: both threads, binding, token), ``server`` (routes, websocket,
Hub), ``link`` (RobotLink, the thread that owns the client), ``inbox`` (the page's requests on their
way to it), ``driving`` (the page's input as teleop samples, the drive state), ``scanview`` (the
scans the page draws), ``messages`` (browser messages), ``state`` (telemetry -> state frames),
``scene`` (map, robot outline, path), ``teach`` (the teach and repeat hook), ``access`` (host,
origin and token checks), ``static/`` (the page). The command, ``omnibot dashboard``, is
``omnibot.apps.dashboard``.

Other packages take the dashboard, its scene's path and the access checks (the host and origin
checks, tokens, rate limits, the listening socket: the Foxglove server's too) from this face::

    from omnibot.web import Dashboard, HostPolicy, access_token

Each loads on first use, with only the module that defines it: the access checks load no FastAPI.
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.web.access import (
        HostPolicy,
        RateLimit,
        access_token,
        listening_socket,
        same_origin,
        token_ok,
    )
    from omnibot.web.dashboard import Dashboard
    from omnibot.web.scene import load_path

_EXPORTS = {
    "access": ("HostPolicy", "RateLimit", "access_token", "listening_socket", "same_origin", "token_ok"),
    "dashboard": ("Dashboard",),
    "scene": ("load_path",),
}

__all__ = [
    "Dashboard",
    "HostPolicy",
    "RateLimit",
    "access",
    "access_token",
    "dashboard",
    "listening_socket",
    "load_path",
    "same_origin",
    "scene",
    "token_ok",
]

if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
