"""Teleoperation: a pad or the keyboard drives the robot through VEL, with a deadman (docs/teleop.md).

::

    joystick (pygame, hot-plug) | keyboard (terminal) | browser (omnibot.web)
      -> JoyState (ROS joy convention)            mapping.py    pure
      -> joy_to_command(config) -> limit_twist()  mapping.py    pure, seed 003's parameters (config.py)
      -> Deadman.update()                         deadman.py    pure: drive / repeated zero / silent
      -> PadSource, DeadmanSource                 sources.py    a person's sources of omnibot.runtime:
                                                                arbitrated, sent as VEL (vel_timeout),
                                                                paced in real time (pacing.py)

Modules: ``config`` (TeleopConfig, YAML), ``mapping`` (JoyState, deadzone, limits; ``Twist`` is
:mod:`omnibot.motion`'s), ``deadman`` (when to stop), ``sources`` (the runtime's sources a person
drives: the pad, the keyboard, the page's stick; the ramp at the robot's accelerations), ``pacing``
(real time on sim:// and real links), ``joystick`` (pygame), ``keyboard`` (terminal). The loop that
drives a runtime with them (Teleop) and the command (``omnibot teleop``) are
:mod:`omnibot.apps.teleop_loop` and :mod:`omnibot.apps.teleop`. The runtime imports nothing of this
package: its people's sources are here, on top of it.
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.motion import ZERO, Twist
    from omnibot.teleop.config import TeleopConfig, load_teleop_config, parse_teleop_config
    from omnibot.teleop.deadman import Action, Deadman, Phase, Sample, Why
    from omnibot.teleop.mapping import (
        JoyState,
        TeleopCommand,
        TwistLimits,
        TwistRamp,
        axes_tuple,
        deadzone,
        fractions_to_twist,
        joy_to_command,
        limit_twist,
    )
    from omnibot.teleop.pacing import Pacer
    from omnibot.teleop.sources import DeadmanSource, JoySource, PadSource, RampedTwist

_EXPORTS = {
    "config": ("TeleopConfig", "load_teleop_config", "parse_teleop_config"),
    "deadman": ("Action", "Deadman", "Phase", "Sample", "Why"),
    "mapping": (
        "ZERO",
        "JoyState",
        "TeleopCommand",
        "Twist",
        "TwistLimits",
        "TwistRamp",
        "axes_tuple",
        "deadzone",
        "fractions_to_twist",
        "joy_to_command",
        "limit_twist",
    ),
    "pacing": ("Pacer",),
    "sources": ("DeadmanSource", "JoySource", "PadSource", "RampedTwist"),
}

__all__ = [
    "ZERO",
    "Action",
    "Deadman",
    "DeadmanSource",
    "JoySource",
    "JoyState",
    "Pacer",
    "PadSource",
    "Phase",
    "RampedTwist",
    "Sample",
    "TeleopCommand",
    "TeleopConfig",
    "Twist",
    "TwistLimits",
    "TwistRamp",
    "Why",
    "axes_tuple",
    "config",
    "deadman",
    "deadzone",
    "fractions_to_twist",
    "joy_to_command",
    "joystick",
    "keyboard",
    "limit_twist",
    "load_teleop_config",
    "mapping",
    "pacing",
    "parse_teleop_config",
    "sources",
]

# on first use: ``omnibot teleop``'s argument parser (built for every ``omnibot`` command) imports
# this package and must not pay for the client and models
if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
