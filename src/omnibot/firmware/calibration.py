"""Seed 000's calibration factors as plain-list piecewise-linear tables (MicroPython-safe).

A table is ``[xs, ys]``: power knots (PWM counts, strictly increasing) and factors; the value is
interpolated linearly between knots and held constant outside them. ``K_l`` has one table per course
(degrees, 0..45 for seed 000) and is interpolated between the two nearest courses.

The motor map (a project addition) makes unequal motors act alike: motor i gets
``sign(a) (offset_i + gain_i(|a|) |a|) + speed_i u`` for the nominal power ``a`` that the factors give
and its rim speed ``u`` (m/s) (:meth:`Calibration.motor_power`): the offset lifts every turning wheel
out of its own dead band, the gain scales the load's share of the power and the speed term corrects
the back-EMF's share (a motor with s times the nominal torque constant has gain 1/s and speed term
(s - 1/s) E, E the nominal back-EMF in counts per m/s; docs/calibration.md). Identity by default.

The roller drag (a project addition, :class:`~omnibot.firmware.power.PowerModel` applies it) holds two
coefficients per wheel, ``roller_cos`` and ``roller_sin`` (PWM counts, zero by default), and the
coast table ``roller_coast`` (``[speeds cm/s, seconds]``: how much longer than the motion the drag
acts, as it also brakes the coast after a MOVE; zero by default).

The reach (a project addition) is ``[folded courses (degrees), speeds cm/s]``: the fastest open-loop
MOVE that lands on each course, as the calibration measured it (interpolated between the courses,
held outside them; 0: no reach known, the default). The executor runs a MOVE asked faster at the
reach (WARN 18).
"""

from omnibot.protocol import codes

TABLE_K = codes.CAL_K
TABLE_KT = codes.CAL_KT
TABLE_KR = codes.CAL_KR
TABLE_KL = codes.CAL_KL  # 10 + k: the k-th course of K_l
TABLE_OFFSET = codes.CAL_OFFSET
TABLE_GAIN = codes.CAL_GAIN  # 20 + i: motor i's gain table
TABLE_ROLLER_COS = codes.CAL_ROLLER_COS
TABLE_ROLLER_SIN = codes.CAL_ROLLER_SIN
TABLE_ROLLER_COAST = codes.CAL_ROLLER_COAST
TABLE_SPEED = codes.CAL_SPEED
TABLE_REACH = codes.CAL_REACH
KNOTS_MAX = codes.CAL_KNOTS_MAX
KL_DROP = codes.CAL_KL_DROP

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any


def map_motor(offset: float, gain: float, speed: float, a: float, u: float) -> float:
    """One motor's power for the nominal power ``a`` (not 0) at rim speed ``u`` (m/s), with its offset,
    its gain at ``|a|`` and its speed term: ``sign(a) (offset min(|a|, 1) + gain |a|) + speed u``, never
    against ``a`` (0 then). The one formula of the firmware and of the host's calibration runs
    (:func:`omnibot.calibration.patterns.map_power`)."""
    m = abs(a)
    p = offset * min(m, 1.0) + gain * m + speed * (u if a > 0 else -u)
    p = max(p, 0.0)
    return p if a > 0 else -p


def interp(xs: list[float], ys: list[float], x: float) -> float:
    """Piecewise-linear y(x), held constant outside the knots."""
    n = len(xs)
    if x <= xs[0]:
        return ys[0]
    for i in range(1, n):
        if x <= xs[i]:
            x0 = xs[i - 1]
            return ys[i - 1] + (x - x0) * (ys[i] - ys[i - 1]) / (xs[i] - x0)
    return ys[n - 1]


def fold_course(course_deg: float, axes: list[float]) -> float:
    """Angle (0..90 degrees) between a course and the nearest of ``axes`` (mod 180 degrees).

    The axes are the config's ``kl_axes``: on omni wheels the "idle axes" (seed 000: motor spindles),
    directions of travel along which some wheel does not turn; for seed 000's four wheels 0 and 90
    degrees, so every course folds into 0..45. A mecanum base folds from its x axis alone (0..90:
    forward, diagonals and sideways apart; omnibot.robot.courses).
    """
    best = 90.0
    for a in axes:
        d = (course_deg - a) % 180.0
        if d > 90.0:
            d = 180.0 - d
        best = min(best, d)
    return best


