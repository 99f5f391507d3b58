"""Our tracker: the time-optimal profile as feedforward, with along-track, cross-track and heading feedback.

The path is planned once with :func:`~omnibot.control.paths.profile.time_optimal_profile` within a
margin of the limits (``margin``: the rest is left for feedback), which gives a reference pose,
velocity and turn rate at every instant. Each control period (100 Hz or more):

1. **reference time** advances with the clock, slowed by a governor when the robot lags more than
   ``lag_start`` behind along the path (so a stuck start or a slipping patch does not leave the
   reference running away and the robot cutting across to catch up);
2. **prediction**: the estimated pose is carried ``lead`` seconds ahead with the estimated velocity
   and the reference's acceleration (telemetry age, link and wheel-loop delay), and the reference
   is taken at the same instant;
3. **feedback** on the error in the path frame at the reference point: cross-track with a PI
   (gain ``cross``, integral ``cross_i``, clamped), along-track with a PI (``along``, ``along_i``),
   and heading with a PI (``heading``, by default :func:`heading_gain`; ``heading_i``) towards the
   path's heading where the robot is along it (the reference's, moved by the along-track error);
4. **command**: v = v_ref + k_t e_t t + k_n e_n n and w = w_ref + k_theta e_theta, the correction
   (v - v_ref) within :func:`~omnibot.control.followers.base.correction_speed`, turned into the
   body frame with the heading at the middle of the next period, speed clamped to the limit, and
   the twist scaled down as a whole where it would be beyond the robot's reach
   (:func:`within_reach`: the wheels' free speed and the floor's load);
5. **planned acceleration** for the VEL (:attr:`~Follower.planned_body_accel`): the reference's
   acceleration (the world's, centripetal included, and the heading's angular one) turned into the
   command's body axes, for a controller of protocol version 4 to feed forward on every VEL; for one
   of version 3, :attr:`~Follower.planned_accel` on straight runs with the heading held.

The path is done when the reference has reached the end and the robot is within ``end_tolerance``
of the last point and nearly still (or ``settle`` seconds after the reference ended).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from omnibot.control.followers.base import (
    PLAN_MARGIN,
    STOP,
    Command,
    Follower,
    State,
    bound_correction,
    clamp_speed,
    correction_speed,
    register,
    to_body,
    wrap,
)
from omnibot.control.followers.response import VelocityResponse
from omnibot.control.paths.limits import MotionLimits
from omnibot.control.paths.path import FloatArray, Path
from omnibot.control.paths.profile import Reference, SpeedProfile

STEADY_ACCEL = 0.5
"""m/s^2: the response model learns only while the reference accelerates less than this (and the
estimator sees no slip, its speed changes slower than :data:`STEADY_SPEEDUP` and the feedback is
within its bound, and has been for :data:`RELEARN` s): it is a steady-state gain."""
RELEARN = 1.0
"""s: after the feedback was last cut to its bound (:attr:`ProfileTracker.correcting`: a robot coming
back to its path) the response model waits this long before it learns again."""
STEADY_SPEEDUP = 0.1
"""m/s^2: the response model also learns only while the reference's speed changes slower than this.
It compares the body's velocity with the command of ``delay`` before (the wheel loop's lag); a
controller that feeds the planned acceleration forward (protocol version 4) follows a ramp with less
lag, and learning on ramps up to 0.5 m/s^2 the model read that as gain (omni3 carpet line-swing at
top speed 1.00 cm RMS, 0.37 against its own estimate; with this 0.91 and 0.15)."""
STRAIGHT_ACCEL = 1e-6
"""m/s^2: the tracker plans version 3's acceleration for VEL (:attr:`~Follower.planned_accel`) only
where the reference goes straight (its acceleration across its velocity below this) with the heading
held: the field carries the speed-up along the travel alone (see the base class). Version 4's
(:attr:`~Follower.planned_body_accel`) carries the whole acceleration and goes with every VEL."""
MOVING_SPEED = 1e-3
"""m/s: below this reference speed the heading asked is the reference's own (a turn in place), above
it the path's heading at the robot's progress."""
HEADING_GAIN = 8.0
"""1/s: the heading loop's gain on a robot whose angular acceleration can deliver it (see
:func:`heading_gain`)."""
CROSS_GAIN = 30.0
"""1/s: the cross-track loop's gain. With the prediction's lead it also feeds back ``CROSS_GAIN *
lead`` of the estimate's velocity across the path, and that velocity is the wheels' (encoders): a
wheel that slips moves it at once. At 45/s (1.8 of it) mecanum4's top-speed line with the body
swinging rang at 6-8 Hz, the commands swinging 0.4-0.6 m/s each way (wheel targets reversing 20
rad/s in 40 ms, the wheels slipping 0.2-0.4 m/s) whenever a slip moved the estimate, and the
odometry came out up to 3.1 cm off (seeds 1-5: 0.4-3.1 cm max with mecanum4's own forward power
curve, 0.4-0.8 with the sideways one); at 30/s 0.5-0.7 cm (docs/navigation.md)."""
HEADING_STEP = 0.1
"""rad: a heading error whose correction (gain x error, rad/s) the robot must be able to add within
the tracker's lead at its angular acceleration limit (:func:`heading_gain`)."""


