"""Teleoperation: a pad or the keyboard drives the robot through VEL, with a deadman (docs/teleop.md).

::

    joystick (pygame, hot-plug) | keyboard (terminal) | browser (omnibot.web)
      -> JoyState (ROS joy convention)            mapping.py    pure
      -> joy_to_command(config) -> limit_twist()  mapping.py    pure, seed 003's parameters (config.py)
      -> Deadman.update()                         deadman.py    pure: drive / repeated zero / silent
      -> client.vel(..., vel_timeout)             loop.py       paced in real time (pacing.py)

Modules: ``config`` (TeleopConfig, YAML), ``mapping`` (JoyState, Twist, deadzone, limits),
``deadman`` (when to stop), ``pacing`` (real time on sim:// and real links), ``loop`` (Teleop),
``joystick`` (pygame), ``keyboard`` (terminal), ``simlink`` (the simulator behind a link),
``command`` (``omnibot teleop``).
"""

from omnibot.teleop.config import TeleopConfig, load_teleop_config, parse_teleop_config
from omnibot.teleop.deadman import Action, Deadman, Sample, Why
from omnibot.teleop.mapping import (
    ZERO,
    JoyState,
    TeleopCommand,
    Twist,
    TwistLimits,
    deadzone,
    fractions_to_twist,
    joy_to_command,
    limit_twist,
)
from omnibot.teleop.pacing import Pacer

__all__ = [
    "ZERO",
    "Action",
    "Deadman",
    "JoyState",
    "Pacer",
    "Sample",
    "TeleopCommand",
    "TeleopConfig",
    "Twist",
    "TwistLimits",
    "Why",
    "deadzone",
    "fractions_to_twist",
    "joy_to_command",
    "limit_twist",
    "load_teleop_config",
    "parse_teleop_config",
]
