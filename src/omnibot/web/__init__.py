"""The web dashboard: a page that shows the robot live and drives it (docs/dashboard.md).

::

    browser --ws--> server.py (FastAPI, uvicorn thread) --messages.py: validate--> queue
                                                                                    |
    robot <--client-- link.py (robot link thread: deadman, VEL, telemetry) <-------+
                         |--> state.py (state frames) --> queue --> server.py broadcaster --> pages

Modules: ``dashboard`` (Dashboard: both threads, binding, token), ``server`` (routes, websocket,
Hub), ``link`` (RobotLink, the thread that owns the client), ``messages`` (browser messages),
``state`` (telemetry -> state frames), ``scene`` (map, robot outline, path), ``teach`` (the teach
and repeat hook), ``command`` (``omnibot dashboard``), ``static/`` (the page).
"""

__all__ = ["access", "dashboard", "scene"]
