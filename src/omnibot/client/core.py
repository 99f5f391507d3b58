"""What the client's concerns share: :class:`ClientCore`, the state a
:class:`~omnibot.client.client.RobotClient` sets up and its collaborators.

The client is built in layers, each a module with one concern and each using only those below:
``receiving`` (what arrives: replies to their commands, events to listeners), ``waiting`` (pumping
the link until something happened, retransmissions due), ``sending`` (commands out, and the steps
before a text command), and the client itself (its public face, the collaborators it owns).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from omnibot.client.events import Listeners
from omnibot.client.views import Hello
from omnibot.client.wire import Wire

if TYPE_CHECKING:
    from omnibot.client.connection import Connection
    from omnibot.client.replies import Replies
    from omnibot.client.switch import ProtocolSwitch
    from omnibot.client.tracing import Tracers
    from omnibot.transport import Clock, Link


class ClientCore:
    """The state every layer of the client reads; :class:`~omnibot.client.client.RobotClient` sets it."""

    timeout: float
    last_hello: Hello | None
    _connection: Connection
    """The link's bytes, traced; its failures and reopening (client/connection.py)."""
    _switch: ProtocolSwitch
    """The protocol spoken, the MODE bits, text's tags and checks; switching (client/switch.py)."""
    _replies: Replies
    """The commands waiting for a reply and which one a reply answers (client/replies.py)."""
    _listeners: Listeners
    _moving: bool
    _heard: bool  # a byte has come from the link to the client (not to a switch's probe)
    _preparing: str  # the step before a text command under way: "probe" (tags?), "resync"

    @property
    def link(self) -> Link:
        """The link to the controller (the connection's; replacing it replaces the connection's)."""
        return self._connection.link

    @link.setter
    def link(self, link: Link) -> None:
        self._connection.link = link

    @property
    def clock(self) -> Clock:
        """The link's clock: wall time, or simulated time on sim://."""
        return self.link.clock

    @property
    def binary(self) -> bool:
        """True while the client speaks the binary protocol."""
        return self._switch.binary

    @property
    def tags(self) -> bool | None:
        """True if text commands carry ``#tag*check``; None until the controller was asked."""
        return self._switch.tags

    @property
    def _wire(self) -> Wire:
        """The wire format in use (the switch's)."""
        return self._switch.wire

    @property
    def _tracers(self) -> Tracers:
        """Told the link's bytes, the commands and replies (a recorder): the connection's."""
        return self._connection.tracers

    def _write(self, data: bytes) -> None:
        self._connection.write(data)

    def _read(self, timeout: float, gather: tuple[bytes, int] | None = None) -> bytes:
        return self._connection.read(timeout, gather)
