"""The optional parts of omnibot (pyproject's extras) and the one error a command gives when its part
is not installed.

``pip install omnibot`` is the core: robot descriptions, kinematics, the protocol, the transports,
the client and the firmware (numpy, pydantic, PyYAML, pyserial, tqdm). The rest comes with an extra,
``pip install 'omnibot[sim]'`` and so on (``[all]`` for everything). A command that reaches a module
of a missing extra ends with :func:`missing_extra`'s line and exit status 2, not an ImportError.
"""

from __future__ import annotations

EXTRA_OF: dict[str, str] = {
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
"""The extra that installs each optional top-level module omnibot imports (by its import name)."""

WHAT: dict[str, str] = {
    "sim": "the simulator",
    "plots": "plots",
    "web": "the dashboard",
    "teleop": "joysticks",
    "logs": "MCAP logs",
    "ros2": "ROS 2",
    "slam": "mapping and localisation",
}
"""What each extra brings, in a few words (its line in the error)."""


def missing_extra(exc: BaseException) -> str | None:
    """The one-line error for ``exc`` when it is the import of a module of an extra that is not
    installed (``None`` for any other exception, a missing omnibot module included: that is a bug)."""
    if not isinstance(exc, ModuleNotFoundError) or not exc.name:
        return None
    top = exc.name.split(".")[0]
    extra = EXTRA_OF.get(top)
    if extra is None:
        return None
    return (
        f"{top!r} is not installed (the {extra!r} extra: {WHAT[extra]}): "
        f"pip install 'omnibot[{extra}]' (or 'omnibot[all]')"
    )
