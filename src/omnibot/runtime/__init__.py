"""The host runtime: the one loop that owns the client in a process; every front end plugs into it.

Teleop (pad, keyboard), the dashboard (its stick, keys, browser gamepad, emergency stop, teach and
repeat), ``omnibot follow`` and ``omnibot run`` are sources, locks and sinks of one
:class:`Runtime`; none of them has a loop or a client of its own. One cycle, every ``period`` s
(100 Hz by default; on ``sim://`` on the lockstep link's simulated time, so runs are deterministic)::

    TEL, WARN, ERROR, RESET --listeners--> estimator (+ telemetry hooks), events, latch
                                                |
    every period (pacer: link clock, or the wall clock with the simulator kept in step):
      1. collect       replies to last cycle's VELs: ERROR -> Notice to every sink and the source;
                       ERROR 40 / WARN 13 / TEL state 3: the latched emergency stop -> Notice
      2. estimate      the estimator's state predicted to now (telemetry age, at most 0.1 s)
      3. sources       source.propose(cycle) -> twist | None, each (pad, page, follower, script...)
      4. arbitrate     twist_mux: highest priority active within its timeout; locks (emergency
                       stop 255, deadman) mask sources at or below their priority -> Decision + why
      5. send          one VEL (clamped; the source's watchdog timeout); a fresh press of a person's
                       deadman sends STOP first when the controller latched its emergency stop
      6. sinks         sink(cycle): dashboard state, traces for plots and reports, teach, logs
                       (the MCAP recorder; later ROS 2 publishers)
      7. wait          pacer.wait(): the client pumps replies and events meanwhile; a source that
                       wakes the loop (a DDS listener's cmd_vel) is asked at once: arbitrate, send
                       (Runtime.react; omnibot.runtime.wakeup), then the wait goes on

The pieces: :mod:`~omnibot.runtime.cycle` (what a cycle carries), :mod:`~omnibot.runtime.arbiter`
(priorities, timeouts, locks), :mod:`~omnibot.runtime.sources` (the source protocol, follower, script),
:mod:`~omnibot.runtime.sinks` (the sink protocol, teach, traces, notices), :mod:`~omnibot.runtime.wakeup`
(sources that push a proposal between cycles), :mod:`~omnibot.runtime.pacing` (when a cycle is due),
:mod:`~omnibot.runtime.runtime` (the Runtime: composition and the cycle) on
:mod:`~omnibot.runtime.core` (its counts, hooks, notices, the latched stop),
:mod:`~omnibot.runtime.listening` (telemetry and events between cycles) and
:mod:`~omnibot.runtime.sending` (the VELs sent, their replies collected). docs/architecture.md has the whole picture and how a new front end plugs in.

A library: it imports the client, the protocol's codes, estimation, control, the robot's description
and the shared types, nothing of a front end (a person's sources are :mod:`omnibot.teleop`'s, the
follower's factory and the verdict :mod:`omnibot.navigation`'s), of a link (the client owns it; the
stall watch is handed the simulator's truth: ``StallWatch(..., truth=...)``) or of a log (a recording
is handed in: ``Runtime(recording=...)``). ``tests/test_imports.py`` holds it to that.
"""

from omnibot.runtime.arbiter import PRIORITY_MAX, Arbiter, EStop, Lock, deadman_lock
from omnibot.runtime.core import Counters
from omnibot.runtime.cycle import NOBODY, Cycle, Decision, Level, Notice
from omnibot.runtime.pacing import LinkPacer
from omnibot.runtime.runtime import Recording, Runtime, RuntimeRecording, Sink
from omnibot.runtime.sending import clamp_to
from omnibot.runtime.sinks import EstimatorWhenMissing, NoticePrinter, SpeedReport, TeachSink, Trace
from omnibot.runtime.sources import APPROACH_GAP, FollowerSource, Proposal, ScriptSource, Source, must_end
from omnibot.runtime.stall import StallWatch, start_sonars
from omnibot.runtime.standstill import Standstill
from omnibot.runtime.wakeup import Wake, Wakeup

__all__ = [
    "APPROACH_GAP",
    "NOBODY",
    "PRIORITY_MAX",
    "Arbiter",
    "Counters",
    "Cycle",
    "Decision",
    "EStop",
    "EstimatorWhenMissing",
    "FollowerSource",
    "Level",
    "LinkPacer",
    "Lock",
    "Notice",
    "NoticePrinter",
    "Proposal",
    "Recording",
    "Runtime",
    "RuntimeRecording",
    "ScriptSource",
    "Sink",
    "Source",
    "SpeedReport",
    "StallWatch",
    "Standstill",
    "TeachSink",
    "Trace",
    "Wake",
    "Wakeup",
    "arbiter",
    "clamp_to",
    "cycle",
    "deadman_lock",
    "must_end",
    "runtime",
    "sinks",
    "sources",
    "stall",
    "standstill",
    "start_sonars",
    "wakeup",
]
