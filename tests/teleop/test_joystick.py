"""Joystick input: ROS joy convention, hot-plug, and pygame itself with no pad attached."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from omnibot.teleop.config import TeleopConfig
from omnibot.teleop.joystick import JoystickSource
from omnibot.teleop.mapping import joy_to_command

ADDED, REMOVED = 1541, 1542


class FakePad:
    def __init__(self, iid: int, axes: list[float], buttons: list[int], hats: list[tuple[int, int]]) -> None:
        self.iid, self.axes, self.buttons, self.hats = iid, axes, buttons, hats

    def init(self) -> None: ...
    def quit(self) -> None: ...
    def get_instance_id(self) -> int:
        return self.iid

    def get_name(self) -> str:
        return f"pad{self.iid}"

    def get_numaxes(self) -> int:
        return len(self.axes)

    def get_axis(self, i: int) -> float:
        return self.axes[i]

    def get_numhats(self) -> int:
        return len(self.hats)

    def get_hat(self, i: int) -> tuple[int, int]:
        return self.hats[i]

    def get_numbuttons(self) -> int:
        return len(self.buttons)

    def get_button(self, i: int) -> int:
        return self.buttons[i]


class FakePygame:
    """The few pygame calls the source makes; ``plug``/``unplug`` queue hot-plug events."""

    JOYDEVICEADDED, JOYDEVICEREMOVED = ADDED, REMOVED
    error = RuntimeError

    def __init__(self) -> None:
        self.devices: list[FakePad] = []
        self.queue: list[SimpleNamespace] = []
        self.display = SimpleNamespace(init=lambda: None, quit=lambda: None)
        self.joystick = SimpleNamespace(
            init=lambda: None, quit=lambda: None, get_count=lambda: 0, Joystick=lambda i: self.devices[i]
        )
        self.event = SimpleNamespace(get=self._events)

    def _events(self) -> list[SimpleNamespace]:
        out, self.queue = self.queue, []
        return out

    def plug(self, pad: FakePad) -> None:
        self.devices.append(pad)
        self.queue.append(SimpleNamespace(type=ADDED, device_index=len(self.devices) - 1))

    def unplug(self, pad: FakePad) -> None:
        self.devices.remove(pad)
        self.queue.append(SimpleNamespace(type=REMOVED, instance_id=pad.iid))


def test_hot_plug_and_ros_convention() -> None:
    pg, messages = FakePygame(), list[str]()
    source = JoystickSource(TeleopConfig(), on_message=messages.append, backend=pg)
    assert source.read(0.0) is None  # nothing attached: the deadman calls it lost
    buttons = [0] * 8
    buttons[7] = 1
    pad = FakePad(10, [0.0, 0.0, 0.0, -1.0], buttons, [(1, 1)])  # SDL: axis 3 pushed up
    pg.plug(pad)
    joy = source.read(0.1)
    assert joy is not None
    assert joy.axes == (0.0, 0.0, 0.0, 1.0, -1.0, 1.0)  # joy: up positive; hat right/up -> -1, +1
    assert joy_to_command(TeleopConfig(), joy).twist.vx == pytest.approx(-3.5)  # seed 003's sign
    assert any("attached: pad10" in m for m in messages)
    pg.unplug(pad)
    assert source.read(0.2) is None
    assert any("removed: pad10" in m for m in messages)
    source.close()


def test_warns_when_the_pad_lacks_the_enable_button() -> None:
    pg, messages = FakePygame(), list[str]()
    source = JoystickSource(TeleopConfig(), on_message=messages.append, backend=pg)
    pg.plug(FakePad(3, [0.0, 0.0], [0, 0, 0, 0], []))
    source.read(0.0)
    assert any("enable_button 7 does not exist" in m for m in messages)
    source.close()


def test_a_failed_read_counts_as_unplugged() -> None:
    pg, messages = FakePygame(), list[str]()
    source = JoystickSource(TeleopConfig(), on_message=messages.append, backend=pg)
    pad = FakePad(4, [0.0], [0] * 8, [])
    pg.plug(pad)
    assert source.read(0.0) is not None

    def broken(i: int) -> float:
        raise RuntimeError("device gone")

    pad.get_axis = broken  # type: ignore[method-assign]
    assert source.read(0.1) is None
    assert not source.attached
    source.close()


def test_real_pygame_without_a_pad(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    source = JoystickSource(TeleopConfig(), on_message=lambda m: None)
    try:
        assert source.read(0.0) is None
        assert not source.attached
    finally:
        source.close()
