"""The signals that end an omnibot process: SIGHUP only when nohup did not ignore it; a held block
is never cut in two by one."""

from __future__ import annotations

import signal
import threading

import pytest

from omnibot.signals import Terminated, ending_signals, held, terminate_cleanly


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


def test_a_signal_inside_a_held_block_is_raised_when_the_block_ends() -> None:
    done = []
    with pytest.raises(Terminated) as raised, terminate_cleanly():
        with held():
            signal.raise_signal(signal.SIGTERM)
            done.append("after the signal")  # the handler ran: its exception waits
            with held():  # nested: only the outermost end raises
                done.append("nested")
            done.append("still held")
        done.append("never")
    assert raised.value.signum == signal.SIGTERM
    assert done == ["after the signal", "nested", "still held"]


def test_ctrl_c_is_held_too_and_a_second_signal_is_raised_at_once() -> None:
    done = []
    with pytest.raises(KeyboardInterrupt) as raised, terminate_cleanly(), held():
        signal.raise_signal(signal.SIGINT)
        done.append("held")
        signal.raise_signal(signal.SIGTERM)  # the user insists: a stuck block still ends
        done.append("never")
    assert type(raised.value) is Terminated and done == ["held"]
    with pytest.raises(KeyboardInterrupt), terminate_cleanly():  # nothing left pending from before
        with held():
            pass
        signal.raise_signal(signal.SIGINT)


def test_held_is_a_no_op_in_another_thread() -> None:
    seen: list[int] = []

    def other() -> None:
        with held():
            seen.append(1)

    worker = threading.Thread(target=other)
    worker.start()
    worker.join()
    with pytest.raises(Terminated), terminate_cleanly():
        signal.raise_signal(signal.SIGTERM)  # not held by the other thread's block
    assert seen == [1]
