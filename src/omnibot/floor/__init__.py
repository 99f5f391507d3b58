"""The floor model: the surfaces (friction, the rollers' rolling losses on each material), the static
normal loads on the wheels and the friction laws' regularisation speeds.

One model for the two that need it: the simulator's physics (:mod:`omnibot.sim`) moves the robot on
it, and the planner's reach (:mod:`omnibot.control.reach`) asks how fast the motors can drive the
robot on it; neither imports the other. Plain numbers and numpy, nothing compiled.
"""

from omnibot.floor.contact import GRAVITY, ROLL_SPEED_EPS, WHEEL_SPEED_EPS, static_loads
from omnibot.floor.surfaces import SURFACES, Surface, get_surface

__all__ = [
    "GRAVITY",
    "ROLL_SPEED_EPS",
    "SURFACES",
    "WHEEL_SPEED_EPS",
    "Surface",
    "contact",
    "get_surface",
    "static_loads",
    "surfaces",
]
