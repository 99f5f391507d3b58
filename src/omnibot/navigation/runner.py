"""The navigator: ``omnibot follow`` and ``record`` on the runtime (telemetry -> estimator ->
follower -> VEL, on the link's clock).

::

    TEL every 10 ms (binary) --runtime listener--> estimator (+ observers) --estimate--+
                                                                                        v
    runtime cycle every 1/rate s on link.clock: predict the estimate to now -> FollowerSource
        (follower.update(State)) -> arbiter -> VEL (body frame, watchdog 150 ms; not awaited)
        -> sinks: the run's trace (:class:`FollowTrace`: estimate, command, truth), the progress bar,
           the stall watch (:mod:`omnibot.runtime.stall`)

Everything waits through :meth:`RobotClient.sleep`, so the same loop runs on a real port (wall
clock) and in lockstep on ``sim://`` (simulated time, faster than real time and deterministic for
a seed). Replies to VEL are collected without blocking at the next cycle; an ERROR reply, a
latched emergency stop or a stall (wheels that turn while the body does not) ends a follow early
(:attr:`FollowRun.failure`: its report says NOT COMPLETED and why) and a scripted manoeuvre with
:class:`NavigationError`. Scripted manoeuvres (``record
--teach drive``, the gyro spin, the slip runs) drive on the same runtime (:meth:`Navigator.drive`, a
:class:`~omnibot.runtime.sources.ScriptSource`): nothing but the runtime sends a VEL. With a simulated robot the ground
truth is sampled at every tick (followers never see it), mapped into the path's frame (the
estimator starts at the path's first pose, the robot is taken to stand there). The runtime
(:mod:`omnibot.runtime`) is the navigator's: other sources (a pad, the dashboard) may join it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from omnibot.client import NotSupported, RobotClient
from omnibot.control import STOP, Follower, Path, State
from omnibot.errors import ConfigError, OmnibotError
from omnibot.estimation import (
    Estimator,
    PoseEstimator,
    SlipParameters,
    make_estimator,
)
from omnibot.motion import Pose2D, Twist
from omnibot.navigation.gyroprobe import GyroProbe
from omnibot.navigation.trace import FollowRun, FollowTrace, FrameMap
from omnibot.progress import Progress
from omnibot.protocol import codes
from omnibot.robot import RobotDescription
from omnibot.runtime import (
    Cycle,
    FollowerSource,
    LinkPacer,
    Notice,
    Runtime,
    RuntimeRecording,
    ScriptSource,
    StallWatch,
)
from omnibot.transport import find_simulator

WATCHDOG = 0.15
"""VEL watchdog, s: the motors stop this long after the last command if the host goes quiet."""
SETTLE = 0.5
"""Seconds to wait after the final STOP before reading the final pose."""
STANDSTILL = 3.0
"""Seconds of standstill before a run (the gyro bias is learned while the wheels do not turn): at
an MPU6050's noise density 3 s pin the bias to 5e-5 rad/s (0.03 degree in 10 s of driving); with
1 s the omni3 figure eight on carpet ended 0.17 degree off."""
SPIN_RATES = (1.0, 2.5)
"""rad/s of the gyro calibration's spins: two rates tell the floor's creep (a rate) from the gyro's
scale error (a fraction of the angle); mecanum4 on carpet creeps 0.02 rad/s beyond its encoders."""
GYRO_USE = 0.9
"""The share of the gyro's range a planned turn rate keeps within: a saturated gyro loses heading."""
SPIN_GYRO_USE = 0.95
"""The share of the gyro's range the calibration's spins keep within (a steady spin in place, ramped:
it overshoots far less than a path's turns)."""


class NavigationError(OmnibotError):
    """The robot could not follow: the controller refused a command, an emergency stop latched..."""


def ramp_fraction(t: float, total: float, ramp: float) -> float:
    """The fraction of full speed at time ``t`` of a motion ``total`` s long that speeds up over the
    first ``ramp`` s and slows down over the last (a trapezoid; 0 outside it)."""
    return max(0.0, min(1.0, t / ramp, (total - t) / ramp))


