"""Motor powers for a body twist: seed 000's formulas (1)-(3) generalised through the kinematics.

For a twist (vx, vy in m/s, w in rad/s) wheel i needs the rim speed
``s_i = rim_i . (vx, vy, w)`` (``rim`` is the inverse-kinematics matrix J times the wheel radius,
precomputed by config.py). The translation part and the rotation part get their own calibration::

    P_i = K * K_l(p_l, course) * (rim_i0 vx + rim_i1 vy)  +  K * K_t(p_t) * rim_i2 w   (MOVE, VEL)
    P_i = K * K_r(p_r) * rim_i2 w                                                    (ROTATE)

where each factor's power argument is the largest uncalibrated power of its part (K |s|) and the
course is folded onto the calibrated range (:func:`calibration.fold_course`, from the config's
``kl_axes``). Each motor's power then
goes through the motor map (:meth:`calibration.Calibration.motor_power`: its dead-band offset, gain
and speed term at the wheel's rim speed ``s_i``, identity by default), and a translation gets the rollers' drag on top (:meth:`PowerModel.drag`,
zero by default). Then, keeping the
direction, all powers are scaled by one factor if any exceeds ``pwm_max`` (SATURATED) and, when every
non-zero power is below ``power_min`` (the dead band: too little to move the robot), all are set to 0
(DEADBAND). With ``floor`` set (an open-loop VEL: :meth:`Executor.vel`), each wheel whose power is
below it is set to 0 on its own (WEAK): it would not turn, and the robot goes off the course asked.

The PWM output has whole counts only. With ``dither`` on (the config's ``pwm_dither``; off by default, below)
:meth:`PowerModel.finish` carries each wheel's rounding error over to its next output (error diffusion:
``p = round(raw + e)``, ``e += raw - p``), and an open-loop motion refreshes its powers every control
period (motion.py), so a wheel's power averages its fractional value over a few periods where rounding
would lose up to half a count (at 10 cm/s one count is 13 % of mecanum4's forward speed). The dead band
and the weak-wheel check are decided on the rounded powers, as without it. It is off unless the config
asks for it: on the acceptance robot's default calibration (unequal motors) the dithering firmware
fitted a motor map 0.06 off and a ROTATE at 180 degrees/s that the calibration made worse (+0.3 ->
+2.2 %), which rounding does not (docs/firmware.md, *Fractional powers*).
"""

import math

from omnibot.firmware.calibration import Calibration, fold_course

SATURATED = 1
DEADBAND = 2
WEAK = 16  # safety.py owns 4 (LIMITED) and 8 (UNCOVERED)

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any


def roller_terms(
    dirs: "list[list[float]]",
    pitches: "list[float]",
    counts: "list[int]",
    ux: float,
    uy: float,
    out_cos: "list[float]",
    out_sin: "list[float]",
) -> None:
    """Each wheel's roller drag terms for travel along the unit vector (ux, uy).

    Wheel i's rollers roll at ``a_i = |u . n_i|`` of the travel (n_i: their rolling direction,
    ``dirs[i]``) and their drag changes with the roller phase phi_i (2 pi per ``pitches[i]`` encoder
    counts from the encoders' origin; a wheel without an encoder has pitch 0 and no terms):
    ``out_cos[i] = a_i cos(phi_i)``, ``out_sin[i] = a_i sin(phi_i)``.
    """
    for i in range(len(pitches)):
        pitch = pitches[i]
        d = dirs[i]
        share = abs(d[0] * ux + d[1] * uy)
        if pitch <= 0.0 or share == 0.0:
            out_cos[i] = 0.0
            out_sin[i] = 0.0
            continue
        phase = 6.283185307179586 * (counts[i] % pitch) / pitch
        out_cos[i] = share * math.cos(phase)
        out_sin[i] = share * math.sin(phase)