class Calibration:
    """K (PWM counts per m/s of rim speed), the K_l, K_t, K_r factor tables and the motor map."""

    def __init__(self, cfg: "dict[str, Any]") -> None:
        self.k = float(cfg["k"])
        self.kl_courses = [float(c) for c in cfg["kl_courses"]]
        self.kl = [_table(t) for t in cfg["kl_tables"]]
        self.kt = _table(cfg["kt"])
        self.kr = _table(cfg["kr"])
        n = int(cfg.get("motors", 0))
        self.offset = [float(v) for v in cfg.get("motor_offset", [0.0] * n)]
        self.gain = [_table(t) for t in cfg.get("motor_gain", [[[0.0], [1.0]]] * n)]
        self.speed = [float(v) for v in cfg.get("motor_speed", [0.0] * len(self.offset))]
        self.roller_cos = [float(v) for v in cfg.get("roller_cos", [0.0] * n)]
        self.roller_sin = [float(v) for v in cfg.get("roller_sin", [0.0] * n)]
        self.roller_coast = _table(cfg.get("roller_coast", [[0.0], [0.0]]))
        self.reach = _table(cfg.get("reach", [[0.0], [0.0]]))

    def motor_power(self, i: int, a: float, u: float = 0.0) -> float:
        """Motor i's power for the nominal power ``a`` at rim speed ``u`` (m/s):
        ``sign(a) (offset_i + gain_i(|a|) |a|) + speed_i u``.

        Below one count the offset ramps in with ``|a|``, so a wheel meant to stand still stays still;
        the speed term never turns the power against ``a`` (it is 0 then).
        """
        if a == 0.0 or i >= len(self.offset):
            return a
        t = self.gain[i]
        return map_motor(self.offset[i], interp(t[0], t[1], abs(a)), self.speed[i], a, u)

    def k_l(self, power: float, folded_course: float) -> float:
        """K_l(power, course), the course already folded (see :func:`fold_course`)."""
        cs = self.kl_courses
        n = len(cs)
        if n == 1 or folded_course <= cs[0]:
            return interp(self.kl[0][0], self.kl[0][1], power)
        for i in range(1, n):
            if folded_course <= cs[i]:
                a = interp(self.kl[i - 1][0], self.kl[i - 1][1], power)
                b = interp(self.kl[i][0], self.kl[i][1], power)
                return a + (folded_course - cs[i - 1]) * (b - a) / (cs[i] - cs[i - 1])
        last = self.kl[n - 1]
        return interp(last[0], last[1], power)

    def start_power(self) -> float:
        """The least power that turns a translating wheel, PWM counts (0: the tables do not say).

        A K_l table is fitted to rates anchored at zero at the dead band, so ``p K_l(p)`` runs close
        to ``a + b p`` near its lowest knots: ``a``, that line's intercept through the two lowest
        knots, is the dead band the calibration measured. The smallest over the courses (seed 000's
        flat factors give 0)."""
        low = -1.0
        for t in self.kl:
            xs, ys = t[0], t[1]
            if len(xs) < 2:
                return 0.0
            p0 = xs[0] * ys[0]
            a = p0 - xs[0] * (xs[1] * ys[1] - p0) / (xs[1] - xs[0])
            if low < 0.0 or a < low:
                low = a
        return max(low, 0.0)

    def coast(self, speed: float) -> float:
        """Seconds the roller drag acts beyond a motion ending at ``speed`` (cm/s)."""
        return interp(self.roller_coast[0], self.roller_coast[1], speed)

    def reach_at(self, folded_course: float) -> float:
        """The calibrated reach (cm/s) of a MOVE on the folded course; 0: none known."""
        return interp(self.reach[0], self.reach[1], folded_course)

    def k_t(self, power: float) -> float:
        """K_t at ``power`` PWM counts (linear between knots, held outside them)."""
        return interp(self.kt[0], self.kt[1], power)

    def k_r(self, power: float) -> float:
        """K_r at ``power`` PWM counts (linear between knots, held outside them)."""
        return interp(self.kr[0], self.kr[1], power)

    def set_knot(self, table: int, index: int, power: int, value: float) -> bool:
        """Write one knot (the CAL command); False if the table, index or power order is invalid.

        Writing knot ``index`` drops the knots after it, so a table is uploaded from knot 0 upwards.
        For ``TABLE_KL + k`` with ``index`` -1, ``power`` is the course (degrees) of the k-th curve and
        k may be one past the last curve to add a curve (given a flat factor 1.0 until knots arrive);
        index -2 drops curves k and after (k >= 1: one curve stays). ``TABLE_OFFSET`` sets motor
        ``index``'s offset to ``value`` counts; ``TABLE_GAIN + i`` writes a knot of motor i's gain table;
        ``TABLE_ROLLER_COS`` and ``TABLE_ROLLER_SIN`` set wheel ``index``'s roller drag coefficient;
        ``TABLE_ROLLER_COAST`` writes a knot (``power``: speed in cm/s, ``value`` in s);
        ``TABLE_SPEED`` sets motor ``index``'s speed term (PWM counts per m/s); ``TABLE_REACH`` writes a
        knot of the reach (``power``: folded course in degrees, ``value``: cm/s, 0 none).
        """
        if table == TABLE_K:
            if value <= 0:
                return False
            self.k = value
            return True
        if table == TABLE_KT:
            return _write(self.kt, index, power, value)
        if table == TABLE_KR:
            return _write(self.kr, index, power, value)
        if table in (TABLE_ROLLER_COS, TABLE_ROLLER_SIN, TABLE_SPEED):
            if table == TABLE_SPEED:
                return _set_entry(self.speed, index, power, value)
            return _set_entry(
                self.roller_cos if table == TABLE_ROLLER_COS else self.roller_sin, index, power, value
            )
        if table == TABLE_ROLLER_COAST:
            return _write(self.roller_coast, index, power, value)
        if table == TABLE_REACH:
            if power < 0 or power > codes.CAL_COURSE_MAX or value < 0:
                return False
            return _write(self.reach, index, power, value)
        if table == TABLE_OFFSET:
            return _set_entry(self.offset, index, power, value)
        if table >= TABLE_GAIN:
            i = table - TABLE_GAIN
            if i >= len(self.gain) or value <= 0:
                return False
            return _write(self.gain[i], index, power, value)
        return self._set_kl(table - TABLE_KL, index, power, value)

    def _set_kl(self, k: int, index: int, power: int, value: float) -> bool:
        """:meth:`set_knot` on K_l's curve ``k``: drop curves (index -2), set or add a course (-1) or
        write a knot."""
        if index == KL_DROP:
            if k < 1 or k > len(self.kl) or power != 0:
                return False
            del self.kl[k:]
            del self.kl_courses[k:]
            return True
        if k < 0 or k > len(self.kl) or (k == len(self.kl) and index != -1):
            return False
        if index == -1:
            courses = self.kl_courses
            if power < 0 or power > codes.CAL_COURSE_MAX:
                return False
            if (k > 0 and power <= courses[k - 1]) or (k + 1 < len(courses) and power >= courses[k + 1]):
                return False
            if k == len(courses):
                courses.append(float(power))
                self.kl.append([[0.0], [1.0]])
            else:
                courses[k] = float(power)
            return True
        return _write(self.kl[k], index, power, value)


def _table(t: "list[Any]") -> "list[list[float]]":
    return [[float(x) for x in t[0]], [float(y) for y in t[1]]]


def _set_entry(coeffs: list[float], index: int, power: int, value: float) -> bool:
    """Set ``coeffs[index]`` (one per motor or wheel; ``power`` must be 0); False if out of range."""
    if index < 0 or index >= len(coeffs) or power != 0:
        return False
    coeffs[index] = value
    return True


def _write(t: "list[list[float]]", index: int, power: int, value: float) -> bool:
    xs, ys = t
    if index < 0 or index > len(xs) or index >= KNOTS_MAX:
        return False
    if index > 0 and power <= xs[index - 1]:
        return False
    del xs[index:]
    del ys[index:]
    xs.append(float(power))
    ys.append(value)
    return True
