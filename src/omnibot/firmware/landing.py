"""Closed-loop landing (project): a finite MOVE, DELTA repetition or ROTATE ends on its encoders.

In closed loop (MODE bit 1, an encoder on every wheel) the executor does not time a finite motion:
it measures how far the body went, from the wheels' counts, and ends the motion when that reaches
its distance (or angle). The measure is the forward kinematics of the counts since the motion
started, ``sum_i c_i (n_i - n_i0)``, with c_i wheel i's share along the motion (config ``travel``
projected on the MOVE's body-frame direction: the path driven along the course, however the body
turns; config ``turn`` for a ROTATE: the body's rotation). A ROTATE lands on its encoders, not the
gyro: measured on the presets in the simulator, the encoders' angle is within 0.7 % of the truth
(1.4 % mecanum4 on carpet, 0.2 % with the floor's creep) where the gyro's, uncalibrated in the
firmware (an MPU6050's scale is good to 3 %, its bias to a fraction of a degree/s, and it clips at
250 degrees/s, below ROTATE's limit), was off by up to 1.3 % over four seeds.

The speed the loop is asked for (the *plan*) ramps: up from rest at the acceleration ``land_accel``
(config: a share of the description's acceleration limits), so that a heavy robot's wheels do not
spin on a step, and down near the end so that the robot can stop (or slow to what the next motion
asks) within what is left::

    plan = min(nominal, plan + a dt, sqrt(v_exit^2 + 2 a max(0, left - v LAG_S)))

``left`` is what is left of this motion and of the repetitions of its DELTA still to come,
``v_exit`` the speed the next motion keeps along this one's direction, ``v LAG_S`` what the wheels,
lagging their targets, still go while the loop slows them. The plan never drops below
:data:`CRAWL` (:data:`CRAWL_W` turning) so a motion always finishes; wheels that stand still within
:data:`TOLERANCE` of the end (a motor's static friction can hold a robot creeping that slowly) have
landed. A chain (a DELTA's repetitions, motions queued back to back) carries the plan from one
motion to the next. Between two control periods the end is predicted from the speed measured over
the last one, so a chain of short repetitions ends each where its distance is, not at the next
period (:meth:`Landing.time_left`).

A driven wheel creeps: its rim turns a little faster than the floor moves under it, in the direction
it pushes, most on carpet, where every wheel's rollers roll against a large rolling resistance
(docs/navigation.md's ``slip.py``): the encoders over-read by 1-21 %, and a robot stopped on them
lands short by as much. With the floor's creep coefficients (config ``slip``: ``[roll, combined,
scale, ramp]``, CAL table 9, from ``omnibot calibrate``'s slip runs) the travel is corrected as the
host's odometry corrects it::

    travel = scale * encoder travel - creep(twist) dt

the creep of :class:`~omnibot.estimation.slip.SlipModel` at the twist measured (its rolling,
combined-drag and ramp terms; the acceleration term cancels over a motion from rest to rest and is
left out): each roller row's drag ``(roll + ramp rate^2) tanh(rolling / ROLL_EPS) + combined
sin(2 beta) rolling`` shared out over the wheels as over-turn (config ``creep_mix``, ``creep_roll``,
``creep_rim``), ``rate`` a MOVE's planned acceleration (a tyre creeps faster than the force it
transmits, so the drag creeps more on a ramp; a ROTATE's rate, an angular one, adds none). The
wheels' targets get the same over-turn, so that the body, not the rims, goes at the speed and on
the course asked. Without them (0, 0, 1, 0: the default) the encoders are taken as they read.
"""

import math

from omnibot.protocol import codes

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any

LAG_S = 0.03
"""s: how long the wheels take to follow a lowered target (the speed loop's lag), counted as travel
still to come when the ramp down is planned."""
CRAWL = 0.02
"""m/s: the slowest a landing MOVE is planned at (its first and last millimetres)."""
CRAWL_W = 0.2
"""rad/s: the same for a ROTATE."""
TOLERANCE = 0.001
"""m: a MOVE this close to its end whose wheels stood still over a control period has landed."""
TOLERANCE_W = 0.005
"""rad (0.3 degree): the same for a ROTATE."""
SLIP_SCALE = codes.CAL_SLIP_SCALE
FAR_US = 1000000
"""us: the time left of a motion not yet within a control period of its end (longer than any poll,
so that only an update ends it)."""
ROLL_EPS = 0.01
"""m/s: rolling speed over which a roller's resistance builds up (estimation/slip.py's)."""


def slip_coefficients(cfg: "dict[str, Any]") -> "list[float]":
    """The config's ``slip``, ``[roll, combined, scale, ramp]`` (a config from before the ramp term
    has three: its ramp is 0); no creep, ``[0, 0, 1, 0]``, without one."""
    slip = [float(v) for v in cfg.get("slip") or [0.0, 0.0, 1.0]]
    return slip + [0.0] * (4 - len(slip))


