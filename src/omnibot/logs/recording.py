"""A command's ``--log`` / ``--foxglove``: the recording its composition root opens and hands on.

Light on purpose (the recorder, MCAP and rosbags are imported only when a command records):
:func:`open_recording` makes a :class:`Recording`, which the command passes to each session it opens
(``recording=`` of :func:`omnibot.client.session.open_robot`, :func:`~omnibot.client.session.guarded`,
:func:`~omnibot.client.session.robot_session`: :meth:`Recording.attach`) and each runtime it runs
(``Runtime(recording=...)``: :meth:`Recording.attach_runtime` when it starts). Nothing here is
global: two recordings in one process record separately. Foxglove's Teleop panel
(:attr:`Recording.panel`) drives only a runtime its command adds it to.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, cast

from omnibot.errors import ConfigError
from omnibot.logs.topics import DEFAULT_ESTIMATOR

if TYPE_CHECKING:
    from omnibot.client import RobotClient
    from omnibot.logs.live import PanelSource
    from omnibot.logs.recorder import Recorder
    from omnibot.logs.sink import RuntimeRecorder
    from omnibot.logs.writer import Mirror
    from omnibot.robot import RobotDescription
    from omnibot.runtime import Runtime


FOXGLOVE_TOKEN_ENV = "OMNIBOT_FOXGLOVE_TOKEN"
"""What ``--foxglove-token`` defaults to (a token on the command line shows in ``ps``)."""


@dataclass(frozen=True)
class FoxgloveBind:
    """Where ``--foxglove`` serves: ``host``, ``port`` and the access ``token`` (None: none, loopback);
    ``made_up``: the token was made up (bound off loopback without one given)."""

    host: str
    port: int
    token: str | None = None
    made_up: bool = False

    @classmethod
    def parse(cls, address: str | int, token: str | None = None) -> FoxgloveBind:
        """``--foxglove [HOST:]PORT`` and ``--foxglove-token`` (default ``$OMNIBOT_FOXGLOVE_TOKEN``),
        checked: the dashboard's token rules (:func:`omnibot.web.access.access_token`)."""
        from omnibot.logs.live import parse_address
        from omnibot.web import access_token

        host, port = parse_address(address)
        given = token or os.environ.get(FOXGLOVE_TOKEN_ENV) or None
        required = access_token(host, given, key="--foxglove-token")
        return cls(host, port, required, made_up=given is None and required is not None)


class Recording:
    """A command's ``--log`` / ``--foxglove``: the file (and the live server) is made when the first
    client is attached (a command that fails before it talks to a robot leaves no file)."""

    def __init__(
        self,
        path: str | Path | None,
        estimator: str = DEFAULT_ESTIMATOR,
        foxglove: FoxgloveBind | None = None,
    ) -> None:
        self.path = Path(path) if path is not None else None
        self.estimator = estimator
        self.foxglove = foxglove
        self.recorder: Recorder | None = None
        self._runtimes: list[Runtime] = []
        self._sinks: list[RuntimeRecorder] = []

    def attach(self, client: RobotClient, robot: RobotDescription | None, guess: bool) -> None:
        """Record ``client`` (the file is made on the first attach, with the Foxglove mirror if asked);
        ``robot`` None with ``guess``: the preset its HELLO names."""
        if self.recorder is None:
            mirrors: list[Mirror] = []
            bind = self.foxglove
            if bind is not None:
                from omnibot.logs.live import FoxgloveLive

                live = FoxgloveLive(bind.port, host=bind.host, token=bind.token)
                print(f"omnibot: Foxglove live on {live.url}", file=sys.stderr)
                if bind.made_up:
                    print(
                        "  (an access token was made up because the server is reachable from other machines)",
                        file=sys.stderr,
                    )
                mirrors.append(live)
            try:
                from omnibot.logs.recorder import Recorder

                self.recorder = Recorder(self.path, estimator=self.estimator, mirrors=mirrors)
            except BaseException:
                for mirror in mirrors:
                    mirror.close()
                raise
        self.recorder.attach(client, robot, guess=guess)

    def attach_runtime(self, runtime: Runtime) -> None:
        """Record ``runtime``'s arbitration and estimate (once per runtime; nothing before a client
        was recorded)."""
        if self.recorder is None or any(r is runtime for r in self._runtimes):
            return
        from omnibot.logs.sink import RuntimeRecorder

        self._runtimes.append(runtime)
        sink = RuntimeRecorder(self.recorder, runtime)
        self._sinks.append(sink)
        runtime.add_sink(sink)

    @property
    def panel(self) -> PanelSource | None:
        """Foxglove's Teleop panel as a runtime source, with ``--foxglove`` once a client was recorded
        (the live server is made with the file); None otherwise."""
        if self.recorder is None:
            return None
        for mirror in self.recorder.mirrors:
            panel = getattr(mirror, "panel", None)  # a FoxgloveLive's Teleop panel
            if panel is not None:
                return cast("PanelSource", panel)
        return None

    def truth_rows(self, rows: Sequence[tuple[float, float, float, float]]) -> int:
        """Ground truth rows ``t, x, y, theta`` on the link's clock into the log
        (:meth:`Recorder.truth_rows`); the rows written, 0 before a client was recorded."""
        return self.recorder.truth_rows(rows) if self.recorder is not None else 0

    @property
    def failure(self) -> str | None:
        """Why the file stopped being written mid-run (a write failed), None while it is whole."""
        return self.recorder.failure if self.recorder is not None else None

    def close(self) -> None:
        """Close the recording's file (nothing when none was made)."""
        for sink in self._sinks:
            sink.close()
        if self.recorder is not None:
            self.recorder.close()


@contextlib.contextmanager
def open_recording(
    path: str | Path | None,
    *,
    estimator: str = DEFAULT_ESTIMATOR,
    foxglove: str | int | None = None,
    foxglove_token: str | None = None,
) -> Iterator[Recording | None]:
    """``--log FILE`` / ``--foxglove [HOST:]PORT`` (``--foxglove-token``): the command's recording,
    closed on the way out; None and None record nothing (None). The file must be writable and the
    address and token valid (checked at once, before any robot moves). The command hands it to the
    sessions it opens and the runtimes it runs (their ``recording`` parameter)."""
    if foxglove is None and foxglove_token is not None:
        raise ConfigError("--foxglove-token goes with --foxglove [HOST:]PORT", key="--foxglove-token")
    if path is None and foxglove is None:
        yield None
        return
    from omnibot.outputs import check_writable

    check_writable(path, "--log")
    bind = FoxgloveBind.parse(foxglove, foxglove_token) if foxglove is not None else None
    rec = Recording(path, estimator, bind)
    try:
        yield rec
    finally:
        rec.close()
