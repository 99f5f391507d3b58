"""Keyboard teleop in a terminal: keys become a virtual pad that goes through the same mapping.

::

    w / Up      forward        a  left (strafe)      q / Left   turn left
    s / Down    back           d  right (strafe)     e / Right  turn right
    Shift (capital letter): turbo    space: stop now    Ctrl-C or Ctrl-D: quit

A terminal reports key presses and auto-repeats, never releases, so a key counts as held for
``hold_first`` s after its first press (longer than the terminal's repeat delay, 250..660 ms) and
for ``hold_repeat`` s after each repeat. Letting go is noticed within ``hold_repeat`` s of the last
repeat; the deadman then stops the robot as it does when a pad's enable button is released.

Each held key puts a full deflection on the config's axis for its direction, with the sign of
that axis' scale, and holds the enable (or, with Shift, the turbo) button: so the keyboard drives
with the same scales, limits and deadman as the pad.
"""

from __future__ import annotations

import contextlib
import os
import select
import termios
import tty
from dataclasses import dataclass
from types import TracebackType
from typing import Any, Literal, Self

from omnibot.errors import ConfigError
from omnibot.teleop.config import TeleopConfig
from omnibot.teleop.mapping import JoyState

Direction = Literal["x", "y", "yaw"]
HOLD_FIRST = 0.6
HOLD_REPEAT = 0.15

KEYS: dict[bytes, tuple[Direction, int]] = {
    b"w": ("x", 1),
    b"s": ("x", -1),
    b"a": ("y", 1),
    b"d": ("y", -1),
    b"q": ("yaw", 1),
    b"e": ("yaw", -1),
    b"\x1b[A": ("x", 1),  # Up
    b"\x1b[B": ("x", -1),  # Down
    b"\x1b[D": ("yaw", 1),  # Left
    b"\x1b[C": ("yaw", -1),  # Right
}
"""Key bytes -> (direction, sign): forward, left and counter-clockwise positive."""
STOP_KEYS = (b" ",)
QUIT_KEYS = (b"\x03", b"\x04")

HELP = (
    "keys: w/s or Up/Down forward/back, a/d strafe left/right, q/e or Left/Right turn, "
    "Shift for turbo, space stops, Ctrl-C quits"
)


@dataclass(frozen=True)
class Key:
    """One key press: a drive key (``direction``, ``sign``, ``turbo``) or ``stop`` / ``quit``."""

    direction: Direction | None = None
    sign: int = 0
    turbo: bool = False
    stop: bool = False
    quit: bool = False


def parse_keys(data: bytes) -> list[Key]:
    """Key presses in terminal input (arrow keys are 3-byte escape sequences); unknown bytes are skipped."""
    keys: list[Key] = []
    i = 0
    while i < len(data):
        seq = data[i : i + 3] if data[i : i + 2] == b"\x1b[" else data[i : i + 1]
        i += len(seq)
        if seq in QUIT_KEYS:
            keys.append(Key(quit=True))
        elif seq in STOP_KEYS:
            keys.append(Key(stop=True))
        elif (hit := KEYS.get(seq.lower() if len(seq) == 1 else seq)) is not None:
            keys.append(Key(hit[0], hit[1], turbo=len(seq) == 1 and seq.isupper()))
    return keys


class KeyState:
    """Which directions are held, from key presses and their times (pure: no terminal)."""

    def __init__(
        self, config: TeleopConfig, hold_first: float = HOLD_FIRST, hold_repeat: float = HOLD_REPEAT
    ):
        self.config = config
        self.hold_first = hold_first
        self.hold_repeat = hold_repeat
        self.quit = False
        self._held: dict[Direction, tuple[int, float, bool]] = {}  # direction -> (sign, until, turbo)

    def press(self, key: Key, now: float) -> None:
        """Take one key press at ``now`` s: quit, stop (drop every held direction) or hold a direction."""
        if key.quit:
            self.quit = True
        elif key.stop:
            self._held.clear()
        elif key.direction is not None:
            old = self._held.get(key.direction)
            repeat = old is not None and old[0] == key.sign and now <= old[1]
            hold = self.hold_repeat if repeat else self.hold_first
            self._held[key.direction] = (key.sign, now + hold, key.turbo)

    def joy(self, now: float) -> JoyState:
        """The virtual pad: full deflection on each held direction's axis, enable (or turbo) held."""
        self._held = {d: h for d, h in self._held.items() if now <= h[1]}
        cfg = self.config
        index = {"x": cfg.axis_linear.x, "y": cfg.axis_linear.y, "yaw": cfg.axis_angular.yaw}
        scale = {"x": cfg.scale_linear.x, "y": cfg.scale_linear.y, "yaw": cfg.scale_angular.yaw}
        used = [i for i in index.values() if i is not None]
        axes = [0.0] * (max(used) + 1 if used else 0)
        turbo = False
        for direction, (sign, _, t) in self._held.items():
            i, s = index[direction], scale[direction]
            if i is not None and s:
                axes[i] = float(sign) * (1.0 if s > 0 else -1.0)
                turbo = turbo or t
        buttons = [0] * (max(cfg.enable_button, cfg.turbo_button or 0) + 1)
        if self._held:
            if turbo and cfg.turbo_button is not None:
                buttons[cfg.turbo_button] = 1
            else:
                buttons[cfg.enable_button] = 1
        return JoyState(tuple(axes), tuple(buttons), now)


class KeyboardSource:
    """Reads keys from a terminal in cbreak mode (no echo, no line buffering); a context manager
    that restores the terminal. ``read(now)`` returns the virtual pad's state."""

    name = "keyboard"

    def __init__(
        self, config: TeleopConfig, fd: int | None = None, *, option: str = "--keyboard", **hold: float
    ) -> None:
        self.fd = 0 if fd is None else fd
        if not os.isatty(self.fd):  # `option`: how the user asked for it, named in the error
            raise ConfigError("keyboard teleop needs a terminal (standard input is not one)", key=option)
        self.state = KeyState(config, **hold)
        self._saved: list[Any] | None = None

    def __enter__(self) -> Self:
        self._saved = termios.tcgetattr(self.fd)
        tty.setcbreak(self.fd)
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    @property
    def quit(self) -> bool:
        """True once Ctrl-C or Ctrl-D was typed."""
        return self.state.quit

    def read(self, now: float) -> JoyState:
        """Drain the terminal's pending input and return the pad-like state it leaves."""
        while select.select([self.fd], [], [], 0)[0]:
            try:
                data = os.read(self.fd, 64)
            except OSError:
                data = b""
            if not data:  # end of input: the terminal went away
                self.state.quit = True
                break
            for key in parse_keys(data):
                self.state.press(key, now)
        return self.state.joy(now)

    def close(self) -> None:
        """Restore the terminal (idempotent)."""
        if self._saved is not None:
            with contextlib.suppress(termios.error, OSError):
                termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)
            self._saved = None
