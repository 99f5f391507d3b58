"""A source that wakes the runtime between cycles: its command goes out at once, still arbitrated, one
send site; in lockstep an event raised by what the simulation delivers is taken at that simulated
instant, the same on every run; the cycles keep their schedule."""

from __future__ import annotations

import itertools
import math
import threading

import pytest

from omnibot.client import Pending, RobotClient, Telemetry
from omnibot.motion import Twist
from omnibot.protocol import codes
from omnibot.protocol.messages import Command, Vel
from omnibot.runtime.arbiter import EStop
from omnibot.runtime.cycle import Cycle
from omnibot.runtime.pacing import LinkPacer
from omnibot.runtime.runtime import Runtime
from omnibot.runtime.sources import Proposal, ScriptSource
from omnibot.runtime.wakeup import GAP, Wake, Wakeup
from omnibot.teleop import Pacer

PERIOD = 0.05
"""s: long cycles, so that a command taken by a cycle and one taken by a reaction differ."""


class Pushed:
    """A source told of twists between cycles (by :meth:`push`, which wakes the runtime)."""

    def __init__(self, name: str = "pushed", priority: int = 90) -> None:
        self.name = name
        self.priority = priority
        self.timeout = 0.5
        self.wake: Wake | None = None
        self.twist: Twist | None = None
        self.asked: list[float] = []

    def wake_with(self, wake: Wake) -> None:
        self.wake = wake

    def push(self, twist: Twist) -> None:
        self.twist = twist
        assert self.wake is not None
        self.wake()

    def propose(self, cycle: Cycle) -> Proposal | None:
        self.asked.append(cycle.now)
        return None if self.twist is None else Proposal(self.twist)


def recorded(client: RobotClient) -> list[tuple[float, float]]:
    """(link time, vx in cm/s) of every VEL the client submits from now on."""
    sent: list[tuple[float, float]] = []
    submit = client.submit

    def record(command: Command, timeout: float | None = None) -> Pending:
        if isinstance(command, Vel):
            sent.append((round(client.clock.now(), 6), command.vx))
        return submit(command, timeout)

    client.submit = record  # type: ignore[method-assign]
    return sent


def lockstep_run(
    samples: dict[int, float],
) -> tuple[list[tuple[float, float]], list[float], list[float], Runtime]:
    """1 s in lockstep: telemetry every 10 ms; at the k-th sample the source is pushed
    ``samples[k]`` m/s (from the telemetry listener: the simulation's own event). The VELs sent,
    the sample times of the pushes, the cycles' times, the runtime."""
    with RobotClient.open("sim://omni4?seed=3&world=empty", timeout=0.5) as client:
        source = Pushed()
        runtime = Runtime(client, period=PERIOD, sources=[source])
        pushed_at: list[float] = []
        count = 0

        def on_sample(event: Telemetry) -> None:
            nonlocal count
            count += 1
            if count in samples:
                pushed_at.append(round(client.clock.now(), 6))
                source.push(Twist(samples[count], 0.0, 0.0))

        runtime.telemetry_hooks.append(on_sample)
        runtime.start()
        client.telemetry(0.01, codes.TEL_MASK)
        runtime.pacer = LinkPacer(client, PERIOD)
        sent = recorded(client)
        cycles: list[float] = []
        runtime.add_sink(lambda cycle: cycles.append(cycle.t))
        runtime.run(duration=1.0)
        runtime.close()
        return sent, pushed_at, cycles, runtime


def test_in_lockstep_each_event_is_sent_at_its_simulated_instant_and_every_run_is_the_same() -> None:
    samples = {7: 0.10, 23: 0.20, 24: 0.25, 51: 0.30}
    sent, pushed_at, times, runtime = lockstep_run(samples)
    assert len(pushed_at) == 4
    # a reaction per push (23 and 24 are 10 ms apart: more than GAP), each VEL at its instant
    assert runtime.reactions == 4 and runtime.wakeup.wakes == 4
    reacted = [(t, vx) for t, vx in sent if t in pushed_at]
    assert reacted == [(t, round(v * 100)) for t, v in zip(pushed_at, samples.values(), strict=True)]
    # the cycles kept their schedule (a period apart on the link clock) and sent too
    assert all(b - a == pytest.approx(PERIOD, abs=2e-3) for a, b in itertools.pairwise(times))
    assert not set(pushed_at) & {round(t, 6) for t in times}  # the events fell between cycles
    again, pushed_again, _, _ = lockstep_run(samples)
    assert (again, pushed_again) == (sent, pushed_at)


