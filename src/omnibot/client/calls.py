"""Typed calls in SI: each builds one checked command and hands it to ``execute`` (DESIGN habit 7).

:class:`TypedCalls` is mixed into :class:`~omnibot.client.client.RobotClient`, which provides
``execute``, ``submit``, ``limits`` and the known MODE bits; conversions and checks are in
:mod:`omnibot.client.commands`.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any, TypeVar

from omnibot.client import commands
from omnibot.client.errors import CalibrationRejected
from omnibot.client.limits import Limits
from omnibot.client.views import Hello, Status
from omnibot.estimation import SlipParameters
from omnibot.protocol import codes
from omnibot.protocol.messages import (
    Cal,
    Command,
    Delta,
    HelloReply,
    Mode,
    Move,
    Power,
    Reply,
    Rotate,
    Sonar,
    StatusReply,
    Stop,
    Telem,
    Vel,
)
from omnibot.protocol.messages import Hello as HelloCommand
from omnibot.protocol.messages import Status as StatusCommand
from omnibot.robot import CalibrationSpec

C = TypeVar("C", bound=Command)
log = logging.getLogger("omnibot.client")
UPLOAD_LINE_TIME = 0.02
"""s a pipelined calibration line may take on the link, at most (a CAL line: 2 ms at 115200 baud, 20
ms at 9600)."""


class TypedCalls:
    """move, rotate, delta, power, vel, stop, mode, sonar, telemetry, cal, status, hello."""

    limits: Limits
    timeout: float
    last_hello: Hello | None
    takes_reach: bool | None = None
    """Whether the controller took the calibrated reach at the last upload (None: none uploaded yet)."""

    @property
    def mode_bits(self) -> int | None:
        """The MODE bits last set or reported by STATUS, None if not known (the client implements it)."""
        raise NotImplementedError

    def execute(self, command: Command, timeout: float | None = None) -> Reply:
        """Send ``command`` and wait for its reply (the client implements it)."""
        raise NotImplementedError

    def submit(self, command: Command, timeout: float | None = None) -> Any:
        """Send ``command`` and return a handle on its future reply (the client implements it)."""
        raise NotImplementedError

    def move(self, distance: float, speed: float, course: float = 0.0, curvature: float = 0.0) -> Move:
        """MOVE ``distance`` m (math.inf: until the next command) at ``speed`` m/s on ``course``
        rad from the head, bending with ``curvature`` 1/m. Returns the command sent."""
        return self._run(commands.move(self.limits, distance, speed, course, curvature))

    def rotate(self, angle: float, rate: float) -> Rotate:
        """ROTATE by ``angle`` rad (math.inf: until the next command) at ``rate`` rad/s."""
        return self._run(commands.rotate(self.limits, angle, rate))

    def delta(
        self,
        distance: float = 0.0,
        speed: float = 0.0,
        course: float = 0.0,
        curvature: float = 0.0,
        repeat: float = 0,
    ) -> Delta:
        """DELTA: runs the remembered MOVE plus these increments max(repeat, 1) times (``repeat``
        an int, or math.inf: until the next command)."""
        return self._run(commands.delta(self.limits, distance, speed, course, curvature, repeat))

    def power(self, time: float, powers: Sequence[int]) -> Power:
        """POWER: raw PWM counts, one per motor, for ``time`` s (no calibration)."""
        return self._run(commands.power(self.limits, time, powers))

    def vel(
        self,
        vx: float,
        vy: float,
        w: float,
        timeout: float,
        accel: float = 0.0,
        body_accel: tuple[float, float, float] | None = None,
    ) -> Vel:
        """VEL: hold (vx, vy) m/s and w rad/s for at most ``timeout`` s unless refreshed; ``accel``
        the planned rate of change of the speed (m/s^2; :attr:`takes_vel_accel` must be true), or
        ``body_accel`` the body's planned acceleration (m/s^2 along its x and y axes, rad/s^2;
        :attr:`takes_vel_body_accel` must be true)."""
        if accel and not self.takes_vel_accel:
            raise ValueError(
                "VEL accel: the controller does not take VEL's acceleration (protocol version "
                f"{codes.VEL_ACCEL_VERSION}; check client.takes_vel_accel)"
            )
        if body_accel is not None and not self.takes_vel_body_accel:
            raise ValueError(
                "VEL body_accel: the controller does not take VEL's body acceleration (protocol "
                f"version {codes.VEL_BODY_ACCEL_VERSION}; check client.takes_vel_body_accel)"
            )
        return self._run(commands.vel(self.limits, vx, vy, w, timeout, accel, body_accel))

    @property
    def takes_vel_accel(self) -> bool:
        """The controller's last HELLO reply agreed on protocol version 3 or later: VEL may carry the
        planned acceleration (the client lists its versions when it greets the controller; a reset
        greeting says 2, so after a reset the client sends none until it asks again)."""
        return self.last_hello is not None and self.last_hello.version >= codes.VEL_ACCEL_VERSION

    @property
    def takes_vel_body_accel(self) -> bool:
        """The controller's last HELLO reply agreed on protocol version 4 or later: VEL may carry the
        body's planned acceleration (AX, AY, AW), as :attr:`takes_vel_accel` for version 3."""
        return self.last_hello is not None and self.last_hello.version >= codes.VEL_BODY_ACCEL_VERSION

    def stop(self) -> Stop:
        """STOP: motors off, queue cleared, remembered MOVE reset, emergency-stop latch released."""
        return self._run(Stop())

    def mode(
        self, mask: int | None = None, *, simulation: bool | None = None, closed_loop: bool | None = None
    ) -> Mode:
        """MODE: a whole mask, or change single bits of the current one (read by STATUS if not known)."""
        if mask is None:
            mask = self.mode_bits if self.mode_bits is not None else self.status().mode
            for bit, on in ((codes.MODE_SIMULATION, simulation), (codes.MODE_CLOSED_LOOP, closed_loop)):
                if on is not None:
                    mask = mask | bit if on else mask & ~bit
            mask &= ~codes.MODE_BINARY
        return self._run(commands.mode(self.limits, mask))

    def sonar(
        self, number: int, period: float, low: float = 0.0, high: float = 0.0, stop: float = 0.0
    ) -> Sonar:
        """SONAR ``number`` (1..k) every ``period`` s (0: off); RANGE band [low, high] m; e-stop
        below ``stop`` m while moving (0: off)."""
        return self._run(commands.sonar(self.limits, number, period, low, high, stop))

    def telemetry(self, period: float, mask: int = codes.TEL_MASK) -> Telem:
        """TELEM: a TEL sample every ``period`` s (0: off) with the groups of ``mask``."""
        return self._run(commands.telem(self.limits, period, mask))

    def cal(self, table: int, index: int, x: int, y: int) -> Cal:
        """CAL with protocol integers (one knot; docs/protocol.md)."""
        return self._run(commands.cal(self.limits, table, index, x, y))

    def upload_calibration(self, spec: CalibrationSpec) -> list[Cal]:
        """Upload a calibration section (K, K_t, K_r, K_l, motor map, roller drag, reach) with CAL
        commands; the commands sent. A controller that does not know the reach (CAL table 8: older
        firmware, the UNO's) takes the rest, and :attr:`takes_reach` says so (False)."""
        sent = commands.calibration(spec, self.limits.motors)
        # pipelined: the i-th reply comes after i lines on the link, so each gets that much longer
        # than the client's own timeout (a person's 0.25 s would time a table's last lines out)
        pipelined = [(c, self.submit(c, self.timeout + UPLOAD_LINE_TIME * i)) for i, c in enumerate(sent)]
        for command, pending in pipelined:
            try:
                pending.result()
                if command.table == codes.CAL_REACH:
                    self.takes_reach = True
            except CalibrationRejected as e:
                if command.table == codes.CAL_REACH:
                    if command.index == 0:  # said once: the controller clamps no MOVE to a reach
                        self.takes_reach = False
                        if spec.reach is not None:
                            log.warning(
                                "the controller does not know the calibrated reach (CAL table 8): "
                                "MOVEs faster than it run as asked and may fall short"
                            )
                    continue
                if command.table != codes.CAL_SPEED:
                    raise
                if command.y != 0:  # a controller older than the motor map's speed term
                    raise CalibrationRejected(
                        e.code,
                        "the controller does not know the motor map's speed terms (CAL table 7): "
                        "update its firmware, or use a calibration without them",
                    ) from None
                # a zero speed term is what such a controller already does
        return sent

    def upload_slip(self, params: SlipParameters) -> bool:
        """Upload the floor's wheel creep (CAL table 9), which a closed-loop MOVE's landing takes out
        of its encoders (docs/firmware.md); False when the controller does not know the table (older
        firmware, the UNO's, which lands nothing: its MOVEs are timed). A controller older than the
        ramp term (index 3) takes a zero one as it is and refuses any other, saying so."""
        for command in commands.slip(params):
            try:
                self.execute(command)
            except CalibrationRejected as e:
                if command.index == 0:
                    log.warning("the controller does not know the floor's creep (CAL table 9): not uploaded")
                    return False
                if command.index != 3 or command.y != 0:
                    raise CalibrationRejected(
                        e.code,
                        "the controller does not know the creep under a ramp (CAL table 9, index 3): "
                        "update its firmware, or use a calibration without it",
                    ) from None
                # no ramp term is what such a controller already does
        return True

    def status(self) -> Status:
        """STATUS as a :class:`Status` (SI)."""
        reply = self.execute(StatusCommand())
        assert isinstance(reply, StatusReply)
        return Status.from_reply(reply)

    def hello(self, versions: Sequence[int] = ()) -> Hello:
        """HELLO (optionally listing the protocol versions we speak) as a :class:`Hello`."""
        reply = self.execute(HelloCommand(tuple(versions)))
        assert isinstance(reply, HelloReply)
        return Hello.from_reply(reply)

    def _run(self, command: C) -> C:
        self.execute(command)
        return command
