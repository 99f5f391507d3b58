"""The signals that end an omnibot process cleanly, one rule for the host commands and the emulator;
:func:`held` keeps their exception out of a block that must not be cut in two (a log's record)."""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType, TracebackType


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


class _Held:
    """The main thread's held blocks (their depth) and the exception a signal raised meanwhile.

    Python runs a signal's handler in the main thread between any two bytecodes, so an exception it
    raises can cut a multi-step update in two (an MCAP record half written into its chunk: the whole
    chunk unreadable). Inside :func:`held` the handlers of :func:`terminate_cleanly` keep the
    exception and it is raised when the outermost held block ends; a second signal meanwhile is
    raised at once (a block stuck in a write still ends on a second Ctrl-C)."""

    def __init__(self) -> None:
        self.depth = 0
        self.pending: BaseException | None = None

    def __enter__(self) -> None:
        if threading.get_ident() == threading.main_thread().ident:
            self.depth += 1

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        if threading.get_ident() != threading.main_thread().ident:
            return
        self.depth -= 1
        if self.depth == 0 and self.pending is not None:
            pending, self.pending = self.pending, None
            raise pending

    def deliver(self, exc: BaseException) -> None:
        """Raise ``exc`` now (a handler, in the main thread), or at the held block's end."""
        if self.depth > 0 and self.pending is None:
            self.pending = exc
            return
        self.pending = None  # the second one ends it: the first is not raised again at the block's end
        raise exc


_HELD = _Held()


def held() -> contextlib.AbstractContextManager[None]:
    """A block no ending signal cuts in two: in the main thread, the exception of SIGINT, SIGTERM or
    SIGHUP (under :func:`terminate_cleanly`) arriving inside it is raised when it ends. Keep it
    short (one record, one chunk's write); elsewhere a no-op."""
    return _HELD


@contextlib.contextmanager
def terminate_cleanly() -> Iterator[None]:
    """While inside, SIGTERM and SIGHUP raise :class:`Terminated` in the main thread (no-op
    elsewhere), and SIGINT its ``KeyboardInterrupt`` as ever (unless another handler was set), both
    held back by :func:`held`. A SIGHUP ignored when the command started (``nohup``) stays ignored."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def _terminate(signum: int, frame: FrameType | None) -> None:
        _HELD.deliver(Terminated(signum))

    def _interrupt(signum: int, frame: FrameType | None) -> None:
        _HELD.deliver(KeyboardInterrupt())

    previous = {signum: signal.signal(signum, _terminate) for signum in ending_signals()}
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        previous[signal.SIGINT] = signal.signal(signal.SIGINT, _interrupt)
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