def _spin(rate: float, total: float, ramp: float) -> Callable[[float], Twist | str]:
    """A spin in place at ``rate`` (rad/s, signed) for ``total`` s, ramped up and down over ``ramp`` s
    (a :meth:`Navigator.drive` script)."""

    def spin(t: float) -> Twist | str:
        if t >= total:
            return ScriptSource.END
        return Twist(0.0, 0.0, rate * ramp_fraction(t, total, ramp))

    return spin


def _follow_timeout(follower: Follower, path: Path) -> float:
    """How long a follow may take by default: three times the path's time at the follower's speed
    (its profile's, else the path at ``v_max``) and 10 s."""
    profile = getattr(follower, "profile", None)
    nominal = profile.min_time if profile is not None else path.length / max(follower.limits.v_max, 1e-3)
    return 3.0 * nominal + 10.0


class Navigator:
    """Runs followers on a robot through a client: telemetry, estimation, the control loop, truth.

    ``estimator`` names the estimator the followers see (:data:`omnibot.estimation.ESTIMATORS`);
    ``observers`` are more estimators fed the same telemetry (for comparisons): names, or
    estimators made with :func:`~omnibot.estimation.registry.make_estimator` (keyed by their
    name). ``wheel_loop`` is the runtime's (:class:`~omnibot.runtime.runtime.Runtime`): close the
    controller's wheel-speed loop (MODE bit 1) when every wheel has an encoder (True), open it (False),
    or leave the MODE as found (None: the motors are off, the robot is pushed by hand).
    ``slip`` is the floor's wheel-slip calibration (creep and distance scale) for the driven-wheel
    encoders (every estimator). ``recording`` (the command's ``--log``) records the runtime.
    """

    def __init__(
        self,
        client: RobotClient,
        robot: RobotDescription,
        *,
        estimator: str = "fused",
        observers: Sequence[str | Estimator] = (),
        wheel_loop: bool | None = True,
        binary: bool = True,
        start: Pose2D | None = None,
        slip: SlipParameters | None = None,
        recording: RuntimeRecording | None = None,
    ) -> None:
        self.client = client
        self.robot = robot
        self.start_pose = start or Pose2D(0.0, 0.0, 0.0)
        self.estimator: Estimator = make_estimator(estimator, robot, self.start_pose, slip)
        self.observers: dict[str, Estimator] = {}
        for obs in observers:
            est = make_estimator(obs, robot, self.start_pose, slip) if isinstance(obs, str) else obs
            self.observers[est.name] = est
        self.binary = binary
        self.sim = find_simulator(client.link)
        self.frame: FrameMap | None = None
        self.runtime = Runtime(client, estimator=self.estimator, wheel_loop=wheel_loop, recording=recording)
        """The one loop that owns the client; it feeds the estimator and the observers."""
        self.runtime.telemetry_hooks.extend(obs.update for obs in self.observers.values())
        self.warnings: list[str] = []
        """The runtime's warnings and errors so far (e.g. the estimator's alerts), for the report."""
        self.runtime.notice_hooks.append(self._heard)
        self._started = False

    def _heard(self, notice: Notice) -> None:
        if notice.level != "info":
            self.warnings.append(notice.text)

    # ------------------------------------------------------------------ setup

    def prepare(self, standstill: float = STANDSTILL) -> None:
        """Stop, pick the protocol, start telemetry, and stand still while the gyro bias is learned."""
        c = self.client
        c.stop()
        period = 0.02
        if self.binary:
            try:
                c.use_binary()
                period = 0.01
            except NotSupported:
                pass
        mask = codes.TEL_ENCODERS | codes.TEL_HEADING | codes.TEL_QUEUE
        if self.robot.encoders.tracking:
            mask |= codes.TEL_TRACKING
        self.runtime.start()
        self._started = True
        if self.sim is not None:
            p = self.sim.pose
            self.frame = FrameMap(Pose2D(p.x, p.y, p.theta), self.start_pose)
        c.telemetry(period, mask)
        c.sleep(standstill)

    def calibrate_gyro(
        self, turns: float = 1.0, rates: tuple[float, ...] = SPIN_RATES
    ) -> tuple[float, float]:
        """Spin in place ``turns`` times each way at each of ``rates`` (rad/s), standing still before
        and after each.

        Still (:data:`STANDSTILL` s, after :data:`SETTLE` s of coming to rest), the gyro reads its bias
        alone: the standstills pin it, and its walk, without the encoders. Turning in place from rest
        to rest, the encoders' rotation over each spin is the reference for the scale: whatever creep
        the ramps cause comes back when braking, and on a floor where the wheels creep all the time
        the body turns (mecanum rollers on carpet) the creep is a near-constant rate, told apart from
        the gyro's scale by the two spin rates: ``d_psi - bias T = (1 + scale) (d_enc + creep
        T_moving)`` for each spin (:func:`~omnibot.estimation.spins.fit_spins`). Every fused
        estimator's heading filter takes bias and scale, as known to 5e-5 rad/s (a 3 s standstill's
        mean; looser, the driven wheels' creep in rotation at speed read as bias: omni3 at 4 m/s on
        carpet) and 0.05 %, and its heading is set from the body's rotation over the manoeuvre by
        the gyro, bias and scale corrected (an encoder error over the spins would be a heading
        offset: omni4 on carpet, 0.18 degree). The robot ends where it started (within its own odometry).
        A rate above the robot's ``angular_speed_max`` or :data:`SPIN_GYRO_USE` of its gyro's range is
        capped to it (with one rate left the creep is not fitted). Returns the learned (bias, scale).
        """
        if self.robot.gyro is None:
            raise ConfigError(f"robot {self.robot.name} has no gyro to calibrate")
        probe = GyroProbe(self.robot)
        estimators = [self.estimator, *self.observers.values()]
        hooks = self.runtime.telemetry_hooks
        hooks.append(probe.update)
        try:
            marks, moving, start = self._gyro_spins(probe, estimators, turns, rates)
        finally:
            hooks.remove(probe.update)
        if probe.silence.silent:
            raise NavigationError(
                f"gyro calibration: {probe.silence.finding()}; run without --calibrate-gyro, or describe "
                f"{self.robot.name} without a gyro for this controller"
            )
        fit = probe.fit(marks, moving)
        if fit is None:
            raise NavigationError("gyro calibration needs telemetry with encoders and gyro heading")
        for est, theta in zip(estimators, start, strict=True):
            if isinstance(est, PoseEstimator) and est.heading_source == "fused":
                est.filter.calibrated(fit.bias, fit.scale_error, bias_std=5e-5, scale_std=5e-4)
                p = est.estimate
                est.reset(Pose2D(p.x, p.y, theta + fit.turned))
        return fit.bias, fit.scale_error

    def _gyro_spins(
        self, probe: GyroProbe, estimators: list[Estimator], turns: float, rates: tuple[float, ...]
    ) -> tuple[list[int], list[float], list[float]]:
        """:meth:`calibrate_gyro`'s manoeuvre: a standstill, then at each rate a spin each way, each
        followed by a standstill. Returns the probe's marks (each standstill's start and end), each
        spin's time and the estimators' headings after the first standstill."""
        c = self.client
        marks = [0]  # the first standstill runs from the probe's first sample
        moving: list[float] = []
        c.sleep(STANDSTILL)
        marks.append(probe.mark())
        start = [e.estimate.theta for e in estimators]
        ramp = 0.5
        cap = self.robot.limits.angular_speed_max
        if self.robot.gyro is not None:
            cap = min(cap, SPIN_GYRO_USE * self.robot.gyro.range)
        for rate in (min(r, cap) for r in rates):
            total = 2.0 * math.pi * turns / rate + 2.0 * ramp
            for sign in (1.0, -1.0):
                self.drive(_spin(sign * rate, total, ramp), name="gyro-spin")
                c.sleep(SETTLE)  # the body comes to rest: the standstill after is the gyro's bias alone
                marks.append(probe.mark())
                c.sleep(STANDSTILL)
                marks.append(probe.mark())
                moving.append(total)
        return marks, moving, start

    def close(self) -> None:
        """Stop the robot and the telemetry, detach the listener (idempotent)."""
        if not self._started:
            return
        self._started = False
        try:
            if not self.client.link.closed:
                self.client.stop()
                self.client.telemetry(0.0)
        finally:
            self.runtime.close()

    # ------------------------------------------------------------------ state

    def state(self) -> State:
        """The estimate, extrapolated to now on the link clock."""
        state = self.runtime.estimate_now()
        assert state is not None  # the runtime has the navigator's estimator
        return state

    def truth(self) -> tuple[float, float, float] | None:
        """Ground truth now, in the path's frame (None without a simulator)."""
        if self.sim is None or self.frame is None:
            return None
        p = self.sim.pose
        return self.frame(p.x, p.y, p.theta)

    # ------------------------------------------------------------------ running

    def drive(
        self,
        script: Callable[[float], Twist | str | None],
        *,
        name: str = "manoeuvre",
        period: float = 0.01,
    ) -> None:
        """Drive a scripted manoeuvre on the runtime, then STOP: ``script(t)`` gives the twist ``t`` s
        after its start (:data:`ScriptSource.END` ends it), one VEL every ``period`` s of the link
        clock (watchdog :data:`WATCHDOG`, not awaited). NavigationError when the controller refused a
        command or latched its emergency stop."""
        c = self.client
        runtime = self.runtime
        source = ScriptSource(script, name=name, watchdog=WATCHDOG)
        runtime.pacer = LinkPacer(c, period)
        runtime.add_source(source)
        try:
            runtime.run(until=lambda: source.finished)
            if source.failure:
                raise NavigationError(source.failure)
        finally:
            runtime.remove_source(source.name)
            runtime.discard_pending()
            if not c.link.closed:
                c.stop()

    def follow(
        self,
        path: Path,
        follower: Follower,
        *,
        timeout: float | None = None,
        progress: Progress | None = None,
    ) -> FollowRun:
        """Drive ``path`` with ``follower`` until it is done (or ``timeout`` s, default from the path),
        or ends early (:attr:`FollowRun.failure`: a stall the stall watch found, a refused command, an
        emergency stop); ``progress`` (a bar in metres) hears the distance the estimator says the
        robot has covered, up to the path's length."""
        c = self.client
        clock = c.clock
        run = FollowRun(path, follower.name, self.estimator.name)
        runtime = self.runtime
        start = clock.now()
        source = FollowerSource(follower, path, watchdog=WATCHDOG)
        source.start(self.state().t)
        if timeout is None:
            timeout = _follow_timeout(follower, path)
        run.start_time = start
        distance0 = self.estimator.distance
        shown = 0.0
        tracer = FollowTrace(run, source, self.truth)

        def trace(cycle: Cycle) -> None:
            nonlocal shown
            if tracer(cycle) and progress is not None:
                covered = min(max(self.estimator.distance - distance0, 0.0), path.length)
                progress.update(covered - shown)
                shown = covered

        runtime.pacer = LinkPacer(c, follower.dt)
        runtime.add_source(source)
        runtime.add_sink(trace)
        watch = StallWatch(runtime, self.robot, truth=self.sim)
        try:
            runtime.run(until=lambda: source.finished or clock.now() - start > timeout)
            run.failure = source.failure
            run.completed = follower.done and not source.failure
            run.end_time = clock.now()
        finally:
            watch.close()
            runtime.remove_source(source.name)
            runtime.remove_sink(trace)
            runtime.discard_pending()
            if not c.link.closed:
                c.stop()
        tracer.record(self.state(), STOP)
        c.sleep(SETTLE)
        est = self.estimator.estimate
        run.final_estimate = est.pose
        truth = self.truth()
        run.final_truth = Pose2D(*truth) if truth is not None else None
        run.distance = self.estimator.distance - distance0
        run.warnings = list(self.warnings)
        return run
