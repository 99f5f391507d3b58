"""What arrives from the controller: each reply to its command, events to the listeners.

:class:`Receiving` is the client's lowest layer (:mod:`omnibot.client.core`): the bytes read go
through the wire format in use; a reply goes to :class:`~omnibot.client.replies.Replies`, which
finds the command it answers and hands the pair back (:meth:`Receiving._complete`, which records
what the reply tells: the MODE bits, moving or not, the HELLO); an event goes to the listeners; a
HELLO nobody asked for is the controller's reset.
"""

from __future__ import annotations

from omnibot.client.core import ClientCore
from omnibot.client.errors import ControllerReset, controller_error
from omnibot.client.events import Event, IdleEvent, ResetEvent, event_from_message
from omnibot.client.pending import Pending
from omnibot.client.views import Hello
from omnibot.client.wire import BinaryWire
from omnibot.protocol import arq, codes
from omnibot.protocol.binary import Packet
from omnibot.protocol.messages import (
    Delta,
    ErrorReply,
    HelloReply,
    Malformed,
    Mode,
    Move,
    Ok,
    Power,
    Reply,
    Rotate,
    StatusReply,
    Stop,
    Vel,
)
from omnibot.protocol.messages import Telemetry as TelemetryMessage

MOTION = (Move, Rotate, Delta, Power, Vel)
"""Commands whose OK sets the robot moving (until IDLE, STOP or a STATUS saying idle)."""


class Receiving(ClientCore):
    """Decoding what the link brings and dispatching it: replies, events, a reset."""

    def _process(self, data: bytes) -> int:
        self._heard = True
        handled = 0
        while data:
            wire = self._wire
            items = wire.feed(data)
            data = b""
            for item in items:
                handled += 1
                self._handle(item)
                if self._wire is not wire:  # switched protocols (MODE) or the controller reset
                    data = wire.rest()
                    break
        return handled

    def _handle(self, item: Packet | Malformed) -> None:
        now = self.clock.now()
        if isinstance(item, Malformed):
            self._listeners.dispatch(event_from_message(item, now))
            return
        message = item.message
        if isinstance(message, HelloReply) and item.event:
            self._reset(event_from_message(message, now))
        elif isinstance(message, Ok | StatusReply | HelloReply) or (
            isinstance(message, ErrorReply) and not item.event
        ):
            if isinstance(self._wire, BinaryWire):
                self._replies.by_seq(item.seq, message)
            elif item.seq:
                self._replies.by_tag(item.seq, message, now)
            else:
                self._replies.in_order(message, now)
        else:
            wire = self._wire
            if isinstance(wire, BinaryWire) and not isinstance(message, TelemetryMessage):
                kind = wire.receiver.classify(item.seq, item.sync)  # seq 0: dropped
                if kind != arq.OUT_OF_ORDER:
                    self._write(wire.ack(item.seq))
                if kind != arq.NEW:
                    return
            self._event(event_from_message(message, now))

    def _complete(self, pending: Pending, reply: Reply) -> None:
        pending.reply = reply
        if self._tracers:
            self._tracers.message("reply", reply)
        if isinstance(reply, ErrorReply):
            pending.error = controller_error(reply.code, reply.description, pending.line)
            return
        command = pending.command
        if isinstance(reply, StatusReply):
            self._switch.mode_reported(reply.mode)
            self._moving = reply.state == codes.STATE_MOVING
        elif isinstance(reply, HelloReply):
            self.last_hello = Hello.from_reply(reply)
            if isinstance(self._wire, BinaryWire):
                self._wire.hello(reply)
        elif isinstance(command, MOTION):
            self._moving = True
        elif isinstance(command, Stop):
            self._moving = False
        elif isinstance(command, Mode):
            self._switch.mode_set(command.mask)

    def _event(self, event: Event) -> None:
        if isinstance(event, IdleEvent):
            self._moving = False
        elif isinstance(event, ResetEvent):
            self._reset(event)
            return
        self._listeners.dispatch(event)

    def _reset(self, event: Event) -> None:
        assert isinstance(event, ResetEvent)
        self.last_hello = event.hello
        self._replies.fail_all(
            lambda p: ControllerReset(f"the controller restarted before answering {p.line}")
        )
        self._moving = False
        self._replies.controller_reset()
        # perhaps another firmware now: ask for tags again (not while asking)
        self._switch.controller_reset(ask_tags=self._preparing != "probe")
        self._listeners.dispatch(event)
