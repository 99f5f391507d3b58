"""The host side of the range scanner: where :class:`~omnibot.scan.Scan` comes from.

::

    ScanSource (poll() -> [Scan...], close())
     +-- RplidarScanner   a real RPLIDAR on a serial port, or the emulated one ``omnibot sim --pty``
     |                    serves on a pty: the rplidar driver (PyPI rplidar-roboticia) in a thread
     +-- SimScanSource    the in-process simulator of a ``sim://`` link: its scan listener

:func:`open_scanner` picks one: a device path gives an RPLIDAR; none on a ``sim://`` link gives the
simulator's scanner. A ``sim://`` link is a :class:`~omnibot.transport.lockstep.LockstepLink` whose
``device.sim`` is the Simulator; :func:`omnibot.transport.device.find_simulator` finds it through
any ``spy+``/``faults+`` wrappers (None for a real link).

An RPLIDAR revolution becomes a Scan laid out as the part measures it: clockwise, so
``angle_min = 0`` (the part's 0 degrees, straight ahead of its cable-less side as mounted) and
``angle_increment = -2 pi / n`` for the n nodes of the revolution, each node put in the ray nearest
its angle; ``inf`` where the node said distance 0 (no return) or where no node fell; quality as the
intensities; ``stamp`` the host's ``time.monotonic()`` when the revolution's first node was read,
``scan_time`` the time since the previous revolution began. Frame name and mount pose are the
caller's (from the robot description).
"""

from __future__ import annotations

import errno
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import Any, Protocol, cast

import numpy as np

from omnibot.errors import ConfigError, LinkError
from omnibot.motion import Pose2D
from omnibot.scan import Scan
from omnibot.transport import Link

__all__ = [
    "RplidarScanner",
    "ScanSource",
    "ScanningSim",
    "SimScanSource",
    "measures_to_scan",
    "open_scanner",
]

MAX_SCANS = 16
"""Scans a source keeps between two polls (the oldest are dropped)."""
ANSWER_WAIT = 3.0
"""s the driver waits for each answer (its serial timeout): a real RPLIDAR answers within
milliseconds; the simulated one of ``omnibot sim`` on a loaded machine has taken over 1 s, the
driver's own default, to send a 7-byte descriptor (CI: 'Descriptor length mismatch')."""
MAX_RESTARTS = 3
"""Scans :class:`RplidarScanner` restarts in a row (without a whole revolution between) before it
gives up and reports the error."""
A1_RANGE = (0.15, 12.0)
"""An A1's range, m (A2: 0.15 to 16 m at most)."""


class ScanSource(Protocol):
    """Where scans come from: the revolutions completed since the last poll, oldest first."""

    def poll(self) -> list[Scan]:
        """The scans completed since the last call (maybe none); LinkError if the source failed."""
        ...

    def close(self) -> None:
        """Stop the scanner and release it."""
        ...


class ScanningSim(Protocol):
    """What a :class:`SimScanSource` needs of :class:`omnibot.sim.simulator.Simulator`."""

    @property
    def robot(self) -> Any:
        """The robot description (its ``name``)."""
        ...

    @property
    def scanner(self) -> object | None:
        """The simulated scanner, None when the robot has none."""
        ...

    def add_scan_listener(self, fn: Callable[[Scan], None]) -> None:
        """Call ``fn`` with every revolution completed, in simulated time."""
        ...

    def remove_scan_listener(self, fn: Callable[[Scan], None]) -> None:
        """Stop calling ``fn``."""
        ...


def measures_to_scan(
    measures: Sequence[tuple[int, float, float]],
    *,
    stamp: float,
    scan_time: float = 0.0,
    range_min: float = A1_RANGE[0],
    range_max: float = A1_RANGE[1],
    frame: str = "laser",
    mount: Pose2D | None = None,
) -> Scan:
    """One revolution of RPLIDAR measures ``(quality, clockwise degrees, mm)`` as a Scan (see the
    module docstring): n rays clockwise from 0, inf for distance 0 and for rays no node fell in."""
    n = len(measures)
    if n == 0:
        raise ValueError("a revolution without measures")
    ranges = np.full(n, math.inf)
    quality = np.zeros(n)
    filled = np.zeros(n, dtype=bool)
    step = 360.0 / n
    for q, angle, mm in measures:
        k = round((angle % 360.0) / step) % n
        r = mm / 1000.0 if mm > 0 else math.inf
        if not filled[k] or r < ranges[k]:  # two nodes in one ray: the nearer return
            ranges[k], quality[k], filled[k] = r, q, True
    return Scan(
        stamp=stamp,
        angle_min=0.0,
        angle_increment=-2.0 * math.pi / n,
        ranges=ranges,
        range_min=range_min,
        range_max=range_max,
        time_increment=scan_time / n,
        scan_time=scan_time,
        intensities=quality,
        frame=frame,
        mount=mount or Pose2D(0.0, 0.0, 0.0),
    )


