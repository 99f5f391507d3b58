"""The recorder (and its Foxglove live server) plugged into a host runtime.

``--log`` / ``--foxglove`` on a command that runs on the runtime: the command's recording,
:meth:`omnibot.logs.recording.Recording.attach_runtime`, called by
:meth:`Runtime.start <omnibot.runtime.runtime.Runtime.start>` of a runtime the command handed it to,
adds :class:`RuntimeRecorder`, a sink: the arbitration at each change on ``/omnibot/control``
(``omnibot_msgs/msg/Control``: source, reason, lock, the twist it asked for) and, when the runtime
has an estimator, *its* estimate after each sample (``odom``, ``/tf``, ``/omnibot/estimate``: the
one the follower steers by, not a second estimator); the commands go out as VELs the recorder
already writes as ``cmd_vel``; the scans of the runtime's scanner (``Cycle.scans``) on ``/scan``. A
command that serves Foxglove live adds the Foxglove Teleop panel as a source itself
(:class:`omnibot.logs.live.PanelSource`; :mod:`omnibot.apps.recording`).

While a path follower (:class:`~omnibot.runtime.sources.FollowerSource`) is among the runtime's
sources, :class:`FollowerLog` also writes each cycle on ``/omnibot/cycle`` (``omnibot_msgs/msg/Cycle``:
the cycle's clocks, the estimate the sources were handed, the decision and its twist, the follower's
error notices) and, once per follower run, the MCAP metadata ``omnibot_follower/RUN`` (the follower's
registered name, its options and limits, the path, its start time): what ``omnibot log replay``
needs to re-run the follower (:mod:`omnibot.logs.follower_replay`).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable
from typing import TYPE_CHECKING

from omnibot.client import Telemetry
from omnibot.estimation import ESTIMATORS
from omnibot.logs import schemas
from omnibot.logs.recorder import Recorder
from omnibot.logs.rosmsg import stamp, twist
from omnibot.logs.topics import CONTROL, CYCLE, FOLLOWER
from omnibot.motion import Pose2D
from omnibot.runtime import Cycle, Decision, FollowerSource

if TYPE_CHECKING:
    from omnibot.estimation import Estimator
    from omnibot.runtime import Runtime


_RECIPES = {
    ("tracking", "fused"): "tracking+gyro",
    ("tracking", "gyro"): "tracking+raw-gyro",
    ("encoders", "fused"): "encoders+gyro",
    ("encoders", "gyro"): "encoders+raw-gyro",
    ("encoders", "encoders"): "encoders",
}
"""A pose estimator's (translation, heading) -> the registered estimator that is made the same way."""


def registered_name(estimator: Estimator) -> str:
    """The name ``make_estimator`` rebuilds ``estimator`` by (``log replay``): its own when registered,
    else its recipe's (the dashboard's teach makes a pose estimator named "teach")."""
    if estimator.name in ESTIMATORS:
        return estimator.name
    recipe = (getattr(estimator, "translation", ""), getattr(estimator, "heading_source", ""))
    return _RECIPES.get(recipe, estimator.name)


class RuntimeRecorder:
    """A runtime sink writing its arbitration into ``recorder``; adopts the runtime's estimator."""

    def __init__(self, recorder: Recorder, runtime: Runtime) -> None:
        self.recorder = recorder
        self.runtime = runtime
        self._last: tuple[str, str, str, bool] | None = None
        self._adopted: Estimator | None = None
        self._follower = FollowerLog(recorder)
        # made before the runtime listens (Runtime.start): this listener sees each sample before
        # the runtime's estimator does, so an estimator installed later (the dashboard's teach) is
        # adopted with the pose it starts from
        self._listener = self._before
        runtime.client.on_telemetry(self._listener)
        runtime.telemetry_hooks.append(self._after)
        if runtime.estimator is not None:
            self._adopt(runtime.estimator, None)
        # a write that fails stops the file, never the run: the runtime's front ends are told once
        recorder.on_failure.append(self._failed)
        if recorder.failure is not None:
            self._failed(recorder.failure)

    def _failed(self, text: str) -> None:
        self.runtime.notify("warn", text, "log")

    def _before(self, tel: Telemetry) -> None:
        estimator = self.runtime.estimator
        if estimator is not None and estimator is not self._adopted and tel.encoders is not None:
            # the recorder's own estimator may have written this sample already: the log then has
            # two estimates at its time, the recorder's and the adopted one's (replay knows)
            self._adopt(estimator, tel)

    def _adopt(self, estimator: Estimator, before: Telemetry | None) -> None:
        self._adopted = estimator
        e = estimator.estimate
        slip = getattr(estimator, "slip_model", None) is not None
        self.recorder.adopt(registered_name(estimator), Pose2D(e.x, e.y, e.theta), before=before, slip=slip)

    def _after(self, tel: Telemetry) -> None:
        """Right after the runtime's estimator took ``tel``: its estimate, as it is now."""
        estimator = self.runtime.estimator
        if estimator is not None and estimator is self._adopted and tel.encoders is not None:
            self.recorder.estimate(tel.time, estimator.estimate)

    def __call__(self, cycle: Cycle) -> None:
        """The runtime's cycle: a ``/omnibot/control`` message when who drives, why, the lock or the
        latched stop changed; each scan of the cycle on ``/scan``."""
        for scan in cycle.scans:
            self.recorder.scan(scan)
        d = cycle.decision
        key = (d.source, d.reason, d.lock, cycle.latched)
        if key != self._last:
            self._last = key
            self.control(cycle.t, d, cycle.latched)
        self._follower(cycle, self.runtime.sources.values())

    def control(self, t: float, d: Decision, latched: bool) -> None:
        """One ``/omnibot/control`` message: ``d`` at link time ``t``."""
        ns = self.recorder.ns(t)
        tw = d.twist
        msg = schemas.new(
            schemas.CONTROL,
            stamp=stamp(ns),
            source=d.source,
            reason=d.reason,
            lock=d.lock,
            estop=d.estop,
            latched=latched,
            twist=twist(tw.vx, tw.vy, tw.w) if tw is not None else twist(0.0, 0.0, 0.0),
        )
        self.recorder.write(CONTROL, schemas.CONTROL, msg, ns)

    def close(self) -> None:
        """Stop taking the runtime's estimate (the recorder stays open)."""
        self.runtime.client.remove_listener(self._listener)
        if self._failed in self.recorder.on_failure:
            self.recorder.on_failure.remove(self._failed)
        if self._after in self.runtime.telemetry_hooks:
            self.runtime.telemetry_hooks.remove(self._after)


