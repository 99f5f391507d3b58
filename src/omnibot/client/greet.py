"""Wait for a controller to answer HELLO: the first exchange of every session on a new link.

A controller may not answer the first HELLO: an Arduino resets when its port opens and its bootloader
swallows what arrives for a second or two; a simulator on a fresh install may still be compiling.
:func:`wait_for_controller` sends HELLO again every ``retry`` seconds (text replies match the oldest
HELLO waiting, so a late reply to an earlier one counts) and restarts at once when the controller
greets with its own power-up HELLO, until ``window`` seconds have passed. ``notice`` hears, once, what
is being waited for when the first HELLO goes unanswered (a CLI shows it on a terminal).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Sequence

from omnibot.client.client import RobotClient
from omnibot.client.errors import ControllerReset
from omnibot.client.pending import Pending
from omnibot.client.views import Hello
from omnibot.errors import LinkTimeout
from omnibot.protocol.messages import Hello as HelloCommand
from omnibot.protocol.messages import HelloReply

HELLO_WINDOW = 20.0
"""s to keep asking: an Arduino's reset and a first compile of the simulator both fit."""
HELLO_RETRY = 1.0
"""s between HELLOs."""


def wait_for_controller(
    client: RobotClient,
    versions: Sequence[int] = (),
    *,
    window: float = HELLO_WINDOW,
    retry: float = HELLO_RETRY,
    notice: Callable[[str], object] | None = None,
) -> Hello:
    """HELLO until the controller answers; its reply as a :class:`Hello`. LinkTimeout (naming the link
    and the wait) when nothing answers within ``window`` s of ``client.clock``; a ControllerError
    if the controller refuses HELLO."""
    clock = client.clock
    deadline = clock.now() + window
    sent: list[Pending] = []
    announced = False
    while True:
        now = clock.now()
        if now >= deadline:
            raise LinkTimeout(
                f"no reply to HELLO on {client.link.url} within {window:g} s: is a controller there?"
            )
        # a text client's first question (a tagged HELLO: does it echo tags?) may go unanswered too
        with contextlib.suppress(LinkTimeout):
            sent.append(client.submit(HelloCommand(tuple(versions)), timeout=min(retry, deadline - now)))
        until = min(now + retry, deadline)
        while not any(p.done for p in sent) and (left := until - clock.now()) > 0:
            client.pump(left)
        replied = next((p for p in sent if p.reply is not None), None)
        if replied is not None:
            reply = replied.result()  # an ERROR reply raises its ControllerError
            assert isinstance(reply, HelloReply)
            for p in sent:  # the HELLOs it did not answer: nobody waits for them any more
                p.timed_out = p.timed_out or not p.done
            return Hello.from_reply(reply)
        for p in sent:
            # a reset (the controller started and listens now) or a HELLO given up for a later one
            # (binary: SYNC) just means asking again; anything else (the link failed) ends the wait
            if p.error is not None and not isinstance(p.error, ControllerReset | LinkTimeout):
                raise p.error
        if notice is not None and not announced and not any(p.done for p in sent):
            announced = True
            notice(f"waiting for the controller on {client.link.url} (HELLO, up to {window:g} s)...")
        sent = [p for p in sent if not p.done]
