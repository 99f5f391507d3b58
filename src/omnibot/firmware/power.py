"""Motor powers for a body twist: seed 000's formulas (1)-(3) generalised through the kinematics.

For a twist (vx, vy in m/s, w in rad/s) wheel i needs the rim speed
``s_i = rim_i . (vx, vy, w)`` (``rim`` is the inverse-kinematics matrix J times the wheel radius,
precomputed by config.py). The translation part and the rotation part get their own calibration::

    P_i = K * K_l(p_l, course) * (rim_i0 vx + rim_i1 vy)  +  K * K_t(p_t) * rim_i2 w   (MOVE, VEL)
    P_i = K * K_r(p_r) * rim_i2 w                                                    (ROTATE)

where each factor's power argument is the largest uncalibrated power of its part (K |s|) and the
course is folded onto the calibrated range (:func:`calibration.fold_course`). Each motor's power then
goes through the motor map (:meth:`calibration.Calibration.motor_power`: its dead-band offset and
gain, identity by default). Then, keeping the
direction, all powers are scaled by one factor if any exceeds ``pwm_max`` (SATURATED) and, when every
non-zero power is below ``power_min`` (the dead band: too little to move the robot), all are set to 0
(DEADBAND).
"""

import math

from omnibot.firmware.calibration import Calibration, fold_course

SATURATED = 1
DEADBAND = 2

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any


class PowerModel:
    """Twist -> signed PWM counts, with the calibration, saturation and dead band."""

    def __init__(self, cfg: "dict[str, Any]", cal: Calibration) -> None:
        self.n = int(cfg["motors"])
        self.rim = [[float(v) for v in row] for row in cfg["rim"]]
        self.radius = [float(r) for r in cfg["radius"]]
        self.axes = [float(a) for a in cfg["idle_axes"]]
        self.pwm_max = int(cfg["pwm_max"])
        self.power_min = int(cfg["power_min"])
        self.cal = cal
        self.scale = 1.0
        self.raw = [0.0] * self.n

    def wheel_speeds(self, vx: float, vy: float, w: float, out: list[float]) -> None:
        """Wheel angular speeds (rad/s) for a twist."""
        for i in range(self.n):
            row = self.rim[i]
            out[i] = (row[0] * vx + row[1] * vy + row[2] * w) / self.radius[i]

    def compute(self, vx: float, vy: float, w: float, rotate: bool, out: list[int]) -> int:
        """Fill ``out`` with powers for the twist; return SATURATED | DEADBAND flags.

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
        if tr_max > 0.0:
            course = math.degrees(math.atan2(vy, vx))
            f_tr = k * cal.k_l(k * tr_max, fold_course(course, self.axes))
        f_rot = 0.0
        if rot_max > 0.0:
            f_rot = k * (cal.k_r(k * rot_max) if rotate else cal.k_t(k * rot_max))
        peak = 0.0
        for i in range(n):
            row = rim[i]
            p = cal.motor_power(i, f_tr * (row[0] * vx + row[1] * vy) + f_rot * row[2] * w)
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
        return flags
