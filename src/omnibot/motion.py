"""The types every layer shares: a pose, a twist, and the estimated state of the robot.

* :class:`Pose2D`: a planar pose (x, y in m, theta in rad), world or path frame;
* :class:`Twist`: a planar velocity (vx, vy in m/s, w in rad/s); body frame for commands
  (x forward, y left, counter-clockwise positive), world frame where a docstring says so;
* :class:`Estimate`: the robot's estimated pose and world-frame velocity at a time, what the
  estimators produce, the runtime fans out to its sinks and the followers steer by (``State``
  in :mod:`omnibot.control.followers.base` is this class).

Nothing here imports anything of omnibot: any module may use these types.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from omnibot.errors import ConfigError


@dataclass(frozen=True)
class Pose2D:
    """A planar pose: x, y in m, theta in rad (counter-clockwise from x)."""

    x: float
    y: float
    theta: float

    def text(self) -> str:
        """The pose as a person gives it (``pose=X,Y,THETA``): ``(x, y, theta deg)``, m and degrees."""
        return f"({self.x:g}, {self.y:g}, {math.degrees(self.theta):g} deg)"


class Twist(NamedTuple):
    """A planar velocity: vx, vy in m/s, w in rad/s (body frame unless said otherwise)."""

    vx: float = 0.0
    vy: float = 0.0
    w: float = 0.0

    @property
    def is_zero(self) -> bool:
        """True when all three components are exactly zero."""
        return self.vx == 0.0 and self.vy == 0.0 and self.w == 0.0

    @property
    def speed(self) -> float:
        """The planar speed, m/s."""
        return math.hypot(self.vx, self.vy)

    def scaled(self, k: float) -> Twist:
        """This twist with every component multiplied by ``k``."""
        return Twist(self.vx * k, self.vy * k, self.w * k)


ZERO = Twist()


@dataclass(frozen=True)
class Estimate:
    """Pose (world frame), world-frame velocity and flags at time ``t`` (s)."""

    t: float
    x: float
    y: float
    theta: float
    vx: float = 0.0
    vy: float = 0.0
    w: float = 0.0
    slipping: bool = False
    """The estimator saw the wheels slip (its velocity is then less trustworthy)."""
    standstill: bool = True

    @property
    def pose(self) -> Pose2D:
        """The position and heading alone."""
        return Pose2D(self.x, self.y, self.theta)

    @property
    def body_twist(self) -> Twist:
        """The velocity in the body frame (the world-frame vx, vy turned by -theta): what a VEL asks."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return Twist(c * self.vx + s * self.vy, -s * self.vx + c * self.vy, self.w)

    def predict(self, t: float) -> Estimate:
        """Extrapolated to time ``t`` at constant velocity (latency compensation)."""
        dt = t - self.t
        return Estimate(
            t,
            self.x + self.vx * dt,
            self.y + self.vy * dt,
            self.theta + self.w * dt,
            self.vx,
            self.vy,
            self.w,
            self.slipping,
            self.standstill,
        )


def parse_pose(
    text: str, key: str, *, optional_heading: bool = False, prefix: str = "", where: str = ""
) -> tuple[float, float, float | None]:
    """``X,Y,THETA`` (m, m, degrees, as a world file's ``start``; ``X,Y`` too with
    ``optional_heading``) -> (x, y, theta in radians or None). Anything else, a non-finite number
    included, is a ConfigError naming ``key``: ``expected {prefix}X,Y,THETA (m, m, degrees), got
    'text'{where}``."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) not in ((2, 3) if optional_heading else (3,)) or not all(math.isfinite(v) for v in values):
        want = "X,Y[,THETA]" if optional_heading else "X,Y,THETA"
        raise ConfigError(f"expected {prefix}{want} (m, m, degrees), got {text!r}{where}", key=key)
    return values[0], values[1], math.radians(values[2]) if len(values) == 3 else None
