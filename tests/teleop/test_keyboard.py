"""Keyboard teleop: key parsing, held keys with terminal auto-repeat, and a real terminal (a pty)."""

from __future__ import annotations

import os
import termios
from collections.abc import Iterator

import pytest

from omnibot.errors import ConfigError
from omnibot.motion import Twist
from omnibot.teleop.config import TeleopConfig
from omnibot.teleop.keyboard import Key, KeyboardSource, KeyState, parse_keys
from omnibot.teleop.mapping import joy_to_command

CONFIG = TeleopConfig()


def test_parse_keys() -> None:
    assert parse_keys(b"wA\x1b[D \x03z") == [
        Key("x", 1),
        Key("y", 1, turbo=True),
        Key("yaw", 1),
        Key(stop=True),
        Key(quit=True),
    ]
    assert parse_keys(b"\x1b[B\x1b[C") == [Key("x", -1), Key("yaw", -1)]


def twist(state: KeyState, now: float) -> tuple[Twist, bool]:
    cmd = joy_to_command(CONFIG, state.joy(now))
    return cmd.twist, cmd.enabled


def test_keys_drive_through_the_pad_mapping() -> None:
    state = KeyState(CONFIG)
    state.press(Key("x", 1), 0.0)
    t, enabled = twist(state, 0.1)
    assert enabled and t == Twist(3.5, 0.0, 0.0)  # seed 003's scale: forward, whatever the axis' sign
    state.press(Key("yaw", -1, turbo=True), 0.1)
    t, _ = twist(state, 0.2)
    assert t == Twist(50.0, 0.0, -50.0)  # turbo button held: the turbo scales
    state.press(Key(stop=True), 0.2)
    assert twist(state, 0.2) == (Twist(), False)


def test_a_held_key_lasts_through_the_repeat_delay_and_ends_soon_after_release() -> None:
    state = KeyState(CONFIG, hold_first=0.6, hold_repeat=0.15)
    state.press(Key("x", 1), 0.0)
    assert twist(state, 0.55)[1]  # the terminal's repeat delay: still held
    for i in range(10):  # auto-repeat every 33 ms from 0.5 s
        state.press(Key("x", 1), 0.5 + 0.033 * i)
    last = 0.5 + 0.033 * 9
    assert twist(state, last + 0.14)[1]
    assert not twist(state, last + 0.16)[1]  # let go: noticed within hold_repeat


@pytest.fixture
def terminal() -> Iterator[tuple[int, int]]:
    master, slave = os.openpty()
    try:
        yield master, slave
    finally:
        os.close(master)
        os.close(slave)


def test_reads_a_real_terminal_in_cbreak_mode_and_restores_it(terminal: tuple[int, int]) -> None:
    master, slave = terminal
    before = termios.tcgetattr(slave)
    with KeyboardSource(CONFIG, fd=slave) as source:
        assert not termios.tcgetattr(slave)[3] & termios.ICANON
        assert source.read(0.0).buttons[7] == 0
        os.write(master, b"w")
        joy = source.read(0.1)
        assert joy_to_command(CONFIG, joy).twist == Twist(3.5, 0.0, 0.0)
        os.write(master, b"\x04")
        source.read(0.2)
        assert source.quit
    assert termios.tcgetattr(slave) == before


def test_not_a_terminal(tmp_path) -> None:
    with open(tmp_path / "f", "w") as f, pytest.raises(ConfigError, match="needs a terminal"):
        KeyboardSource(CONFIG, fd=f.fileno())
