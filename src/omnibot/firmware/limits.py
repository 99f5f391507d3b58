"""Parameter checks of every command against the protocol and the robot's limits.

``check(keyword, params)`` returns 0 or the ERROR code; a rejected command changes nothing.
Robot limits come from the config (robot description): distance, speed, curvature and rate bounds;
DELTA increments may be twice MOVE's. Seed 000's figures for the omni4 robot: abs(L) < 500 cm,
30 <= abs(V) <= 100 cm/s, abs(C) < 100, abs(F) < 900 deg/s.
"""

from omnibot.protocol import codes

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any

CM_MAX = 500  # SONAR LOW/HIGH/STOP
TIME_MAX = 30000  # POWER T, SONAR/TELEM periods, ms
VEL_TIME_MAX = 1000


class Limits:
    """The checks, with the robot's bounds (floats: exclusive for L, C, F; inclusive for V)."""

    def __init__(self, cfg: "dict[str, Any]") -> None:
        self.motors = int(cfg["motors"])
        self.pwm_max = int(cfg["pwm_max"])
        self.l_max = float(cfg["distance_max_cm"])
        self.v_min = float(cfg["speed_min_cms"])
        self.v_max = float(cfg["speed_max_cms"])
        self.c_max = float(cfg["curvature_max"])
        self.f_max = float(cfg["rate_max_dps"])
        self.sonars = len(cfg["sonar_period_min_ms"])
        self.sonar_period_min = [max(60, int(p)) for p in cfg["sonar_period_min_ms"]]
        self.has_encoders = True
        for c in cfg["encoder_cpr"]:
            if int(c) <= 0:
                self.has_encoders = False

    def check(self, kw: int, p: list[int]) -> int:
        """Check command ``kw``'s parameters against the robot's bounds: 0 when valid, else the ERROR code."""
        n = len(p)
        lo, hi = codes.PARAM_COUNTS[kw]
        if kw == codes.POWER:
            lo = hi = self.motors + 1
        if n < lo or n > hi or (kw == codes.VEL and n == 6):  # VEL: 4, 5 (A) or 7 (AX, AY, AW)
            return codes.E_PARAM_COUNT
        if kw == codes.MOVE:
            return self._move(p[0], p[1], p[2], p[3], 1)
        if kw == codes.DELTA:
            if not 0 <= p[4] <= codes.INF:
                return codes.E_REPEAT
            return self._move(p[0], p[1], p[2], p[3], 2)
        if kw == codes.ROTATE:
            if abs(p[0]) > codes.INF:
                return codes.E_ANGLE
            if p[1] == 0 or abs(p[1]) >= self.f_max:
                return codes.E_SPEED
            return 0
        if kw == codes.POWER:
            return self._power(p)
        if kw == codes.VEL:
            return self._vel(p[0], p[1], p[2], p[3])
        if kw == codes.SONAR:
            return self._sonar(p)
        if kw == codes.TELEM:
            if p[0] != 0 and not codes.TEL_PERIOD_MIN <= p[0] <= TIME_MAX:
                return codes.E_TIME
            if p[1] & ~codes.TEL_MASK:
                return codes.E_UNSUPPORTED
            return 0
        if kw == codes.MODE:
            if p[0] & ~codes.MODE_MASK:
                return codes.E_UNSUPPORTED
            if p[0] & codes.MODE_CLOSED_LOOP and not self.has_encoders:
                return codes.E_UNSUPPORTED
            return 0
        if kw == codes.HELLO:  # HELLO,V1,...: the host's versions; one must be ours
            for v in p:
                if v in codes.VERSIONS:
                    return 0
            return codes.E_UNSUPPORTED if n else 0
        return 0

    def _power(self, p: list[int]) -> int:
        """POWER,T,P1..Pn: a time and a power within full scale for every motor."""
        if not 1 <= p[0] <= TIME_MAX:
            return codes.E_TIME
        for i in range(1, len(p)):
            if abs(p[i]) > self.pwm_max:
                return codes.E_SPEED
        return 0

    def _vel(self, vx: int, vy: int, w: int, t: int) -> int:
        """VEL's speed (within the speed limit), turn rate and watchdog time."""
        if vx * vx + vy * vy > self.v_max * self.v_max or abs(w) >= self.f_max:
            return codes.E_SPEED
        if not 1 <= t <= VEL_TIME_MAX:
            return codes.E_TIME
        return 0

    def _sonar(self, p: list[int]) -> int:
        """SONAR,S,P,LOW,HIGH,STOP: a sonar the robot has, its period and distances."""
        s = p[0] - 1
        if not 0 <= s < self.sonars:
            return codes.E_SONAR
        if p[1] != 0 and not self.sonar_period_min[s] <= p[1] <= TIME_MAX:
            return codes.E_SONAR_PERIOD
        for i in range(2, 5):
            if not 0 <= p[i] <= CM_MAX:
                return codes.E_SONAR
        return 0

    def _move(self, L: int, V: int, D: int, Cv: int, k: int) -> int:
        if abs(L) >= self.l_max * k and not (k == 1 and abs(L) == codes.INF):
            return codes.E_DISTANCE
        if k == 1:
            if abs(V) < self.v_min or abs(V) > self.v_max or V == 0:
                return codes.E_SPEED
        elif abs(V) > self.v_max * k:
            return codes.E_SPEED
        if abs(D) >= 360 * k:
            return codes.E_COURSE
        if abs(Cv) >= self.c_max * k:
            return codes.E_CURVATURE
        return 0
