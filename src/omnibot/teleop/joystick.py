"""Joystick input through pygame (SDL 2), with hot-plug: pads may come and go while teleop runs.

No window is opened: SDL's video driver defaults to ``dummy`` (set ``SDL_VIDEODRIVER`` to override)
and background joystick events are allowed. Readings are turned into ROS joy's convention (SDL says
stick up / left is negative, joy says positive; hats follow the axes as two extra axes each, left
and up positive) so that ROS teleop configs such as seed 003's carry over unchanged.

``read(now)`` returns the pad's state, or None while no pad is attached (the deadman then stops
the robot: "lost"). The pad used is the ``device_id``-th attached one (0: the first); when it is
unplugged the next attached pad takes over, if any.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from types import ModuleType
from typing import Any

from omnibot.teleop.config import TeleopConfig
from omnibot.teleop.mapping import JoyState, axes_tuple


def _load_pygame() -> ModuleType:
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    os.environ.setdefault("SDL_JOYSTICK_ALLOW_BACKGROUND_EVENTS", "1")
    import pygame

    return pygame


class JoystickSource:
    """Pads through pygame; ``backend`` stands in for the pygame module in tests."""

    name = "joystick"
    quit = False
    """A pad has no quit key (Ctrl-C in the terminal ends teleop)."""

    def __init__(
        self,
        config: TeleopConfig,
        *,
        on_message: Callable[[str], None] = print,
        backend: Any = None,
    ) -> None:
        self.config = config
        self.on_message = on_message
        self.pg = backend if backend is not None else _load_pygame()
        self.pg.display.init()  # SDL's event queue lives in the video subsystem (dummy driver)
        self.pg.joystick.init()
        self._pads: dict[int, Any] = {}  # instance id -> Joystick, in attach order
        self._active: int | None = None
        for index in range(self.pg.joystick.get_count()):
            self._attach(index)

    @property
    def attached(self) -> bool:
        """True while a pad is attached and read."""
        return self._active is not None

    def read(self, now: float) -> JoyState | None:
        """The active pad's state (ROS joy convention), None if no pad is attached."""
        pg = self.pg
        for event in pg.event.get():
            if event.type == pg.JOYDEVICEADDED:
                self._attach(event.device_index)
            elif event.type == pg.JOYDEVICEREMOVED:
                self._detach(event.instance_id)
        if self._active is None:
            return None
        pad = self._pads[self._active]
        try:
            axes = [-pad.get_axis(i) for i in range(pad.get_numaxes())]
            for h in range(pad.get_numhats()):
                hx, hy = pad.get_hat(h)
                axes += [float(-hx), float(hy)]
            buttons = tuple(int(bool(pad.get_button(b))) for b in range(pad.get_numbuttons()))
        except pg.error as exc:  # unplugged between the event pump and the read
            self.on_message(f"joystick read failed ({exc}); treating it as unplugged")
            self._detach(self._active)
            return None
        return JoyState(axes_tuple(axes), buttons, now)

    def _attach(self, device_index: int) -> None:
        try:
            pad = self.pg.joystick.Joystick(device_index)
            pad.init()
        except self.pg.error as exc:
            self.on_message(f"joystick {device_index} could not be opened: {exc}")
            return
        iid = pad.get_instance_id()
        if iid in self._pads:
            return
        self._pads[iid] = pad
        self.on_message(
            f"joystick attached: {pad.get_name()} ({pad.get_numaxes()} axes, {pad.get_numbuttons()} buttons)"
        )
        self._choose()

    def _detach(self, instance_id: int) -> None:
        pad = self._pads.pop(instance_id, None)
        if pad is None:
            return
        self.on_message(f"joystick removed: {pad.get_name()}")
        if self._active == instance_id:
            self._active = None
        self._choose()

    def _choose(self) -> None:
        ids = list(self._pads)
        want = ids[self.config.device_id] if self.config.device_id < len(ids) else (ids[0] if ids else None)
        if want is None or want == self._active:
            return
        self._active = want
        pad = self._pads[want]
        self._check_buttons(pad)

    def _check_buttons(self, pad: Any) -> None:
        n, cfg = pad.get_numbuttons(), self.config
        if (
            cfg.require_enable_button
            and cfg.enable_button >= n
            and (cfg.turbo_button is None or cfg.turbo_button >= n)
        ):
            self.on_message(
                f"warning: {pad.get_name()} has {n} buttons (0..{n - 1}); enable_button {cfg.enable_button} "
                "does not exist, so it cannot drive: give a config file (--config) for this pad"
            )
        else:
            self.on_message(f"using {pad.get_name()}: hold button {cfg.enable_button} to drive")

    def close(self) -> None:
        """Release the pads and SDL's joystick and video subsystems."""
        for pad in self._pads.values():
            pad.quit()
        self._pads.clear()
        self._active = None
        self.pg.joystick.quit()
        self.pg.display.quit()