def heading_gain(limits: MotionLimits, lead: float) -> float:
    """1/s: the heading loop's gain, :data:`HEADING_GAIN` or less: at most what lets the robot add the
    correction of a :data:`HEADING_STEP` error within ``lead`` s at its angular acceleration limit.

    A heavier body gets a softer loop: omni3 (30 kg, 10 rad/s^2) 4/s, omni4 and mecanum4 (20 rad/s^2)
    8/s. A stiffer one asks a body that lags in heading (its wheels at their grip, on carpet) for
    turn rates it cannot reach, and the grip the correction takes is the translation's.
    """
    return min(HEADING_GAIN, limits.alpha_max * lead / HEADING_STEP)


@register("tracker")
class ProfileTracker(Follower):
    """Time-optimal feedforward plus path-frame PI feedback (see the module docstring)."""

    end_tolerance: ClassVar[float] = 0.01

    def __init__(
        self,
        limits: MotionLimits,
        *,
        rate: float = 100.0,
        margin: float = PLAN_MARGIN,
        lead: float = 0.04,
        cross: float = CROSS_GAIN,
        cross_i: float = 100.0,
        along: float = 10.0,
        along_i: float = 20.0,
        heading: float | None = None,
        heading_i: float = 10.0,
        lag_start: float = 0.03,
        lag_span: float = 0.10,
        settle: float = 1.5,
        adapt: bool = True,
        turn_lead: float | None = None,
        reach: bool = True,
        progress_heading: bool = True,
        **options: Any,
    ) -> None:
        super().__init__(limits, rate=rate, **options)
        self.margin = margin
        self.lead = lead
        self.k_cross, self.i_cross = cross, cross_i
        self.k_along, self.i_along = along, along_i
        self.k_heading = heading_gain(limits, lead) if heading is None else heading
        self.i_heading = heading_i
        self.lag_start, self.lag_span = lag_start, lag_span
        self.settle = settle
        self.turn_lead = lead if turn_lead is None else turn_lead
        self.reach = reach
        """Scale a command beyond the robot's reach down as a whole (:func:`within_reach`); False
        sends it as asked (the wheel loops saturate one by one)."""
        self.progress_heading = progress_heading
        """Ask for the path's heading where the robot is along it; False: the reference's own,
        wherever the robot is."""
        self.correction = correction_speed(limits)
        """m/s: the most the feedback adds to the reference's velocity (:func:`correction_speed`)."""
        self.correcting = False
        """The last command's feedback was cut to :attr:`correction`: the robot is coming back to the
        path (a push, a corrected estimate), lagging its command by design; the response model does
        not learn from it, nor for :data:`RELEARN` s after (it read a 30 cm recovery on omni4 as a
        slow floor and then asked 1.27-1.30 m/s of a 1 m/s robot)."""
        self._corrected_at = -math.inf  # when the feedback was last cut to its bound, s
        self.response = VelocityResponse() if adapt else None
        self.profile: SpeedProfile | None = None
        self.tau = 0.0
        """Reference time, s (the profile's clock, slowed by the governor)."""
        self._last_t: float | None = None
        self._integral = np.zeros(3)  # along, cross, heading
        self._holds_heading = False
        self._ended_at: float | None = None
        self._steady: bool | None = None  # the last command's reference was steady (None: a STOP)
        self._dt_seen = 0.0  # the last command's interval, s
        self.errors = (0.0, 0.0, 0.0)
        """Last along-track, cross-track (m) and heading (rad) errors of the estimate."""

    def start(self, path: Path, t: float) -> None:
        """Begin following ``path`` at time ``t``: plan the speed profile, zero the reference time and
        the integrals."""
        super().start(path, t)
        self.profile = self.plan(path, self.margin)
        self.tau = 0.0
        self._holds_heading = float(np.ptp(path.theta)) == 0.0  # planned_accel only then
        self._last_t = t
        self._ended_at = None
        self._corrected_at = -math.inf
        self._integral[:] = 0.0
        if self.response is not None:
            self.response.reset()

    def command(self, state: State) -> Command:
        """Track the time-parametrised reference with feedforward plus feedback; STOP once done."""
        prof, path = self.profile, self.path
        assert prof is not None and path is not None
        self.planned_accel = 0.0
        self.planned_body_accel = None
        self._steady = None
        if self.done:
            return STOP
        dt = self.dt if self._last_t is None else max(0.0, state.t - self._last_t)
        self._last_t = state.t

        pace = self._advance(state, dt)  # 1. reference time with the lag governor
        if pace is None:
            return STOP
        end = prof.min_time

        # 2. prediction: robot and reference at the instant the command takes effect
        lead = self.lead
        ref = prof.at(self.tau + lead * pace)
        # the robot carried ahead on the reference's acceleration (on a curve a straight-line
        # prediction lands outside it, and the loop would hold the robot inside by v^2 lead^2 / 2R)
        half = 0.5 * lead * lead
        px = state.x + state.vx * lead + half * ref.ax
        py = state.y + state.vy * lead + half * ref.ay
        pth = state.theta + state.w * lead
        self.progress = ref.s
        tx, ty = _direction(ref.vx, ref.vy, prof, self.tau + lead)
        straight = abs(ref.ax * ty - ref.ay * tx) < STRAIGHT_ACCEL
        if self._holds_heading and straight and self.tau < end:  # (at its end the reference stands)
            self.planned_accel = (ref.ax * tx + ref.ay * ty) * pace  # the reference's speed-up, m/s^2
        # the reference's whole acceleration (world frame; the turn's), 0 once it stands at the end
        moving = pace if self.tau < end else 0.0
        acc_x, acc_y, alpha = ref.ax * moving, ref.ay * moving, ref.alpha * moving
        nx, ny = -ty, tx

        # 3. feedback in the path frame
        ex, ey = ref.x - px, ref.y - py
        e_t, e_n = ex * tx + ey * ty, ex * nx + ey * ny
        # the heading asked is the path's where the robot is along it, e_t behind the reference (on
        # a path whose heading changes with its length; where the reference turns in place, its own)
        on_path = self.progress_heading and ref.speed > MOVING_SPEED
        turn = ref.w / ref.speed if on_path else 0.0  # rad per m of the path
        e_th = wrap(ref.theta - turn * e_t - pth)
        self.errors = (e_t, e_n, e_th)
        vx, vy, w = self._feedback(ref.vx, ref.vy, ref.w, tx, ty, dt)
        # into the body frame at the heading the body will have when the command acts: a body
        # turning at w while it goes would otherwise drive w x turn_lead off the course
        heading = state.theta + state.w * self.turn_lead
        command = to_body(vx, vy, w, heading, self.dt)
        body = to_body(acc_x, acc_y, alpha, heading + 0.5 * w * self.dt)  # the same axes
        self.planned_body_accel = (body.vx, body.vy, body.w)
        self._steady, self._dt_seen = self._learns(ref, tx, ty, state.t), dt
        return command

    def _learns(self, ref: Reference, tx: float, ty: float, t: float) -> bool:
        """Whether the response model may learn from the command for ``ref`` (heading ``tx, ty``) at
        time ``t``: the reference steady and the feedback within its bound for :data:`RELEARN` s."""
        if self.correcting:
            self._corrected_at = t
        return (
            math.hypot(ref.ax, ref.ay) < STEADY_ACCEL
            and abs(ref.ax * tx + ref.ay * ty) < STEADY_SPEEDUP
            and t - self._corrected_at > RELEARN
        )

    def respond(self, state: State, command: Command) -> Command:
        """``command`` (the body's twist, within the limits) through the learned response model and
        within the robot's reach (:meth:`_through_response`); a STOP as it is."""
        if self._steady is None:
            return command
        return self._through_response(state, command, self._steady, self._dt_seen)

    def _feedback(
        self, vx: float, vy: float, w: float, tx: float, ty: float, dt: float
    ) -> tuple[float, float, float]:
        """The world-frame command: the reference's velocity ``vx, vy, w`` plus PI feedback on
        :attr:`errors` along the path's tangent ``tx, ty`` and its normal, within the limits."""
        e_t, e_n, e_th = self.errors
        nx, ny = -ty, tx
        limits = self.limits
        integral = self._integrate(e_t, e_n, e_th, dt)
        u_t = self.k_along * e_t + self.i_along * integral[0]
        u_n = self.k_cross * e_n + self.i_cross * integral[1]
        self.correcting = math.hypot(u_t, u_n) > self.correction
        cx, cy = bound_correction(vx + u_t * tx + u_n * nx, vy + u_t * ty + u_n * ny, vx, vy, self.correction)
        vx, vy = clamp_speed(cx, cy, limits.v_max)
        w = w + self.k_heading * e_th + self.i_heading * integral[2]
        return vx, vy, max(-limits.w_max, min(limits.w_max, w))

    def _integrate(self, e_t: float, e_n: float, e_th: float, dt: float) -> FloatArray:
        """The errors' integrals (along, across, heading) with this interval's added, each held
        within what gives a tenth of the speed or turn-rate limit."""
        limits = self.limits
        integral = self._integral
        integral += np.array([e_t, e_n, e_th]) * dt
        caps = (
            0.1
            * np.array([limits.v_max, limits.v_max, limits.w_max])
            / np.maximum([self.i_along, self.i_cross, self.i_heading], 1e-9)
        )
        np.clip(integral, -caps, caps, out=integral)
        return integral

    def _advance(self, state: State, dt: float) -> float | None:
        """Advance the reference time by ``dt`` at the lag governor's pace (1 on time, down to 0.2 as
        the robot lags behind the reference) and return the pace; None once the run is done (the
        reference at its end and the robot there, or settled for :attr:`settle` s)."""
        prof = self.profile
        assert prof is not None
        now = prof.at(self.tau)
        tx, ty = _direction(now.vx, now.vy, prof, self.tau)
        lag = (now.x - state.x) * tx + (now.y - state.y) * ty
        pace = 1.0 if lag <= self.lag_start else max(0.2, 1.0 - (lag - self.lag_start) / self.lag_span)
        self.tau += dt * pace
        end = prof.min_time
        if self.tau >= end:
            self.tau = end
            if self._ended_at is None:
                self._ended_at = state.t
            if self.at_end(state) or state.t - self._ended_at >= self.settle:
                self.done = True
                return None
        return pace

    def _through_response(self, state: State, command: Command, steady: bool, dt: float) -> Command:
        """``command`` through the learned response model, when there is one (it observes the body's
        twist while the reference is ``steady`` and nothing slips), then within the robot's reach."""
        limits = self.limits
        model = self.response
        if model is None:
            return within_reach(limits, command) if self.reach else command
        c, s = math.cos(state.theta), math.sin(state.theta)
        if not state.slipping and steady:
            model.observe(state.t, c * state.vx + s * state.vy, -s * state.vx + c * state.vy, state.w, dt)
        ux, uy = clamp_speed(*model.compensate(command.vx, command.vy, command.w)[:2], 1.3 * limits.v_max)
        uw = max(-limits.w_max, min(limits.w_max, command.w / model.g_w))
        command = Command(ux, uy, uw)
        if self.reach:
            command = within_reach(limits, command)
        model.sent(state.t, command.vx, command.vy, command.w)
        return command


