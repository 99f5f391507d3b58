"""An emulated Slamtec RPLIDAR A1/A2: the scanner's serial side, fed with :class:`~omnibot.scan.Scan`.

A :class:`~omnibot.transport.lockstep.LockstepDevice` (bytes in, time steps, bytes out; no I/O, no
thread), so it runs in lockstep in a test or on a pty through
:class:`~omnibot.transport.pty_bridge.PtyBridge` (``omnibot sim --pty`` serves the robot's scanner
so). What it does, as the real part does (Slamtec's protocol manual for A1/A2):

- GET_INFO (model, firmware, hardware, serial number), GET_HEALTH, GET_SAMPLERATE and
  GET_ACC_BOARD_FLAG are answered at once (a descriptor, then the data);
- SCAN answers a descriptor (5-byte nodes, multiple responses), then streams nodes while the motor
  turns; FORCE_SCAN streams even while it does not; STOP and RESET answer nothing and end the
  stream; RESET reboots (requests in the next RESET_TIME s are lost) and prints a start-up banner;
- a request it does not know (EXPRESS_SCAN is not emulated) or whose checksum is wrong is
  discarded: no answer, the host times out. While it scans, requests other than STOP, RESET, SCAN,
  FORCE_SCAN and SET_MOTOR_PWM wait until the scan ends (the manual: cached by the protocol stack);
- the motor: the A1's runs while DTR is not asserted (:meth:`set_dtr`: on a real adapter the host's
  DTR drives MOTOCTL; a pty has no DTR, so the A1 emulated on a pty always turns), the A2's while
  SET_MOTOR_PWM set a duty above 0 (0 at power-up). The duty does not change the speed here.

Each Scan fed (:meth:`feed`) is one revolution: ``round(sample_rate * scan.scan_time)`` nodes (or one
per ray when the scan has no ``scan_time``), clockwise from 0 degrees in equal steps, each the
distance of the scan's ray nearest its direction (the Scan is counter-clockwise: a node at
clockwise angle a reads the ray at -a), paced at ``sample_rate`` nodes per second. Distance 0 and
quality 0 where the ray has no return (inf, or outside the scan's [range_min, range_max], or beyond
the 16.4 m a distance_q2 holds); quality from the scan's intensities (clipped to 0..63), else
DEFAULT_QUALITY. The first node of each revolution has the start flag. A revolution ends before the
next begins: with no Scan waiting the stream pauses; of Scans fed faster than they stream only the
newest MAX_QUEUED wait (the others counted in ``dropped_scans``); STOP and RESET drop them.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from omnibot.errors import ConfigError
from omnibot.lidar.rplidar_codec import (
    NODE_SIZE,
    AccBoardFlag,
    Command,
    Descriptor,
    DeviceInfo,
    Health,
    Request,
    ResponseType,
    SampleRate,
    ScanNode,
    SendMode,
    decode_request,
    encode_acc_board_flag,
    encode_descriptor,
    encode_health,
    encode_info,
    encode_node,
    encode_samplerate,
)
from omnibot.scan import Scan

__all__ = ["A1", "A2", "MODELS", "RplidarDevice", "RplidarModel", "model_named", "revolution_nodes"]

DEFAULT_QUALITY = 15
"""Quality of a return when the scan has no intensities (what an A1 reports for most returns)."""
MAX_QUEUED = 2
"""Scans waiting for their revolution; older ones are dropped."""
RESET_TIME = 0.01
"""s an RPLIDAR takes to reboot after RESET (requests meanwhile are lost)."""
MAX_DISTANCE_Q2 = 0xFFFF


@dataclass(frozen=True)
class RplidarModel:
    """What tells one RPLIDAR model from another, on the wire."""

    name: str
    model: int
    """GET_INFO's model byte (major model in the high nibble: 1 A1, 2 A2)."""
    firmware: tuple[int, int]
    hardware: int
    baud: int
    sample_rate: float
    """Standard-scan nodes per second."""
    pwm_motor: bool
    """The motor is driven by SET_MOTOR_PWM (A2), not by DTR (A1)."""


A1 = RplidarModel("A1", 0x18, (1, 29), 7, 115200, 2000.0, pwm_motor=False)
A2 = RplidarModel("A2", 0x28, (1, 29), 5, 256000, 4000.0, pwm_motor=True)
MODELS = {"a1": A1, "a2": A2}


def model_named(name: str) -> RplidarModel:
    """The model for ``a1``/``a2`` (also ``rplidar_a1``, ``RPLIDAR A2M8``...); ConfigError otherwise."""
    key = name.lower().replace("rplidar", "").strip(" _-")[:2]
    if key not in MODELS:
        raise ConfigError(f"unknown RPLIDAR model {name!r}: expected one of {', '.join(MODELS)}", key="model")
    return MODELS[key]


