"""The recorder (and its Foxglove live server) plugged into a host runtime.

``--log`` / ``--foxglove`` on a command that runs on the runtime: :func:`omnibot.logs.active.attach_runtime`
(called by :meth:`Runtime.start <omnibot.runtime.runtime.Runtime.start>`) adds

* :class:`RuntimeRecorder`, a sink: the arbitration at each change on ``/omnibot/control``
  (``omnibot_msgs/msg/Control``: source, reason, lock, the twist it asked for) and, when the runtime
  has an estimator, *its* estimate after each sample (``odom``, ``/tf``, ``/omnibot/estimate``: the
  one the follower steers by, not a second estimator); the commands go out as VELs the recorder
  already writes as ``cmd_vel``;
* the Foxglove Teleop panel as a source (:class:`omnibot.logs.live.PanelSource`) when the command
  serves Foxglove live.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from omnibot.client.events import Telemetry
from omnibot.estimation.estimator import ESTIMATORS
from omnibot.logs import schemas
from omnibot.logs.recorder import Recorder, stamp, twist
from omnibot.logs.topics import CONTROL
from omnibot.motion import Pose2D
from omnibot.runtime.cycle import Cycle, Decision

if TYPE_CHECKING:
    from omnibot.estimation.estimator import Estimator
    from omnibot.runtime.runtime import Runtime


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
        # made before the runtime listens (Runtime.start): this listener sees each sample before
        # the runtime's estimator does, so an estimator installed later (the dashboard's teach) is
        # adopted with the pose it starts from
        self._listener = self._before
        runtime.client.on_telemetry(self._listener)
        runtime.telemetry_hooks.append(self._after)
        if runtime.estimator is not None:
            self._adopt(runtime.estimator, None)

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
        latched stop changed."""
        d = cycle.decision
        key = (d.source, d.reason, d.lock, cycle.latched)
        if key != self._last:
            self._last = key
            self.control(cycle.t, d, cycle.latched)

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
        if self._after in self.runtime.telemetry_hooks:
            self.runtime.telemetry_hooks.remove(self._after)
