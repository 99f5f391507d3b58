"""The ``sim://`` link scheme: the simulated controller in-process, alone or as a robot of a fleet.

Importing this module registers the scheme (:data:`omnibot.transport.url.SCHEME_PROVIDERS` names
it, so ``open_link("sim://...")`` imports it on first use)::

    sim://PRESET_OR_FILE?seed=0&surface=wood&world=empty&baud=115200&pose=X,Y,THETA
    sim://PRESET_OR_FILE?fleet=NAME&name=r1&pose=X,Y,THETA&seed=1...

* alone: a :class:`~omnibot.transport.lockstep.LockstepLink` to a :class:`SimDevice`;
* ``fleet=NAME``: a :class:`~omnibot.sim.fleet_link.FleetLink`; the links of one process with the
  same fleet share one world and one simulated clock (``name`` names the robot, ``r1``, ``r2``... by
  default; ``world`` and ``surface``, where given, must be the fleet's).

``pose=X,Y,THETA`` (m, m, degrees, as a world file's ``start``) puts the robot there instead of the
world's start.
"""

from __future__ import annotations

from omnibot.errors import ConfigError, SimulationError
from omnibot.sim.device import SimDevice
from omnibot.sim.fleet_link import join_fleet, parse_pose
from omnibot.transport import DEFAULT_BAUD, Link, LinkUrl, LockstepLink, register_scheme

OPTIONS = ("seed", "surface", "world", "baud", "pose", "fleet", "name")


def open_sim(u: LinkUrl) -> Link:
    """Open the ``sim://`` layer ``u``: one simulated robot, or one robot of a fleet."""
    if not u.target:
        raise ConfigError("sim:// needs a robot: sim://omni4, sim://omni3, sim://mecanum4 or sim://FILE.yaml")
    seed = u.get_int("seed", 0, minimum=0)
    baud = u.get_int("baud", DEFAULT_BAUD, minimum=0)
    surface = u.get_str("surface", "") or None
    world = u.get_str("world", "") or None
    pose_text = u.get_str("pose", "")
    pose = parse_pose(pose_text, u.source) if pose_text else None
    fleet = u.get_str("fleet", "")
    name = u.get_str("name", "")
    if "fleet" in u.options and not fleet:
        raise ConfigError(
            f"fleet= needs a name in URL {u.source!r} (sim://omni4?fleet=lab&name=r1)", key="fleet"
        )
    if name and not fleet:
        raise ConfigError(
            f"name= names a robot of a fleet: add fleet=NAME in URL {u.source!r} (sim://omni4?fleet=lab&name={name})",
            key="name",
        )
    if fleet:
        return join_fleet(
            fleet,
            u.target,
            name=name,
            seed=seed,
            pose=pose,
            world=world,
            surface=surface,
            baud=baud,
            url=u.url,
        )
    try:
        device = SimDevice(
            u.target,
            surface=surface,
            world=world,
            seed=seed,
            start_pose=None if pose is None else (pose.x, pose.y, pose.theta),
        )
    except SimulationError as exc:
        if pose is None:
            raise
        raise ConfigError(f"{exc} (pose={pose_text} in URL {u.source!r})", key="pose") from None
    return LockstepLink(device, baud=baud, url=u.url)


register_scheme(
    "sim",
    open_sim,
    options=OPTIONS,
    help="sim://PRESET?seed=N&surface=NAME&world=NAME&pose=X,Y,THETA&fleet=NAME&name=R&baud=115200: "
    "in-process lockstep simulator (robots of one fleet share a world and a clock)",
)