def revolution_nodes(scan: Scan, count: int, default_quality: int = DEFAULT_QUALITY) -> list[ScanNode]:
    """The ``count`` nodes of one revolution that reads ``scan`` (see the module docstring)."""
    if count < 1:
        raise ValueError(f"a revolution has at least one node, not {count}")
    cw_deg = np.arange(count) * (360.0 / count)
    angle_q6 = np.rint(cw_deg * 64.0).astype(np.int64) % (360 * 64)
    step = abs(scan.angle_increment)
    full = round(2.0 * math.pi / step)
    # index of the ray nearest each direction, counted along the scan's own direction of increase
    u = (np.sign(scan.angle_increment) * (-np.radians(cw_deg) - scan.angle_min)) % (2.0 * math.pi)
    idx = np.rint(u / step).astype(np.int64)
    idx = np.where(idx >= full, idx - full, idx)
    inside = idx < len(scan)
    idx = np.where(inside, idx, 0)
    r = scan.ranges[idx]
    q2 = np.rint(np.where(np.isfinite(r), r, 0.0) * 4000.0)
    ok = inside & np.isfinite(r) & (r >= scan.range_min) & (r <= scan.range_max) & (q2 <= MAX_DISTANCE_Q2)
    q2 = np.where(ok, q2, 0).astype(np.int64)
    if scan.intensities is None:
        quality = np.full(count, default_quality, dtype=np.int64)
    else:
        quality = np.clip(np.rint(np.asarray(scan.intensities, dtype=float)[idx]), 0, 63).astype(np.int64)
    quality = np.where(ok, quality, 0)
    return [ScanNode(k == 0, int(quality[k]), int(angle_q6[k]), int(q2[k])) for k in range(count)]