class PowerModel:
    """Twist -> signed PWM counts, with the calibration, saturation and dead band."""

    def __init__(self, cfg: "dict[str, Any]", cal: Calibration) -> None:
        self.n = int(cfg["motors"])
        self.rim = [[float(v) for v in row] for row in cfg["rim"]]
        self.radius = [float(r) for r in cfg["radius"]]
        self.axes = [float(a) for a in cfg.get("kl_axes", cfg["idle_axes"])]
        """The axes K_l's and the reach's courses fold from (a board config older than ``kl_axes``:
        the idle axes, as it was calibrated on)."""
        self.pwm_max = int(cfg["pwm_max"])
        self.power_min = int(cfg["power_min"])
        self.cal = cal
        self.scale = 1.0
        self.raw = [0.0] * self.n
        n = self.n
        self.roller_dir = [[float(v) for v in row] for row in cfg.get("roller_dir", [[0.0, 0.0]] * n)]
        self.roller_pitch = [float(p) for p in cfg.get("roller_pitch", [0.0] * n)]
        self.base = [0.0] * n
        self.drag_gain = 1.0
        self.floor = 0.0
        """PWM counts: a wheel given less (not 0) is set to 0 (WEAK); 0 for no such check."""
        self.dither = bool(cfg.get("pwm_dither", False))
        self.carry = [0.0] * n
        """Each wheel's rounding error carried to its next output (``dither``), PWM counts."""
        self._fc = [0.0] * n
        self._fs = [0.0] * n
        self._ux = 0.0
        self._uy = 0.0

    def wheel_speeds(self, vx: float, vy: float, w: float, out: list[float]) -> None:
        """Wheel angular speeds (rad/s) for a twist."""
        for i in range(self.n):
            row = self.rim[i]
            out[i] = (row[0] * vx + row[1] * vy + row[2] * w) / self.radius[i]

    def compute(self, vx: float, vy: float, w: float, rotate: bool, out: list[int]) -> int:
        """Fill ``out`` with powers for the twist; return SATURATED | DEADBAND | WEAK flags.

        ``rotate`` selects K_r (turning in place) instead of K_l/K_t. The float powers before rounding
        (after saturation) are left in ``self.raw`` and the saturation factor in ``self.scale``.
        """
        n = self.n
        rim = self.rim
        cal = self.cal
        k = cal.k
        raw = self.raw
        tr_max = 0.0
        rot_max = 0.0
        for i in range(n):
            row = rim[i]
            a = abs(row[0] * vx + row[1] * vy)
            b = abs(row[2] * w)
            tr_max = max(tr_max, a)
            rot_max = max(rot_max, b)
        f_tr = 0.0
        self._ux = 0.0
        self._uy = 0.0
        if tr_max > 0.0:
            v = math.sqrt(vx * vx + vy * vy)
            self._ux = vx / v
            self._uy = vy / v
            course = math.degrees(math.atan2(vy, vx))
            f_tr = k * cal.k_l(k * tr_max, fold_course(course, self.axes))
        f_rot = 0.0
        if rot_max > 0.0:
            f_rot = k * (cal.k_r(k * rot_max) if rotate else cal.k_t(k * rot_max))
        peak = 0.0
        carry = self.carry
        for i in range(n):
            carry[i] = 0.0  # a new twist starts from its rounded powers
            row = rim[i]
            t = row[0] * vx + row[1] * vy
            p = cal.motor_power(i, f_tr * t + f_rot * row[2] * w, t + row[2] * w)
            raw[i] = p
            self.base[i] = p
            peak = max(peak, abs(p))
        return self.finish(peak, out)

    def drags(self) -> bool:
        """True when the last twist translates and some wheel has a roller drag to make up for."""
        if self._ux == 0.0 and self._uy == 0.0:
            return False
        cal = self.cal
        for i in range(self.n):
            if self.roller_pitch[i] > 0.0 and (cal.roller_cos[i] != 0.0 or cal.roller_sin[i] != 0.0):
                return True
        return False

    def drag(self, counts: list[int], out: list[int]) -> int:
        """Redo ``out`` for the last twist with the rollers' drag at the wheels' encoder ``counts``.

        The drag is ``sum_i cos_i c_i + sin_i s_i`` PWM counts, with the wheels' terms c_i, s_i of
        :func:`roller_terms` and the coefficients of the calibration, times ``drag_gain`` (a MOVE of
        T s sets it to ``1 + coast / T``: the drag also shortens the coast after the motors stop, which
        only more power during the motion can make up). It is made up by every wheel in
        proportion to its share of the travel, ``(rim_i . u) / max|rim_j . u|`` (the busiest wheel
        gets it all), on top of the powers :meth:`compute` gave; saturation and the dead band as there.
        """
        n = self.n
        ux = self._ux
        uy = self._uy
        cal = self.cal
        fc = self._fc
        fs = self._fs
        roller_terms(self.roller_dir, self.roller_pitch, counts, ux, uy, fc, fs)
        total = 0.0
        for i in range(n):
            total += cal.roller_cos[i] * fc[i] + cal.roller_sin[i] * fs[i]
        total *= self.drag_gain
        rim = self.rim
        busiest = 0.0
        for i in range(n):
            busiest = max(busiest, abs(rim[i][0] * ux + rim[i][1] * uy))
        raw = self.raw
        peak = 0.0
        for i in range(n):
            row = rim[i]
            p = self.base[i] + total * (row[0] * ux + row[1] * uy) / busiest
            raw[i] = p
            peak = max(peak, abs(p))
        return self.finish(peak, out)

    def finish(self, peak: float, out: list[int]) -> int:
        """Saturate ``self.raw`` (peak = its largest magnitude), round into ``out``, apply the dead band."""
        flags = 0
        raw = self.raw
        n = self.n
        self.scale = 1.0
        if peak > self.pwm_max:
            self.scale = self.pwm_max / peak
            flags = SATURATED
            for i in range(n):
                raw[i] *= self.scale
        below = True
        nonzero = False
        for i in range(n):
            p = round(raw[i])
            if p > self.pwm_max:
                p = self.pwm_max
            elif p < -self.pwm_max:
                p = -self.pwm_max
            out[i] = p
            if p != 0:
                nonzero = True
                if abs(p) >= self.power_min:
                    below = False
        if nonzero and below and self.power_min > 0:
            for i in range(n):
                out[i] = 0
            flags |= DEADBAND
        floor = self.floor
        if floor > 0.0:
            for i in range(n):
                if out[i] != 0 and abs(out[i]) < floor:
                    out[i] = 0
                    flags |= WEAK
        if self.dither:
            self._dither(out)
        return flags

    def fractional(self) -> bool:
        """True when dithering would change the last powers over time: some wheel's power is not a
        whole count (what :meth:`refinish` is for)."""
        if not self.dither:
            return False
        raw = self.raw
        return any(raw[i] != round(raw[i]) for i in range(self.n))

    def refinish(self, out: list[int]) -> None:
        """The last powers again, for the next control period (each wheel's carried error added)."""
        self._dither(out)

    def _dither(self, out: list[int]) -> None:
        """Add each wheel's carried rounding error to its power ``out`` (a wheel at 0 starts afresh)
        and carry the new one."""
        raw = self.raw
        carry = self.carry
        top = self.pwm_max
        for i in range(self.n):
            r = raw[i]
            if out[i] == 0:
                carry[i] = 0.0
                continue
            v = r + carry[i]
            p = round(v)
            if p > top:
                p = top
            elif p < -top:
                p = -top
            if p == 0 or (p > 0) != (r > 0):
                p = out[i]  # never off, never against the power asked: rounded as without dithering
            out[i] = p
            carry[i] = v - p
