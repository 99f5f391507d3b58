"""The distance check of a MOVE (project): what the wheel encoders measured against the plan.

A finite MOVE on a robot with an encoder on every wheel is watched. Its progress is the body's travel
along the MOVE's direction in the body frame, ``sum_i c_i (n_i - n_i0)``: n_i wheel i's encoder count,
c_i its share (config ``travel``: the least-squares forward kinematics, metres of body travel per
count, projected on the direction). That is the length of path driven along the course however the
body turns, for a straight and for a curved MOVE alike. When the MOVE ends the queue, the watch goes
on through the coast; once no count moved for one check period (the wheels stand still) or after
:data:`COAST_MAX_US`, a progress short of the distance by more than ``progress_tolerance`` is
reported (:meth:`ProgressWatch.step` returns True: WARN 17, after IDLE). Another motion started before
then, STOP, or the simulation mode end the watch unjudged: the distances of chained motions cannot be
told apart on the encoders.

What it does not see: wheel slip (the encoders count turns the floor did not take, so a slipping robot
looks further along than it is) and a wheel radius other than the description's (a robot whose wheels
are 5 % larger reads 5 % short when it lands): the tolerance covers such errors, not more.
"""

COAST_MAX_US = 3000000  # the longest coast watched; a robot pushed about is judged then
OFF = 0  # no MOVE watched
MOVING = 1
COASTING = 2

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any


class ProgressWatch:
    """One MOVE's encoder progress against its distance (module docstring)."""

    def __init__(self, cfg: "dict[str, Any]") -> None:
        n = int(cfg["motors"])
        travel = cfg.get("travel", [[0.0] * n, [0.0] * n])
        self.tx = [float(v) for v in travel[0]]
        self.ty = [float(v) for v in travel[1]]
        self.tolerance = float(cfg.get("progress_tolerance", 0.0))
        self.available = self.tolerance > 0.0 and all(int(c) > 0 for c in cfg["encoder_cpr"])
        self.state = OFF
        self.distance = 0.0
        self.progress = 0.0
        self._share = [0.0] * n
        self._start = [0] * n
        self._last = [0] * n
        self._coast_us = 0

    @property
    def moving(self) -> bool:
        """True while a watched MOVE runs."""
        return self.state == MOVING

    def start(self, counts: "list[int]", ux: float, uy: float, distance_m: float) -> None:
        """Watch a MOVE of ``distance_m`` along the body-frame unit vector (ux, uy) from ``counts``."""
        if not self.available or distance_m <= 0.0:
            self.state = OFF
            return
        for i in range(len(self._share)):
            self._share[i] = self.tx[i] * ux + self.ty[i] * uy
            self._start[i] = counts[i]
        self.distance = distance_m
        self.state = MOVING

    def cancel(self) -> None:
        """End the watch unjudged."""
        self.state = OFF

    def ended(self, counts: "list[int]") -> None:
        """The watched MOVE's timeline ended with the queue empty: watch its coast."""
        for i in range(len(self._last)):
            self._last[i] = counts[i]
        self._coast_us = 0
        self.state = COASTING

    def measure(self, counts: "list[int]") -> float:
        """The body's travel along the MOVE's direction since it started, m (also left in ``progress``)."""
        s = 0.0
        for i in range(len(self._share)):
            s += self._share[i] * (counts[i] - self._start[i])
        self.progress = s
        return s

    def step(self, counts: "list[int]", dt_us: int) -> bool:
        """One check period of the coast (``dt_us`` since the last): True once, when the wheels stood
        still (or the coast lasted :data:`COAST_MAX_US`) and the MOVE fell short beyond the tolerance."""
        if self.state != COASTING:
            return False
        self._coast_us += dt_us
        still = True
        for i in range(len(self._last)):
            if counts[i] != self._last[i]:
                still = False
            self._last[i] = counts[i]
        if not still and self._coast_us < COAST_MAX_US:
            return False
        self.state = OFF
        return self.measure(counts) < (1.0 - self.tolerance) * self.distance
