"""The signals that end an omnibot process cleanly, one rule for the host commands and the emulator."""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType


def ending_signals() -> list[signal.Signals]:
    """SIGTERM, and SIGHUP (the terminal or SSH session it ran in went away) unless it was ignored
    when the process started (``nohup``): then it stays ignored."""
    ending = [signal.SIGTERM]
    if signal.getsignal(signal.SIGHUP) is not signal.SIG_IGN:
        ending.append(signal.SIGHUP)
    return ending


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP (the terminal or SSH session it ran in went away), turned into an exception
    so that every ``finally`` (and :func:`omnibot.client.session.guarded`) runs; :attr:`signum` says which."""

    def __init__(self, signum: int = signal.SIGTERM) -> None:
        self.signum = signal.Signals(signum)
        super().__init__(self.signum.name)


@contextlib.contextmanager
def terminate_cleanly() -> Iterator[None]:
    """While inside, SIGTERM and SIGHUP raise :class:`Terminated` in the main thread (no-op
    elsewhere). A SIGHUP ignored when the command started (``nohup``) stays ignored."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def _raise(signum: int, frame: FrameType | None) -> None:
        raise Terminated(signum)

    previous = {signum: signal.signal(signum, _raise) for signum in ending_signals()}
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
