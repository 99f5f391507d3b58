"""The one exception hierarchy of omnibot.

::

    OmnibotError                  every error omnibot raises on purpose
     +-- ConfigError              a robot description, world or config file is wrong (names the key)
     +-- KinematicsError          a wheel layout cannot do what was asked (e.g. not holonomic)
     +-- SimulationError          the simulator was given something it cannot simulate
     |    +-- SimulationSetupError  ... when built: a start pose in a wall, a bad dt (also a
     |                              ConfigError: the command could not start, exit status 2)
     +-- ProtocolError            bytes or a message that do not follow the protocol
     +-- LinkError                a byte link failed (port gone, refused, closed)
     |    +-- LinkTimeout         nothing arrived in time
     +-- ControllerError          the motor controller answered ERROR,<code>,<text>
     +-- PlanningError            no way to a place on a map (mapping.planner)
          +-- OffMapError         the start or goal lies outside the map (also a ConfigError)
          +-- BlockedError        the start or goal is in a wall, unknown space or too near a wall
          |                       (also a ConfigError: a bad goal is a bad argument)
          +-- NoPathError         the map has no collision-free way between them

The CLI turns any OmnibotError into a one-line message and a non-zero exit status.
"""

from __future__ import annotations


class OmnibotError(Exception):
    """Base class of every error omnibot raises on purpose."""


class ConfigError(OmnibotError, ValueError):
    """A description, world or configuration file is malformed; the message names the bad key."""

    def __init__(self, message: str, key: str | None = None) -> None:
        super().__init__(f"{key}: {message}" if key else message)
        self.key = key


class KinematicsError(OmnibotError, ValueError):
    """A wheel layout cannot do what was asked of it."""


class SimulationError(OmnibotError):
    """The simulator was asked for something it cannot simulate."""


class SimulationSetupError(SimulationError, ConfigError):
    """The simulator cannot be built as asked (its world, start pose, step): what was given is wrong,
    so the command could not start (a ConfigError: exit status 2, not a run that failed)."""


class ProtocolError(OmnibotError, ValueError):
    """Bytes or a message that do not follow the protocol."""


class LinkError(OmnibotError, OSError):
    """A byte link failed: the port went away, the peer refused or closed."""


class LinkTimeout(LinkError, TimeoutError):
    """Nothing arrived on a link within the timeout."""


class ControllerError(OmnibotError):
    """The motor controller rejected a command with ``ERROR,<code>,<text>``."""

    def __init__(self, code: int, text: str) -> None:
        super().__init__(f"controller error {code}: {text}")
        self.code = code
        self.text = text


class PlanningError(OmnibotError, ValueError):
    """No collision-free path could be planned on the map (the message says why, in the map frame)."""


class OffMapError(PlanningError, ConfigError):
    """The start or the goal lies outside the map (a bad argument: also a ConfigError)."""


class BlockedError(PlanningError, ConfigError):
    """The start or the goal lies in a wall, in unknown space or closer to a wall than the robot fits
    (a bad argument: also a ConfigError)."""


class NoPathError(PlanningError):
    """The map has no collision-free way from the start to the goal."""
