"""The dashboard: the robot link thread and the web server thread, started and stopped together.

::

    with Dashboard("sim://omni4?world=room", http_port=0) as dash:   # 0: an ephemeral port
        print(dash.url)                                              # http://127.0.0.1:PORT/
        ...                                                          # dash.hub.latest: newest state

Threads: ``omnibot-robot-link`` owns the client (:class:`~omnibot.web.link.RobotLink`);
``omnibot-web`` runs uvicorn with its own event loop. Everything that can fail on bad input (the
link URL, the robot, the world, the path, binding the port, a missing token) fails in the
constructor, before any thread starts, with an :class:`~omnibot.errors.OmnibotError`.

A planned path read from a file (:class:`~omnibot.web.scene.PlannedPath`) is drawn from the robot's
pose at the start, as ``omnibot follow`` would drive it from there; a list of points is drawn as
given, in the frame of the pose the page shows.

Binding: 127.0.0.1 by default. Bound to any other address the dashboard requires an access token:
the one given, or a fresh random one (printed in :attr:`Dashboard.url`). Requests are answered only
when their ``Host`` names this server (:class:`~omnibot.web.access.HostPolicy`: the loopback names,
the bound address, the names in ``allow_hosts``), which defeats DNS rebinding.
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Self

import uvicorn

from omnibot.client import RobotClient, open_robot
from omnibot.errors import ConfigError, OmnibotError
from omnibot.estimation import SlipModel
from omnibot.robot import RobotDescription
from omnibot.runtime import Recording
from omnibot.sim import World, load_world
from omnibot.teleop import TeleopConfig
from omnibot.transport import find_device
from omnibot.web.access import HostCheck, HostPolicy, access_token, listening_socket
from omnibot.web.link import RobotLink
from omnibot.web.messages import MAX_FRAME
from omnibot.web.scene import PlannedPath, Point, build_scene
from omnibot.web.server import Hub, create_app
from omnibot.web.teach import TeachRepeat

if TYPE_CHECKING:
    from omnibot.sim import SimDevice


def bind(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port`` (0: any free port), or a ConfigError saying why not."""
    if not 0 <= port <= 65535:
        raise ConfigError(f"expected a port 0..65535, got {port}", key="--http-port")
    return listening_socket(host, port, host_key="--host", port_key="--http-port", backlog=64)


def _world_of(world: World | str | Path | None, device: SimDevice | None) -> World | None:
    """The room drawn: ``world`` (a world or the file or name of one), else the simulator's own."""
    if world is not None:
        return world if isinstance(world, World) else load_world(world)
    return device.sim.world if device is not None else None


def _server(app: HostCheck) -> uvicorn.Server:
    """The HTTP and WebSocket server of ``app``: quiet (warnings only, no access log, the
    application's logging left alone), frames up to 4 of the hub's, 2 s to shut down gracefully."""
    return uvicorn.Server(
        uvicorn.Config(
            app,
            log_level="warning",
            log_config=None,  # leave the application's logging alone
            access_log=False,
            lifespan="on",
            ws_max_size=MAX_FRAME * 4,
            timeout_graceful_shutdown=2,
        )
    )


class Dashboard:
    """Serves the dashboard for the robot at ``port_url`` (see the module docstring)."""

    def __init__(
        self,
        port_url: str,
        robot: RobotDescription | str | None = None,
        *,
        host: str = "127.0.0.1",
        http_port: int = 8080,
        token: str | None = None,
        world: World | str | Path | None = None,
        path: PlannedPath | Sequence[Point] | None = None,
        config: TeleopConfig | None = None,
        teach: TeachRepeat | None = None,
        allow_hosts: Sequence[str] = (),
        make_teach: Callable[[RobotDescription], TeachRepeat] | None = None,
        wheel_loop: bool = True,
        floor: Callable[[RobotClient, RobotDescription], SlipModel | None] | None = None,
        recording: Recording | None = None,
        surface: str | None = None,
    ) -> None:
        """``robot`` (a description, preset or file; None: the one the controller names) must be the
        robot on the link; ``make_teach`` builds ``teach`` once the robot is known; ``wheel_loop``:
        the runtime closes the controller's wheel-speed loop (False: open loop); ``floor`` applies a
        floor's calibration once the robot is known (uploads its tables) and gives its wheel slip,
        which the runtime asks the wheels for on top of each twist; ``recording`` (``--log``) records
        the client and the runtime; ``surface``, the floor's name when known (``--surface``), keeps
        the stick's ramp within its grip."""
        self.token = token = access_token(host, token)
        self.host = host
        HostPolicy.for_bind(host, 1, allow_hosts)  # a bad name fails here, before anything opens
        session = open_robot(port_url, robot, timeout=0.5, recording=recording)
        client, description = session.client, session.robot
        try:
            mode = client.status().mode
            if make_teach is not None:
                teach = make_teach(description)
            device = find_device(client.link)
            the_world = _world_of(world, device)
            # on a link without truth, odometry starts at the map's start pose (where the robot is put)
            start = the_world.start if device is None and the_world is not None else None
            self.link = RobotLink(
                client,
                description,
                config,
                teach=teach,
                start=start,
                mode=mode,
                wheel_loop=wheel_loop,
                slip=floor(client, description) if floor is not None else None,
                recording=recording,
                surface=surface,
            )
            # a path file is drawn where following it from here would drive it; points as given
            points = path.placed(self.link.pose) if isinstance(path, PlannedPath) else path
            self.scene = build_scene(description, the_world, points)
            self.scene["teach"] = teach is not None
            self._sock = bind(host, http_port)
        except BaseException:
            client.close()
            raise
        self._make_app(host, allow_hosts)

    def _make_app(self, host: str, allow_hosts: Sequence[str]) -> None:
        """The page's hub and app, served on the bound socket behind the host check (``allow_hosts``
        and the address ``host`` resolved to)."""
        self.port = int(self._sock.getsockname()[1])
        self.hub = Hub(self.scene, self.link.outbox, self.link.submit)
        self.app = create_app(self.hub, self.token)
        bound = str(self._sock.getsockname()[0])  # the address a name given to --host resolved to
        self.host_check = HostCheck(self.app, HostPolicy.for_bind(host, self.port, [*allow_hosts, bound]))
        self._server = _server(self.host_check)
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        """The page's address (with ``?token=`` when one is required)."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        query = f"?token={self.token}" if self.token else ""
        return f"http://{host}:{self.port}/{query}"

    def start(self, timeout: float = 10.0) -> None:
        """Start the link and the server; returns once the server accepts connections."""
        self.link.start()
        self._thread = threading.Thread(
            target=self._server.run, kwargs={"sockets": [self._sock]}, name="omnibot-web", daemon=True
        )
        self._thread.start()
        deadline = time.monotonic() + timeout
        while not self._server.started:
            if not self._thread.is_alive() or time.monotonic() > deadline:
                self.stop()
                raise OmnibotError("the dashboard's web server did not start")
            time.sleep(0.01)

    def stop(self) -> None:
        """Stop the server, then the link (the robot gets STOP); idempotent."""
        self._server.should_exit = True
        if self._thread is not None:
            self._thread.join(10.0)
            self._thread = None
        with contextlib.suppress(OSError):
            self._sock.close()
        self.link.stop()

    def __enter__(self) -> Self:
        self.start()
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.stop()