def test_without_a_source_that_wakes_a_lockstep_run_is_the_one_it_was() -> None:
    def run(wakeup: bool) -> list[tuple[float, float]]:
        with RobotClient.open("sim://omni4?seed=4&world=empty", timeout=0.5) as client:
            script = ScriptSource(lambda t: Twist(0.2, 0.0, 0.3) if t < 0.5 else ScriptSource.END)
            runtime = Runtime(client, period=0.01, sources=[script])
            if wakeup:
                runtime.add_source(Pushed())  # a source that may wake, and never does
            runtime.start()
            client.telemetry(0.01, codes.TEL_MASK)
            runtime.pacer = LinkPacer(client, 0.01)
            sent = recorded(client)
            runtime.run(until=lambda: script.finished)
            runtime.close()
            assert runtime.reactions == 0
            return sent

    assert run(True) == run(False)


def test_a_person_above_the_woken_source_and_an_emergency_stop_still_win() -> None:
    with RobotClient.open("sim://omni4?seed=1&world=empty", timeout=0.5) as client:
        pad = ScriptSource(lambda t: Twist(0.1, 0.0, 0.0), name="pad", priority=200)
        pushed = Pushed()
        estop = EStop()
        runtime = Runtime(client, period=PERIOD, sources=[pad, pushed], locks=[estop.lock])
        runtime.pacer = LinkPacer(client, PERIOD)
        sent = recorded(client)
        runtime.step()  # the pad drives
        pushed.push(Twist(0.3, 0.0, 0.0))
        decision = runtime.react()
        assert decision is not None and decision.source == "pad" and len(sent) == 1  # nothing more sent
        runtime.remove_source("pad")
        runtime.wakeup.hold_until = -math.inf
        estop.press("page")
        pushed.push(Twist(0.3, 0.0, 0.0))
        decision = runtime.react()
        assert decision is not None and decision.estop and decision.twist is None and len(sent) == 1
        estop.resume()
        pushed.push(Twist(0.3, 0.0, 0.0))
        runtime.wakeup.hold_until = -math.inf
        decision = runtime.react()
        assert decision is not None and decision.source == "pushed" and sent[-1][1] == 30
        runtime.step()  # the change of who drives goes to the sinks with the next cycle
        assert runtime.sent.vel == 3


def test_a_wake_from_another_thread_ends_the_wall_clock_wait_and_the_tick_stays_due() -> None:
    with RobotClient.open("sim://omni4?seed=1&world=empty", timeout=0.5) as client:
        source = Pushed()
        runtime = Runtime(client, period=60.0, sources=[source])
        runtime.pacer = Pacer(client, 60.0)  # a minute's cycle: only a wake ends the wait in time
        runtime.step()
        pushed = threading.Thread(target=source.push, args=(Twist(0.2, 0.0, 0.0),))
        sent = recorded(client)
        pushed.start()
        assert runtime.pacer.wait(runtime.wakeup) is False  # woken, not due
        pushed.join()
        runtime.react()
        assert [vx for _, vx in sent] == [20] and len(source.asked) == 2


def test_the_gap_holds_a_second_wake_and_the_flag_says_who_woke() -> None:
    wakeup = Wakeup()
    wake = wakeup.waker("a")
    clock = [0.0]
    wakeup.hold_until = GAP
    wake()
    wakeup.wake("b")
    assert wakeup.raised and not wakeup.ready(clock[0]) and wakeup.ready(GAP)
    assert wakeup.take() == {"a", "b"} and not wakeup.raised and wakeup.take() == set()