def _driver() -> Any:
    import rplidar

    class Driver(rplidar.RPLidar):  # type: ignore[misc]
        """The driver, with DTR optional: a pty (the emulated scanner) has no modem lines, and
        pyserial's setDTR raises ENOTTY there; on a real adapter DTR is set as the driver sets it."""

        def _dtr(self, level: bool) -> None:
            try:
                self._serial.setDTR(level)
            except OSError as exc:
                if exc.errno not in (errno.ENOTTY, errno.EINVAL):
                    raise

        def start_motor(self) -> None:
            self._dtr(False)  # A1: DTR low starts the motor
            self._set_pwm(self._motor_speed)  # A2
            self.motor_running = True

        def stop_motor(self) -> None:
            self._set_pwm(0)
            time.sleep(0.001)
            self._dtr(True)
            self.motor_running = False

    return Driver


class RplidarScanner:
    """An RPLIDAR read by the rplidar driver in a background thread, one Scan per revolution.

    Opening connects, checks the health (LinkError for a part in its error state) and starts the
    motor and a standard scan; :meth:`close` stops the scan and the motor and joins the thread.
    """

    def __init__(
        self,
        port: str,
        *,
        baudrate: int = 115200,
        frame: str = "laser",
        mount: Pose2D | None = None,
        range_min: float = A1_RANGE[0],
        range_max: float = A1_RANGE[1],
        timeout: float = ANSWER_WAIT,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.port = port
        self.frame = frame
        self.mount = mount or Pose2D(0.0, 0.0, 0.0)
        self.range_min, self.range_max = range_min, range_max
        self._clock = clock
        self._scans: deque[Scan] = deque(maxlen=MAX_SCANS)
        self._lock = threading.Lock()
        self._stopping = threading.Event()
        self.error: BaseException | None = None
        """What ended the reading thread, if anything but close()."""
        self.restarts = 0
        """Scans restarted after a node the driver rejected."""
        self._read_whole = False
        import rplidar

        try:
            self._lidar = _driver()(port, baudrate=baudrate, timeout=timeout)
        except rplidar.RPLidarException as exc:
            raise LinkError(f"cannot open the RPLIDAR on {port}: {exc}") from None
        try:
            self.info: dict[str, Any] = self._lidar.get_info()
            status, code = self._lidar.get_health()
            if status == "Error":
                raise LinkError(f"the RPLIDAR on {port} reports error {code} (protection stop)")
        except rplidar.RPLidarException as exc:
            self._lidar.disconnect()
            raise LinkError(f"the RPLIDAR on {port} did not answer: {exc}") from None
        except BaseException:
            self._lidar.disconnect()
            raise
        self._thread = threading.Thread(target=self._run, name=f"omnibot-rplidar {port}", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        """Read until close(); after a node the driver rejects (a real part's stream can slip a
        byte: "New scan flags mismatch", "Check bit not equal to 1"), stop the scan, flush the
        input and start again, at most MAX_RESTARTS times in a row."""
        import rplidar

        failures = 0
        while not self._stopping.is_set():
            try:
                self._read()
                return
            except rplidar.RPLidarException as exc:
                if self._stopping.is_set():
                    return
                failures = 0 if self._read_whole else failures + 1
                self.restarts += 1
                if failures > MAX_RESTARTS:
                    self.error = exc
                    return
                try:
                    self._lidar.stop()  # STOP, wait 0.1 s, drop what came meanwhile
                except BaseException as stop_exc:
                    if not self._stopping.is_set():
                        self.error = stop_exc
                    return
            except BaseException as exc:
                if not self._stopping.is_set():
                    self.error = exc
                return

    def _read(self) -> None:
        """Start a scan and publish every revolution until close()."""
        revolution: list[tuple[int, float, float]] = []
        began: float | None = None
        self._read_whole = False
        for new_scan, quality, angle, distance in self._lidar.iter_measures(max_buf_meas=5000):
            if self._stopping.is_set():
                return
            if new_scan:
                now = self._clock()
                if revolution and began is not None:
                    self._publish(revolution, began, now - began)
                    self._read_whole = True
                revolution, began = [], now
            if began is not None:  # the nodes before the first start flag are half a revolution
                revolution.append((quality, angle, distance))

    def _publish(self, measures: list[tuple[int, float, float]], stamp: float, scan_time: float) -> None:
        scan = measures_to_scan(
            measures,
            stamp=stamp,
            scan_time=scan_time,
            range_min=self.range_min,
            range_max=self.range_max,
            frame=self.frame,
            mount=self.mount,
        )
        with self._lock:
            self._scans.append(scan)

    def poll(self) -> list[Scan]:
        """The revolutions completed since the last call; LinkError once the reading has failed."""
        with self._lock:
            scans = list(self._scans)
            self._scans.clear()
        if not scans and self.error is not None:
            raise LinkError(f"reading the RPLIDAR on {self.port} failed: {self.error}")
        return scans

    def close(self) -> None:
        """Stop scanning and the motor, join the thread, close the port (idempotent)."""
        if self._stopping.is_set():
            return
        self._stopping.set()
        self._thread.join(1.0)
        serial = self._lidar._serial
        if self._thread.is_alive():  # blocked waiting for bytes that will not come
            serial.close()
            self._thread.join(5.0)
        try:
            if serial.is_open:
                self._lidar.stop()
                self._lidar.stop_motor()
        except OSError:
            pass  # the port went away: nothing left to stop
        finally:
            self._lidar.disconnect()

    def __enter__(self) -> RplidarScanner:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class SimScanSource:
    """The scanner of an in-process Simulator: its scans, in simulated time, as they complete."""

    def __init__(self, sim: ScanningSim) -> None:
        if getattr(sim, "scanner", None) is None:
            raise ConfigError(f"the simulated robot {sim.robot.name!r} has no scanner", key="scanner")
        self.sim = sim
        self._scans: deque[Scan] = deque(maxlen=MAX_SCANS)
        self._listening = True
        self._listener: Callable[[Scan], None] = self._scans.append
        sim.add_scan_listener(self._listener)

    def poll(self) -> list[Scan]:
        """The scans completed since the last call."""
        scans = list(self._scans)
        self._scans.clear()
        return scans

    def close(self) -> None:
        """Stop listening (idempotent)."""
        if self._listening:
            self._listening = False
            self.sim.remove_scan_listener(self._listener)


def scanner_baud(model: str) -> int:
    """The serial rate of an RPLIDAR model (``a1`` 115200, ``a2`` 256000)."""
    from omnibot.lidar.rplidar_device import model_named

    return model_named(model).baud


def open_scanner(spec: str | None, link: Link | ScanningSim | None, robot: Any) -> ScanSource:
    """The robot's scanner: ``spec`` a serial device (``/dev/ttyUSB1``, a pty of ``omnibot sim
    --pty``) -> :class:`RplidarScanner` set from the robot description's scanner section (model,
    frame, mount x/y/yaw_deg, range); ``spec`` None with a ``sim://`` link (or its Simulator) ->
    :class:`SimScanSource`. ConfigError naming ``--scanner`` when the robot has no scanner or a
    real link gets no ``spec``."""
    section = getattr(robot, "scanner", None)
    name = getattr(robot, "name", "the robot")
    if section is None:
        raise ConfigError(f"robot {name!r} has no scanner in its description", key="--scanner")
    if spec is not None:
        return RplidarScanner(
            spec,
            baudrate=scanner_baud(str(getattr(section, "model", "a1"))),
            frame=str(getattr(section, "frame", "laser")),
            mount=Pose2D(
                float(getattr(section, "x", 0.0)),
                float(getattr(section, "y", 0.0)),
                math.radians(float(getattr(section, "yaw_deg", 0.0))),
            ),
            range_min=float(getattr(section, "range_min", A1_RANGE[0])),
            range_max=float(getattr(section, "range_max", A1_RANGE[1])),
        )
    sim: ScanningSim | None
    if isinstance(link, Link):
        from omnibot.transport import find_simulator

        sim = cast("ScanningSim | None", find_simulator(link))
    else:
        sim = link
    if sim is None:
        raise ConfigError(
            "a real robot's scanner is read from its own port: give --scanner /dev/ttyUSB1 (or the "
            "scanner pty omnibot sim --pty prints)",
            key="--scanner",
        )
    return SimScanSource(sim)
