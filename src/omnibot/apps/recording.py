"""The recording a command hands to the sessions it opens and the runtimes it runs.

:func:`omnibot.cli.main` opens it around the command from ``--log FILE`` / ``--foxglove [HOST:]PORT``
and puts it on the command's arguments (``args.recording``, read with
:func:`omnibot.cliargs.recording_of`); the command passes it on as the ``recording`` of
:func:`~omnibot.client.session.robot_session` (and ``open_robot``, ``guarded``) and of
:class:`~omnibot.runtime.runtime.Runtime` (through the libraries that build one: the navigator, the
dashboard, ``goto``, ``calibrate``). Nothing else records: a session or a runtime given no recording
is not recorded.

With ``--foxglove`` the user asked to drive from Foxglove too: Foxglove's Teleop panel
(:class:`omnibot.logs.live.PanelSource`, priority 30: over a follower, under a person) becomes a
source of every runtime the command records, here and nowhere else.
"""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from omnibot.client import RobotClient
    from omnibot.logs import Recorder, Recording
    from omnibot.robot import RobotDescription
    from omnibot.runtime import Runtime


class CommandRecording:
    """A command's ``recording``: ``recording`` records its clients and runtimes; with
    ``panel_drives`` Foxglove's Teleop panel is added to each runtime as a source."""

    def __init__(self, recording: Recording, *, panel_drives: bool) -> None:
        self.recording = recording
        self.panel_drives = panel_drives

    @property
    def recorder(self) -> Recorder | None:
        """The MCAP recorder (None until a client was recorded)."""
        return self.recording.recorder

    @property
    def failure(self) -> str | None:
        """Why the file stopped being written mid-run, None while it is whole."""
        return self.recording.failure

    def attach(self, client: RobotClient, robot: RobotDescription | None, guess: bool) -> None:
        """Record ``client`` (see :meth:`Recording.attach <omnibot.logs.recording.Recording.attach>`)."""
        self.recording.attach(client, robot, guess)

    def truth_rows(self, rows: Sequence[tuple[float, float, float, float]]) -> int:
        """Ground truth rows on the link's clock into the log (see :meth:`Recording.truth_rows
        <omnibot.logs.recording.Recording.truth_rows>`)."""
        return self.recording.truth_rows(rows)

    def attach_runtime(self, runtime: Runtime) -> None:
        """Record ``runtime`` and, with ``--foxglove``, let Foxglove's Teleop panel drive it."""
        self.recording.attach_runtime(runtime)
        panel = self.recording.panel if self.panel_drives else None
        if panel is not None and panel.name not in runtime.sources:
            runtime.add_source(panel)


@contextlib.contextmanager
def command_recording(args: argparse.Namespace) -> Iterator[CommandRecording | None]:
    """The recording ``args`` asks for (``--log``, ``--foxglove``, ``--foxglove-token``; None: none),
    closed on the way out."""
    from omnibot.logs import open_recording  # here: ``omnibot --help`` loads nothing of logs

    with open_recording(
        getattr(args, "log", None),
        foxglove=getattr(args, "foxglove", None),
        foxglove_token=getattr(args, "foxglove_token", None),
    ) as rec:
        yield None if rec is None else CommandRecording(rec, panel_drives=rec.foxglove is not None)