class RplidarDevice:
    """An RPLIDAR A1/A2 on a UART, stepped in time (see the module docstring)."""

    def __init__(
        self,
        model: RplidarModel = A1,
        *,
        tick: float = 0.001,
        sample_rate: float | None = None,
        serial_number: bytes = bytes(range(16)),
        start_time: float = 0.0,
        on_scanning: Callable[[bool], None] | None = None,
    ) -> None:
        if tick <= 0:
            raise ValueError(f"tick must be > 0 s, got {tick}")
        self.model = model
        self.sample_rate = sample_rate or model.sample_rate
        """Nodes per second while scanning."""
        if self.sample_rate * NODE_SIZE * 10 > model.baud:
            raise ConfigError(
                f"{self.sample_rate:g} nodes/s do not fit the {model.name}'s {model.baud} baud "
                f"(at most {model.baud / (NODE_SIZE * 10):g})",
                key="sample_rate",
            )
        self.info = DeviceInfo(model.model, model.firmware, model.hardware, serial_number)
        self.health = Health(0, 0)
        """What GET_HEALTH answers (set a warning or an error to test a host)."""
        self._tick = tick
        self._time = start_time
        self.dtr = False
        """DTR asserted by the host (stops an A1's motor)."""
        self.pwm = 0
        """Last SET_MOTOR_PWM duty (an A2's motor turns while > 0)."""
        self.scanning = False
        self.forced = False
        self.on_scanning = on_scanning
        """Called with True when a scan starts and False when it ends (e.g. to measure only while
        a host reads: the simulator's scanner costs nothing while nobody listens)."""
        self.discarded: list[Request] = []
        """Requests discarded (unknown command, wrong checksum, sent while rebooting)."""
        self.dropped_scans = 0
        self.revolutions = 0
        """Revolutions streamed in full."""
        self._rx = bytearray()
        self._tx = bytearray()
        self._waiting: list[Request] = []  # sent while scanning, handled when the scan ends
        self._scans: deque[Scan] = deque()
        self._rev: list[ScanNode] = []
        self._next_node = 0
        self._next_node_time = start_time
        self._ready_at = start_time  # after a RESET: the time it answers again

    # -- LockstepDevice ----------------------------------------------------------------------

    @property
    def time(self) -> float:
        """Seconds of device time."""
        return self._time

    @property
    def tick(self) -> float:
        """Seconds per :meth:`step`."""
        return self._tick

    def receive(self, data: bytes) -> None:
        """Bytes from the host."""
        self._rx += data

    def transmit(self) -> bytes:
        """Bytes sent since the last call."""
        out = bytes(self._tx)
        self._tx.clear()
        return out

    def step(self) -> None:
        """Advance one tick: handle the requests received, stream the nodes due."""
        self._time += self._tick
        if self._time < self._ready_at:
            self._rx.clear()  # rebooting: the UART is not listening
            return
        self._handle_requests()
        if self.scanning:
            self._stream()

    # -- inputs besides the UART -------------------------------------------------------------

    def feed(self, scan: Scan) -> None:
        """One revolution to stream (the simulator's scanner calls this with each scan)."""
        self._scans.append(scan)
        while len(self._scans) > MAX_QUEUED:
            self._scans.popleft()
            self.dropped_scans += 1

    def set_dtr(self, asserted: bool) -> None:
        """The host's DTR line (on an A1 asserted DTR stops the motor)."""
        self.dtr = asserted

    @property
    def motor_running(self) -> bool:
        """Whether the motor turns (A1: DTR not asserted; A2: a PWM duty above 0)."""
        return self.pwm > 0 if self.model.pwm_motor else not self.dtr

    # -- requests ----------------------------------------------------------------------------

    def _handle_requests(self) -> None:
        if self._waiting and not self.scanning:
            waiting, self._waiting = self._waiting, []
            for held in waiting:
                self._handle(held)
        while self._rx:
            used, request = decode_request(bytes(self._rx))
            del self._rx[:used]
            if request is None:
                return
            if self.scanning and request.command not in _WHILE_SCANNING:
                self._waiting.append(request)
            else:
                self._handle(request)
            if self._time < self._ready_at:  # a RESET: the rest is lost
                self._rx.clear()
                return

    def _handle(self, request: Request) -> None:
        command = request.command
        if not request.valid or command not in _HANDLERS:
            self.discarded.append(request)
            return
        _HANDLERS[command](self, request)

    def _answer(self, kind: ResponseType, data: bytes) -> None:
        self._tx += encode_descriptor(Descriptor(len(data), SendMode.SINGLE, kind)) + data

    def _get_info(self, request: Request) -> None:
        self._answer(ResponseType.INFO, encode_info(self.info))

    def _get_health(self, request: Request) -> None:
        self._answer(ResponseType.HEALTH, encode_health(self.health))

    def _get_samplerate(self, request: Request) -> None:
        us = round(1e6 / self.sample_rate)
        self._answer(ResponseType.SAMPLERATE, encode_samplerate(SampleRate(us, max(1, us // 2))))

    def _get_acc_board_flag(self, request: Request) -> None:
        flag = AccBoardFlag(1 if self.model.pwm_motor else 0)
        self._answer(ResponseType.ACC_BOARD_FLAG, encode_acc_board_flag(flag))

    def _set_motor_pwm(self, request: Request) -> None:
        payload = request.payload or b""
        if len(payload) != 2:
            self.discarded.append(request)
            return
        self.pwm = int.from_bytes(payload, "little")

    def _set_scanning(self, on: bool) -> None:
        if on != self.scanning and self.on_scanning is not None:
            self.on_scanning(on)
        self.scanning = on

    def _scan(self, request: Request) -> None:
        self._set_scanning(True)
        self.forced = request.command == Command.FORCE_SCAN
        self._rev, self._next_node = [], 0
        self._next_node_time = self._time
        self._tx += encode_descriptor(Descriptor(NODE_SIZE, SendMode.MULTIPLE, ResponseType.SCAN))

    def _stop(self, request: Request) -> None:
        self._set_scanning(False)
        self.forced = False
        self._scans.clear()  # measured for a scan that is over: the next one measures afresh
        self._rev, self._next_node = [], 0

    def _reset(self, request: Request) -> None:
        self._stop(request)
        self.pwm = 0
        self.health = Health(0, 0)
        self._waiting.clear()
        self._ready_at = self._time + RESET_TIME
        major, minor = self.model.firmware
        self._tx += (
            f"RP LIDAR System.\r\nFirmware Ver {major}.{minor:02d}, HW Ver {self.model.hardware}\r\n"
            f"Model: {self.model.model:02X}\r\n"
        ).encode("ascii")

    # -- streaming ---------------------------------------------------------------------------

    def _stream(self) -> None:
        if not (self.motor_running or self.forced):
            self._next_node_time = max(self._next_node_time, self._time)
            return
        period = 1.0 / self.sample_rate
        while self._next_node_time <= self._time + 1e-12:
            if self._next_node >= len(self._rev):
                if self._rev:
                    self.revolutions += 1
                if not self._scans:  # nothing to measure yet: pause the stream
                    self._rev, self._next_node = [], 0
                    self._next_node_time = self._time
                    return
                scan = self._scans.popleft()
                count = len(scan) if scan.scan_time <= 0 else max(1, round(self.sample_rate * scan.scan_time))
                self._rev, self._next_node = revolution_nodes(scan, count), 0
            self._tx += encode_node(self._rev[self._next_node])
            self._next_node += 1
            self._next_node_time += period


_WHILE_SCANNING = frozenset(
    {Command.STOP, Command.RESET, Command.SCAN, Command.FORCE_SCAN, Command.SET_MOTOR_PWM}
)
_HANDLERS: dict[int, Callable[[RplidarDevice, Request], None]] = {
    Command.GET_INFO: RplidarDevice._get_info,
    Command.GET_HEALTH: RplidarDevice._get_health,
    Command.GET_SAMPLERATE: RplidarDevice._get_samplerate,
    Command.GET_ACC_BOARD_FLAG: RplidarDevice._get_acc_board_flag,
    Command.SET_MOTOR_PWM: RplidarDevice._set_motor_pwm,
    Command.SCAN: RplidarDevice._scan,
    Command.FORCE_SCAN: RplidarDevice._scan,
    Command.STOP: RplidarDevice._stop,
    Command.RESET: RplidarDevice._reset,
}
