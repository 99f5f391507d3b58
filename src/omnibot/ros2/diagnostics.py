"""The bridge's ``/diagnostics``: diagnostic_msgs/DiagnosticStatus built for a robot (:class:`Diagnosed`:
whose statuses they are, named apart in a fleet), and what adds one to every message (a
:data:`Reporter`: the path follower, odometry resets).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from omnibot.logs import schemas

Reporter = Callable[[], Any]
"""Something that adds a diagnostic_msgs/DiagnosticStatus to every ``/diagnostics`` message (the path
follower, odometry resets)."""


def kv(key: str, value: object) -> Any:
    """A diagnostic_msgs/KeyValue."""
    return schemas.new("diagnostic_msgs/msg/KeyValue", key=key, value=str(value))


def status(level: int, name: str, message: str, hardware_id: str, values: dict[str, object]) -> Any:
    """A diagnostic_msgs/DiagnosticStatus (``level`` 0 OK, 1 WARN, 2 ERROR)."""
    return schemas.new(
        "diagnostic_msgs/msg/DiagnosticStatus",
        level=level,
        name=name,
        message=message,
        hardware_id=hardware_id,
        values=[kv(k, v) for k, v in values.items()],
    )


@dataclass(frozen=True)
class Diagnosed:
    """Whose diagnostic statuses these are: ``hardware_id`` is the robot's name (its namespace, in a
    fleet; else the description's), and a robot with a namespace has it in every status name
    (``omnibot r1: control``), so two robots' statuses on the one ``/diagnostics`` never read alike."""

    hardware_id: str
    namespace: str = ""

    @classmethod
    def of(cls, robot: str, namespace: str = "") -> Diagnosed:
        """The robot named ``robot`` (its description's name) in ``namespace``."""
        return cls(namespace.strip("/") or robot, namespace.strip("/"))

    def name(self, item: str) -> str:
        """The status name of ``item`` (``control``, ``battery``, ``path``, ``odometry``)."""
        return f"omnibot {self.namespace}: {item}" if self.namespace else f"omnibot: {item}"

    def status(self, level: int, item: str, message: str, values: dict[str, object]) -> Any:
        """The robot's diagnostic_msgs/DiagnosticStatus of ``item``."""
        return status(level, self.name(item), message, self.hardware_id, values)
