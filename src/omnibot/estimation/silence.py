"""A gyro that says nothing: its heading stands still while the wheels turn the body.

The protocol sends the gyro's groups even from a controller without a gyro, as 0 (docs/protocol.md,
TEL): the Arduino UNO firmware (its wiring has none), a MicroPython board whose gyro pins are not
set. A gyro that stops answering leaves the heading where it was. The host knows the robot by the
name in HELLO, and a description with a gyro (omni4's has one) would then fuse a heading that never
moves: the fused filter takes the wheels' rotation for a skid and holds the heading still while the
body turns, and a follower spins the robot round trying to turn it.

A working gyro's integrated heading (0.01 degree steps) does not stand still while the body turns:
10 degrees are 1,000 steps. So a heading that has not changed while the wheel encoders say the body
turned :data:`SILENT_TURN` (net, so that the wheels' wobble and a floor's slip on a straight run do
not add up) is taken as no gyro. Any change of the heading starts the count again.
"""

from __future__ import annotations

import math

SILENT_TURN = math.radians(10.0)
"""Net rotation the wheel encoders must measure while the gyro's heading stands still to call the
gyro silent, rad. Far above what the wheels' slip turns them on a straight run (odometry drift: under
2 degrees in the benchmark's runs), small enough that a follower has not gone far wrong by then."""


class GyroSilence:
    """Watches a TEL stream for a gyro heading that stands still while the encoders turn."""

    def __init__(self, threshold: float = SILENT_TURN) -> None:
        self.threshold = threshold
        self.turned = 0.0
        """The encoders' net rotation since the gyro's heading last changed, rad."""
        self.silent = False
        """The gyro was found silent (for good: the estimate no longer waits for it)."""
        self._heading: float | None = None

    def update(self, heading: float | None, d_ref: float | None) -> bool:
        """Fold in one sample's gyro heading (rad, None: not sent) and the encoders' rotation since the
        last sample (rad, None: none); True on the sample that finds the gyro silent."""
        if self.silent or heading is None:
            return False
        if heading != self._heading:
            self._heading = heading
            self.turned = 0.0
            return False
        if d_ref is not None:
            self.turned += d_ref
        if abs(self.turned) < self.threshold:
            return False
        self.silent = True
        return True

    def finding(self) -> str:
        """What was found, in words (once :attr:`silent`)."""
        return (
            f"the gyro's heading stood still while the wheels turned the body "
            f"{math.degrees(abs(self.turned)):.0f} degrees: no working gyro on this controller "
            f"(the UNO firmware has none)"
        )
