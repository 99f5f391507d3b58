"""``omnibot record`` and ``omnibot follow``: teach and repeat from the command line.

Both default to the simulated robot in lockstep (faster than real time, deterministic for a seed);
``--port URL`` drives any link instead (a real board, ``sim://...``, ``tcp://...``), the robot being
the one the controller names (:func:`omnibot.client.session.robot_on_link`). Either way the session
leaves the controller stopped and in the MODE it was found in (:mod:`omnibot.client.session`):
:func:`robot_client`, the robot both drive. Each command is its own module: :mod:`omnibot.apps.record`
and :mod:`omnibot.apps.follow`.

Errors in the input (a malformed path file, an unknown follower, bad numbers) are ConfigErrors: one
line, exit status 2. A run that did not do its job exits 1 with the reason: a recording shorter than
:data:`~omnibot.navigation.outcome.MIN_POINTS` points or :data:`~omnibot.navigation.outcome.MIN_LENGTH`
m, a follow run outside its tolerances (:class:`~omnibot.navigation.outcome.Tolerances`).
"""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Iterator
from typing import Any

from omnibot.cliargs import recording_of, seed_of, sim_robot, world_of


@contextlib.contextmanager
def robot_client(args: argparse.Namespace, start: Any = None) -> Iterator[tuple[Any, Any]]:
    """(client, robot): ``--port``'s robot (checked against ``--robot``), or the simulated ``--robot``
    in ``--world``: standing at the world's own start where it has one (``room``, ``corridor``), else
    at ``start`` (``follow``: the path's start), else at the origin; the controller is left as it was
    found on every way out."""
    from omnibot.client import guarded, robot_session
    from omnibot.navigation import simulated_client
    from omnibot.robot import load_robot

    recording = recording_of(args)
    if args.port:
        with robot_session(args.port, args.robot, recording=recording) as session:
            yield session.client, session.robot
        return
    from omnibot.cliargs import check_world
    from omnibot.sim import load_world

    check_world(args)
    robot = load_robot(sim_robot(args))
    world = world_of(args)
    if load_world(world).start is not None:
        start = None  # the world's start: a path is followed in its own frame from where the robot stands
    client = simulated_client(
        robot,
        surface=args.surface,
        seed=seed_of(args),
        start=start,
        world=None if world == "empty" else world,
    )
    with guarded(client, robot=robot, recording=recording):
        yield client, robot