def path_columns(path: object) -> dict[str, list[float] | None]:
    """A path's columns (x, y, theta, t, v) as lists of floats (None for a column it lacks)."""
    out: dict[str, list[float] | None] = {}
    for name in ("x", "y", "theta", "t", "v"):
        col = getattr(path, name, None)
        out[name] = None if col is None else [float(v) for v in col]
    return out


class FollowerLog:
    """Part of :class:`RuntimeRecorder`: each cycle while a follower source runs, and each follower
    run's metadata (see the module docstring)."""

    def __init__(self, recorder: Recorder) -> None:
        self.recorder = recorder
        self.runs = 0
        """Follower runs seen so far (the run number of the current one)."""
        self._source: FollowerSource | None = None
        self._described = False

    def __call__(self, cycle: Cycle, sources: Iterable[object]) -> None:
        """Record ``cycle`` if a follower is among ``sources`` (the first one found)."""
        source = next((s for s in sources if isinstance(s, FollowerSource)), None)
        if source is None:
            self._source = None
            return
        if source is not self._source:
            self._source, self._described = source, False
            self.runs += 1
        if not self._described and source.started:
            self._described = True
            self.describe(source)
        self.cycle(cycle, source.name)

    def describe(self, source: FollowerSource) -> None:
        """The metadata ``omnibot_follower/RUN`` of a follower run that has started."""
        follower = source.follower
        self.recorder.add_metadata(
            f"{FOLLOWER}/{self.runs}",
            {
                "source": source.name,
                "follower": follower.name,
                "options": json.dumps(follower.options),
                "limits": json.dumps(dataclasses.asdict(follower.limits)),
                "path": json.dumps(path_columns(source.path)),
                "t0": repr(float(follower.t0)),
                "on_override": source.on_override,
            },
        )

    def cycle(self, cycle: Cycle, name: str) -> None:
        """One ``/omnibot/cycle`` message (the follower source is called ``name``)."""
        ns = self.recorder.ns(cycle.t)
        e = cycle.estimate
        d = cycle.decision
        tw = d.twist
        msg = schemas.new(
            schemas.CYCLE,
            stamp=stamp(ns),
            run=self.runs,
            index=cycle.index,
            now=float(cycle.now),
            t=float(cycle.t),
            has_estimate=e is not None,
            estimate_t=float(e.t) if e else 0.0,
            x=float(e.x) if e else 0.0,
            y=float(e.y) if e else 0.0,
            theta=float(e.theta) if e else 0.0,
            vx=float(e.vx) if e else 0.0,
            vy=float(e.vy) if e else 0.0,
            w=float(e.w) if e else 0.0,
            slipping=bool(e.slipping) if e else False,
            standstill=bool(e.standstill) if e else False,
            source=d.source,
            lock=d.lock,
            estop=d.estop,
            latched=cycle.latched,
            has_twist=tw is not None,
            twist=twist(tw.vx, tw.vy, tw.w) if tw is not None else twist(0.0, 0.0, 0.0),
            errors=[n.text for n in cycle.notices if n.level == "error" and n.source == name],
        )
        self.recorder.write(CYCLE, schemas.CYCLE, msg, ns)
