"""What every message of the protocol shares (:class:`MessageBase`: its keyword, ``params()`` and
``label()``), the messages without parameters (:class:`NoParams`) and with a code and a text
(:class:`Coded`: ERROR and WARN), and the check of a message's parameter count. The messages:
:mod:`omnibot.protocol.messages`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, Self

from omnibot.errors import ProtocolError
from omnibot.protocol import codes


def check_count(cls: type, params: Sequence[int], low: int, high: int | None = None) -> None:
    """ProtocolError unless ``params`` has ``low`` to ``high`` (default ``low``) integers."""
    """ProtocolError unless ``params`` has ``low`` to ``high`` (default ``low``) integers."""
    high = low if high is None else high
    if not low <= len(params) <= high:
        want = str(low) if low == high else f"{low}..{high}"
        raise ProtocolError(f"{cls.__name__} takes {want} integers, got {len(params)}")


def check_command_count(cls: type[MessageBase], params: Sequence[int]) -> None:
    """ProtocolError unless ``params`` has as many integers as the command ``cls`` takes."""
    check_count(cls, params, *codes.PARAM_COUNTS[cls.TYPE])


class MessageBase:
    """Behaviour shared by every message (not a message itself)."""

    TYPE: ClassVar[int]
    __slots__ = ()

    @property
    def keyword(self) -> str:
        """The text keyword (``MOVE``, ``OK``, ...)."""
        return codes.KEYWORDS[self.TYPE]

    def params(self) -> tuple[int, ...]:
        """The message's integers in wire order."""
        return ()

    def label(self) -> str:
        """The message's text field ("" if it has none)."""
        return ""


class NoParams(MessageBase):
    """A message without parameters."""

    __slots__ = ()

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """The message; ProtocolError when any integer comes with it."""
        check_count(cls, params, 0)
        return cls()


@dataclass(frozen=True)
class Coded(MessageBase):
    """A code with a text: ERROR and WARN."""

    code: int
    text: str = ""

    @property
    def description(self) -> str:
        """The text, or the standard text of the code when the controller sent none."""
        return self.text or codes.TEXTS.get(self.code, "")

    def params(self) -> tuple[int, ...]:
        """The code."""
        return (self.code,)

    def label(self) -> str:
        """The text."""
        return self.text

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from its code and text; ProtocolError unless one integer comes."""
        check_count(cls, params, 1)
        return cls(params[0], label)
