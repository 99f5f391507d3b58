"""The optional parts of omnibot (pyproject's extras) and the one error a command gives when its part
is not installed.

``pip install omnibot`` is the core: robot descriptions, kinematics, the protocol, the transports,
the client and the firmware (pydantic, PyYAML, pyserial, tqdm; no numpy). The rest comes with an
extra, ``pip install 'omnibot[sim]'`` and so on (``[all]`` for everything); numpy comes with every
extra whose modules import it, and alone with ``[control]`` (odometry, paths and control on a robot).
A command that reaches a module of a missing extra ends with :func:`missing_extra`'s line and exit
status 2, not an ImportError.
"""

from __future__ import annotations

EXTRA_OF: dict[str, str] = {
    "numpy": "control",
    "numba": "sim",
    "llvmlite": "sim",
    "matplotlib": "plots",
    "fastapi": "web",
    "starlette": "web",
    "uvicorn": "web",
    "websockets": "web",
    "pygame": "teleop",
    "mcap": "logs",
    "zstandard": "logs",
    "rosbags": "logs",
    "cyclonedds": "ros2",
    "gtsam": "slam",
    "scipy": "slam",
    "evo": "slam",
    "PIL": "slam",
    "rplidar": "slam",
    "ompl": "slam",
}
"""The extra that installs each optional top-level module omnibot imports (by its import name); for
a module several extras install (:data:`SHARED`), the one a command without its own extra needs."""

SHARED = frozenset({"numpy"})
"""Modules that several extras install: a command missing one is told its own extra
(:data:`COMMAND_EXTRA`)."""

COMMAND_EXTRA: dict[str, str] = {
    "sim": "sim",
    "tour": "sim",
    "demo": "sim",
    "teleop": "teleop",
    "dashboard": "web",
    "ros2": "ros2",
    "map": "slam",
    "goto": "slam",
    "log": "logs",
}
"""The extra each ``omnibot`` command needs beyond the core (a command not listed: ``EXTRA_OF``'s)."""

WHAT: dict[str, str] = {
    "control": "odometry, paths and control",
    "sim": "the simulator",
    "plots": "plots",
    "web": "the dashboard",
    "teleop": "joysticks",
    "logs": "MCAP logs",
    "ros2": "ROS 2",
    "slam": "mapping and localisation",
}
"""What each extra brings, in a few words (its line in the error)."""


def missing_extra(exc: BaseException, command: str | None = None) -> str | None:
    """The one-line error for ``exc`` when it is the import of a module of an extra that is not
    installed (``None`` for any other exception, a missing omnibot module included: that is a bug);
    ``command``, the ``omnibot`` command that ran into it, names the extra of a shared module."""
    if not isinstance(exc, ModuleNotFoundError) or not exc.name:
        return None
    top = exc.name.split(".")[0]
    extra = EXTRA_OF.get(top)
    if extra is None:
        return None
    if top in SHARED and command in COMMAND_EXTRA:
        extra = COMMAND_EXTRA[command]
    return (
        f"{top!r} is not installed (the {extra!r} extra: {WHAT[extra]}): "
        f"pip install 'omnibot[{extra}]' (or 'omnibot[all]')"
    )