class Landing:
    """One finite motion's travel on the encoders against its distance, and its speed plan."""

    def __init__(self, cfg: "dict[str, Any]") -> None:
        n = int(cfg["motors"])
        travel = cfg.get("travel") or [[0.0] * n, [0.0] * n]
        self.tx = [float(v) for v in travel[0]]
        self.ty = [float(v) for v in travel[1]]
        self.tw = [float(v) for v in cfg.get("turn") or [0.0] * n]
        accel = cfg.get("land_accel") or [0.0, 0.0]
        self.accel = float(accel[0])
        self.accel_w = float(accel[1])
        self.available = (
            all(int(c) > 0 for c in cfg["encoder_cpr"])
            and any(v != 0.0 for v in self.tw)
            and self.accel > 0.0
            and self.accel_w > 0.0
        )
        self.active = False
        self.rotate = False
        self.goal = 0.0  # m (rad for a ROTATE), > 0
        self.done = 0.0  # travelled along the motion since it started
        self.speed = 0.0  # along the motion, measured over the last update, m/s (rad/s)
        self.nominal = 0.0  # the speed asked, m/s (rad/s)
        self.plan = 0.0  # the speed planned now, m/s (rad/s); 0 at rest
        self.rate = 0.0  # the plan's rate of change, m/s^2 (rad/s^2)
        self.ux = 0.0  # the motion's direction: body-frame unit vector, or the turn's sign
        self.uy = 0.0
        self.uw = 0.0
        self._share = [0.0] * n
        self._last = [0] * n
        self._per_rad = [int(c) / (2.0 * math.pi) for c in cfg["encoder_cpr"]]
        self.slip = slip_coefficients(cfg)  # roll m/s, combined, scale, ramp (CAL table 9)
        zero = [[0.0, 0.0, 0.0]] * n
        self._roll = [[float(v) for v in row] for row in cfg.get("creep_roll") or zero]
        self._rim = [[float(v) for v in row] for row in cfg.get("creep_rim") or zero]
        self._mix = [[float(v) for v in row] for row in cfg.get("creep_mix") or [[0.0] * n] * n]
        self._twist = [0.0, 0.0, 0.0]  # the motion's twist per unit of its speed
        self._term = [0.0] * n
        self._over = [0.0] * n

    def set_slip(self, index: int, y: int) -> bool:
        """CAL table 9: coefficient ``index`` (0 roll in 0.01 mm/s, 1 combined, 2 scale, both
        x 10000, 3 ramp in 1e-6 s^3/m) from its protocol integer ``y``; False when out of range
        (ERROR 38)."""
        if index == 0 and y >= 0:
            self.slip[0] = y * 1e-5
        elif index == 1 and y >= 0:
            self.slip[1] = y / SLIP_SCALE
        elif index == 2 and SLIP_SCALE // 2 < y < 2 * SLIP_SCALE:
            self.slip[2] = y / SLIP_SCALE
        elif index == 3 and y >= 0:
            self.slip[3] = y * 1e-6
        else:
            return False
        return True

    @property
    def left(self) -> float:
        """What is left of the motion's distance (angle), negative once past it."""
        return self.goal - self.done

    def rest(self) -> None:
        """The robot is at rest (stopped, or a motion that is not landed ran): the next plan starts at 0."""
        self.active = False
        self.speed = 0.0
        self.plan = 0.0
        self.rate = 0.0

    def start(
        self,
        counts: "list[int]",
        twist: "list[float]",
        rotate: bool,
        goal: float,
        nominal: float,
        wheels: "list[float] | None",
        dt_us: int,
    ) -> None:
        """Land a motion whose body twist per unit of speed is ``twist`` (a MOVE: its body-frame unit
        direction and its turn per m, rad/m; a ROTATE, ``rotate``: 0, 0, +-1), of ``goal`` m along
        the direction (rad of turn), asked at ``nominal`` m/s (rad/s), from ``counts``.

        After a landed motion of the same kind (translation, rotation; ``dt_us`` after its last
        update) the plan carries on, and so does what it went past its end (or stopped short of it),
        projected on this motion's direction: a chain of short repetitions, each ended at the poll
        after its distance, covers the chain's distance. Otherwise the plan starts at the body's
        speed along this motion from the ``wheels``' speeds (rad/s, the speed loop's last measure;
        None at rest)."""
        ux = twist[0]
        uy = twist[1]
        uw = twist[2] if rotate else 0.0
        carry = 0.0
        if self.active and rotate == self.rotate:
            self._advance(counts, dt_us, self.speed)
            dot = ux * self.ux + uy * self.uy + uw * self.uw
            if dot > 0.0:
                carry = self.left * dot
        for i in range(3):
            self._twist[i] = twist[i]
        for i in range(len(self._share)):
            self._share[i] = self.tx[i] * ux + self.ty[i] * uy + self.tw[i] * uw
            self._last[i] = counts[i]
        if not self.active or rotate != self.rotate:
            v = 0.0
            if wheels is not None:
                for i in range(len(self._share)):
                    v += self._share[i] * self._per_rad[i] * wheels[i]
            self.speed = v
            self.plan = v if v > 0.0 else 0.0
            self.rate = 0.0
        self.ux = ux
        self.uy = uy
        self.uw = uw
        self.rotate = rotate
        self.goal = goal + carry
        self.done = 0.0
        self.nominal = nominal
        self.active = True

    def update(self, counts: "list[int]", dt_us: int) -> None:
        """Add the travel since the last update (``dt_us`` ago), less the wheels' creep, and measure
        the speed over it."""
        if dt_us > 0:
            self.speed = self._advance(counts, dt_us, 0.0) * 1e6 / dt_us

    def _advance(self, counts: "list[int]", dt_us: int, v: float) -> float:
        """Add the travel to ``counts`` over ``dt_us``, less the creep at the speed ``v`` along the
        motion (0: at the speed of this step); the travel added."""
        step = 0.0
        for i in range(len(self._share)):
            step += self._share[i] * (counts[i] - self._last[i])
            self._last[i] = counts[i]
        dt = dt_us * 1e-6
        step *= self.slip[2]
        if dt > 0.0:
            step -= self.creep(v if v != 0.0 else step / dt) * dt
        self.done += step
        return step

    def creep(self, v: float) -> float:
        """How much faster than the body moves along the motion its encoders say it does (m/s or
        rad/s) at the speed ``v`` along it, from the floor's creep coefficients (0 without)."""
        t = self._twist
        if not self.overturn(t[0] * v, t[1] * v, t[2] * v, self._over):
            return 0.0
        c = 0.0
        for k in range(len(self._share)):
            c += self._share[k] * self._per_rad[k] * self._over[k]
        return c

    def overturn(self, q0: float, q1: float, q2: float, out: "list[float]") -> bool:
        """Each wheel's creep at the body twist (q0, q1, q2) as over-turn, rad/s, into ``out`` (on a
        MOVE's ramp at its plan's rate); False (``out`` untouched) without creep coefficients."""
        roll = self.slip[0]
        comb = self.slip[1]
        if not self.rotate:  # the drag creeps more under the ramp's force (estimation/slip.py)
            roll += self.slip[3] * self.rate * self.rate
        if roll == 0.0 and comb == 0.0:
            return False
        n = len(self._share)
        term = self._term
        for j in range(n):
            r = self._roll[j]
            rolling = r[0] * q0 + r[1] * q1 + r[2] * q2
            m = self._rim[j]
            rim = m[0] * q0 + m[1] * q1 + m[2] * q2
            both = rim * rim + rolling * rolling
            t = roll * math.tanh(rolling / ROLL_EPS)
            if both > 1e-12:
                t += comb * 2.0 * abs(rim) * abs(rolling) / both * rolling
            term[j] = t
        for k in range(n):
            row = self._mix[k]
            over = 0.0
            for j in range(n):
                over += row[j] * term[j]
            out[k] = over
        return True

    def braking(self) -> float:
        """The distance (angle) in which the motion can stop from its nominal speed (or the speed
        measured, when faster), its lag included: how far ahead the plan must look."""
        a = self.accel_w if self.rotate else self.accel
        v = self.speed if self.speed > self.nominal else self.nominal
        return v * v / (2.0 * a) + v * LAG_S

    def replan(self, rest: float, v_exit: float, dt_us: int) -> float:
        """Advance the plan by ``dt_us``, slowing in time to ``v_exit`` at the end of ``left + rest``
        (``rest``: the repetitions still to come); the plan's share of ``nominal``."""
        a = self.accel_w if self.rotate else self.accel
        room = self.left + rest - max(self.speed, 0.0) * LAG_S
        v = math.sqrt(v_exit * v_exit + 2.0 * a * room) if room > 0.0 else v_exit
        up = self.plan + a * dt_us * 1e-6
        v = min(v, up)
        v = min(v, self.nominal)
        floor = CRAWL_W if self.rotate else CRAWL
        if v < floor:
            v = floor if floor < self.nominal else self.nominal
        self.rate = (v - self.plan) * 1e6 / dt_us if dt_us > 0 else 0.0
        self.plan = v
        return v / self.nominal

    def time_left(self, period_us: int) -> int:
        """Microseconds until the distance is reached at the speed measured: 0 when it is (or the
        wheels stand still within the tolerance of it), an exact time when that comes within
        ``period_us``, else :data:`FAR_US` (the next update decides)."""
        left = self.left
        v = self.speed
        if left <= 0.0 or (v <= 0.0 and left < (TOLERANCE_W if self.rotate else TOLERANCE)):
            return 0
        if v > 0.0 and left < v * period_us * 1e-6:
            return int(left / v * 1e6)
        return FAR_US
