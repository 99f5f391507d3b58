"""Stand-ins for teleop tests: a fake wall clock and an input source that follows a script."""

from __future__ import annotations

from collections.abc import Callable

from omnibot.sim import Simulator
from omnibot.teleop.config import TeleopConfig
from omnibot.teleop.mapping import JoyState
from omnibot.transport import find_device


class FakeWall:
    """A wall clock that moves only when slept on (so paced loops run fast and deterministically)."""

    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t

    def sleep(self, seconds: float) -> None:
        self.t += max(0.0, seconds)


Reading = tuple[tuple[float, ...], tuple[int, ...]]


def seed_pad(
    x: float = 0.0, y: float = 0.0, yaw: float = 0.0, enable: bool = True, turbo: bool = False
) -> Reading:
    """Axes and buttons of seed 003's pad asking for forward x, left y, counter-clockwise yaw (-1..1)."""
    cfg = TeleopConfig()
    axes = [0.0] * 4
    axes[cfg.axis_linear.x or 0] = -x  # scale_linear.x is negative: forward is axis 3 negative
    axes[cfg.axis_linear.y or 0] = y
    axes[cfg.axis_angular.yaw or 0] = yaw
    buttons = [0] * 8
    buttons[7] = int(enable)
    buttons[6] = int(turbo)
    return tuple(axes), tuple(buttons)


def truth(client: object) -> Simulator:
    """The simulator behind a sim:// client."""
    device = find_device(client.link)  # type: ignore[attr-defined]
    assert device is not None
    return device.sim


class ScriptedSource:
    """``script(t) -> (axes, buttons) | None | "stale"``; "stale" repeats the last reading's time
    (an input that froze), None is no pad."""

    name = "script"

    def __init__(self, script: Callable[[float], object]) -> None:
        self.script = script
        self.quit = False
        self._last: JoyState | None = None

    def read(self, now: float) -> JoyState | None:
        step = self.script(now)
        if step is None:
            return None
        if step == "stale":
            return self._last
        assert isinstance(step, tuple)
        axes, buttons = step
        self._last = JoyState(tuple(axes), tuple(buttons), now)
        return self._last