def within_reach(limits: MotionLimits, command: Command) -> Command:
    """``command`` scaled down as a whole, if need be, to the robot's reach: no wheel past its
    free-running speed and, given the limits' floor, the twist within what the floor's load leaves
    the motors (:meth:`~omnibot.control.paths.limits.MotionLimits.reach`).

    Past it the wheel-speed loops saturate one by one, and the twist the wheels then give is not
    the one asked: at omni3's top speed with the body swinging the translation took the wheels and
    the turn fell behind, until the body caught up and overshot past the gyro's range. Scaled as a
    whole, the command keeps its course and its share of turn, and only the pace drops (which the
    lag governor then follows)."""
    k = float(limits.reach(np.array([[command.vx, command.vy, command.w]]))[0])
    if k >= 1.0:
        return command
    return Command(command.vx * k, command.vy * k, command.w * k)


def _direction(vx: float, vy: float, prof: SpeedProfile, tau: float) -> tuple[float, float]:
    """Unit direction of the reference: its velocity, or the path's direction where it is still."""
    speed = math.hypot(vx, vy)
    if speed > 1e-6:
        return vx / speed, vy / speed
    j = int(np.searchsorted(prof.t, min(max(tau, 0.0), prof.min_time), side="right")) - 1
    j = min(max(j, 0), len(prof.t) - 1)
    return float(prof.tx[j]), float(prof.ty[j])
