"""A command sent and maybe not answered yet (:class:`Pending`): which replies can answer it, and its
:meth:`~Pending.result`, which pumps the :class:`~omnibot.client.client.RobotClient` that sent it until
the reply, a failure or its deadline.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from omnibot.errors import LinkTimeout
from omnibot.protocol.messages import Command, ErrorReply, HelloReply, Ok, Reply, StatusReply
from omnibot.protocol.messages import Hello as HelloCommand
from omnibot.protocol.messages import Status as StatusCommand

if TYPE_CHECKING:
    from omnibot.client.waiting import Waiting


class Pending:
    """A command sent and (maybe) not answered yet; :meth:`result` waits for its reply."""

    def __init__(
        self,
        client: Waiting,
        command: Command | None,
        line: str,
        seq: int,
        deadline: float,
        malformed: bool = False,
    ) -> None:
        self.command = command
        """The command; None for raw bytes whose form the client did not check."""
        self.malformed = malformed
        """Raw text that does not parse as a command: the controller answers it with ERROR."""
        self.line = line
        """The command as text, for messages."""
        self.seq = seq
        """Binary sequence number; in text the tag (0: untagged)."""
        self.probe = False
        """Text: the tagged HELLO that asks whether the controller echoes tags."""
        self.deadline = deadline
        """Link-clock time after which :meth:`result` raises LinkTimeout."""
        self.reply: Reply | None = None
        self.error: BaseException | None = None
        self.timed_out = False
        self.abandoned = False  # binary: pending when a SYNC frame was sent
        self.size = 0
        """Text: the bytes it took on the line, counted in the text window until it is answered."""
        self._client = client

    @property
    def done(self) -> bool:
        """True once a reply (or a failure) is in."""
        return self.reply is not None or self.error is not None

    def accepts(self, reply: Reply) -> bool:
        """Whether ``reply`` can answer this command (text matching). Raw text that did not parse
        can only get an ERROR; other raw text anything but a HELLO reply (send HELLO typed)."""
        if isinstance(reply, ErrorReply):
            return True
        if self.probe:
            return not isinstance(reply, HelloReply)  # untagged: the answer of a controller without tags
        if self.command is None:
            return not self.malformed and not isinstance(reply, HelloReply)
        if isinstance(self.command, StatusCommand):
            return isinstance(reply, StatusReply)
        if isinstance(self.command, HelloCommand):
            return isinstance(reply, HelloReply)
        return isinstance(reply, Ok)

    def result(self, timeout: float | None = None) -> Reply:
        """Wait for the reply (pumping the client) and return it; raise the ControllerError of an
        ERROR reply, LinkTimeout after ``timeout`` s (default: until the deadline), LinkError."""
        if not self.done:
            client = self._client
            deadline = self.deadline if timeout is None else client.clock.now() + timeout
            try:
                try:
                    client._wait(lambda: self.done, deadline, f"no reply to {self.line}")
                except LinkTimeout:
                    if timeout is not None or not client._in_flight(self):
                        raise
                    client._wait_for_verdict(self)  # binary: the retries of its frame decide
            except LinkTimeout as exc:
                self.timed_out = True
                client._replies.timed_out(self)
                if client.tags and self.seq:
                    exc.add_note("it may or may not have run (a tagged text command)")
                raise
        if self.error is not None:
            raise self.error
        assert self.reply is not None
        return self.reply

    def _fail(self, error: BaseException) -> None:
        if not self.done:
            self.error = error

    def __repr__(self) -> str:
        state = "error" if self.error else "replied" if self.reply else "waiting"
        return f"<Pending {self.line!r} seq={self.seq} {state}>"
