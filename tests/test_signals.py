"""The signals that end an omnibot process: SIGHUP only when nohup did not ignore it."""

from __future__ import annotations

import signal

from omnibot.signals import ending_signals


def test_sigterm_and_sighup_end_a_process() -> None:
    before = signal.signal(signal.SIGHUP, signal.SIG_DFL)
    try:
        assert ending_signals() == [signal.SIGTERM, signal.SIGHUP]
    finally:
        signal.signal(signal.SIGHUP, before)


def test_a_sighup_ignored_at_start_is_not_an_ending_signal() -> None:
    before = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        assert ending_signals() == [signal.SIGTERM]
    finally:
        signal.signal(signal.SIGHUP, before)
