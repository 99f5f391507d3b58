"""The signals that end an omnibot process cleanly, one rule for the host commands and the emulator."""

from __future__ import annotations

import signal


def ending_signals() -> list[signal.Signals]:
    """SIGTERM, and SIGHUP (the terminal or SSH session it ran in went away) unless it was ignored
    when the process started (``nohup``): then it stays ignored."""
    ending = [signal.SIGTERM]
    if signal.getsignal(signal.SIGHUP) is not signal.SIG_IGN:
        ending.append(signal.SIGHUP)
    return ending
