"""Floor surfaces for the simulator and the planner: friction of the rubber rollers and their rolling losses.

Each surface gives, for the contact of an omni/mecanum wheel with the floor:

* ``mu``: Coulomb friction coefficient along the wheel's traction direction (rubber roller on the floor);
* ``slip_velocity``: regularisation velocity v_eps of the friction law F = -mu N tanh(slip / v_eps)
  (the slip at which 76 % of mu N is developed; it stands for the compliance of the rubber and,
  on carpet, of the pile);
* ``rolling_multiplier``: factor on the wheel's own ``RollerSpec.rolling_resistance`` (measured or
  assumed on a hard, smooth floor), so that the same wheel loses more on a soft floor.

Seed 000 found that the floor makes "a difference up to 20 %" in the distance of the same powered
motion (its two reference floors, wood and carpet). In the simulator that comes out of the carpet's
rolling multiplier (the unpowered wheels' rollers roll across the path, and every roller of a
diagonal course) rather than from a lookup, and the multiplier is fitted to that statement: at 1.8x
wood's roller resistance seed 000's series (1000 ms from rest) go 4-15 % less far on carpet on a
motor axis from 70 counts and 7-18 % at 45 degrees from 80 counts (most near the start, where the
drag is the larger share of the motors' torque; ``benchmarks/seed000_figures.py``,
``tests/sim/test_realism.py``). Castor and wheelchair measurements give small hard wheels on low
pile 3-6x a hard floor's rolling resistance; seed 000's rubber rollers, wider and softer than a
castor, lose less, and a multiplier of 4 made its carpet 2-3x shorter than wood near the start.
"""

from __future__ import annotations

from dataclasses import dataclass

from omnibot.config_errors import suggest
from omnibot.errors import ConfigError


@dataclass(frozen=True)
class Surface:
    """One floor material (see the module docstring for the meaning of each number)."""

    name: str
    mu: float
    slip_velocity: float
    rolling_multiplier: float
    source: str = ""

    def __post_init__(self) -> None:
        if self.mu < 0 or self.slip_velocity <= 0 or self.rolling_multiplier < 0:
            raise ConfigError(
                f"surface '{self.name}' needs mu >= 0, slip_velocity > 0 and rolling_multiplier >= 0"
            )


SURFACES: dict[str, Surface] = {
    s.name: s
    for s in (
        Surface(
            "wood",
            mu=0.60,
            slip_velocity=0.02,
            rolling_multiplier=1.0,
            source="rubber on varnished/painted wood 0.4-0.7 (friction tables); seed 002 saw slip on "
            "painted plywood; the reference floor for RollerSpec.rolling_resistance",
        ),
        Surface(
            "linoleum",
            mu=0.55,
            slip_velocity=0.02,
            rolling_multiplier=1.0,
            source="rubber on dry linoleum/vinyl 0.4-0.6 (floor slip-resistance tests); hard and smooth "
            "like wood, so the same rolling losses",
        ),
        Surface(
            "concrete",
            mu=0.80,
            slip_velocity=0.02,
            rolling_multiplier=1.3,
            source="rubber on dry sealed concrete 0.6-0.85 (friction tables); its roughness adds some "
            "roller losses",
        ),
        Surface(
            "carpet",
            mu=0.60,
            slip_velocity=0.04,
            rolling_multiplier=1.8,
            source="the roller resistance fitted to seed 000's 'up to 20 %' between its wood and carpet "
            "(small hard castors on low pile roll with 3-6x a hard floor's resistance; the seed's "
            "rubber rollers lose less); the pile is compliant, so a larger slip velocity",
        ),
    )
}


def get_surface(surface: str | Surface) -> Surface:
    """A :class:`Surface` by name (``wood``, ``carpet``, ``concrete``, ``linoleum``) or as given."""
    if isinstance(surface, Surface):
        return surface
    try:
        return SURFACES[surface]
    except KeyError:
        raise ConfigError(suggest(f"unknown surface '{surface}'", surface, SURFACES)) from None
