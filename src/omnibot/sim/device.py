"""The simulated motor controller: the real firmware running on the simulator through a simulator HAL.

This module joins firmware and simulator; :mod:`omnibot.sim.scheme` puts the pair behind a link::

    host bytes --receive()--> SimHAL UART --> firmware Controller.poll() --set_power--> Simulator
    host bytes <-transmit()-- SimHAL UART <--         (events, replies, TEL)   <--sensors--/

:class:`SimDevice` implements :class:`~omnibot.transport.lockstep.LockstepDevice`, so the same object
serves the in-process lockstep link (``sim://PRESET``), the real-time pty emulator (``omnibot sim
--pty``) and tests. The firmware is polled at the robot's ``controller.loop_hz`` (an Arduino-class
loop), the physics steps at 1 kHz.

``sim://`` URLs open it alone or as a robot of a fleet (:mod:`omnibot.sim.fleet`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from omnibot.firmware.config import build_config
from omnibot.firmware.controller import Controller
from omnibot.firmware.hal import HAL
from omnibot.robot import RobotDescription, load_robot
from omnibot.sim.clock import SimClock
from omnibot.sim.simulator import Simulator
from omnibot.sim.truth import TruthRecorder
from omnibot.sim.world import World

SPEED_OF_SOUND = 343.0
"""m/s at 20 degrees C; an HC-SR04 echo takes 2 d / c."""
ECHO_TIMEOUT = 0.030
"""s the HC-SR04 waits for an echo that never comes."""


class SimHAL(HAL):
    """The firmware's HAL over a :class:`Simulator`: its clock, motors and sensors."""

    def __init__(self, sim: Simulator) -> None:
        self.sim = sim
        robot = sim.robot
        self.rx = bytearray()
        self.tx = bytearray()
        self.pwm = [0] * robot.n_wheels
        self._pwm_dirty = False
        encoder_index = {e.wheel: k for k, e in enumerate(robot.encoders.motors)}
        self._encoder_of_wheel = [encoder_index.get(w.name) for w in robot.wheels]
        self._sonar_ready: list[float] = [math.inf] * len(robot.sonars)
        self._sonar_cm: list[int] = [-1] * len(robot.sonars)

    def ticks_us(self) -> int:
        """The simulator's time in whole microseconds."""
        return self.sim.clock.ticks_us()

    def uart_read(self) -> bytes:
        """Take everything the host has sent (b"" when nothing)."""
        if not self.rx:
            return b""
        data = bytes(self.rx)
        self.rx.clear()
        return data

    def uart_write(self, data: bytes) -> None:
        """Queue ``data`` for the host."""
        self.tx += data

    def set_power(self, i: int, pwm: int) -> None:
        """Set motor ``i``'s signed PWM; the simulator gets it at :meth:`apply_power`."""
        if self.pwm[i] != pwm:
            self.pwm[i] = pwm
            self._pwm_dirty = True

    def apply_power(self) -> None:
        """Hand changed PWM values to the simulator (once per step, not once per motor)."""
        if self._pwm_dirty:
            self.sim.set_pwm(self.pwm)
            self._pwm_dirty = False

    def encoder_count(self, i: int) -> int:
        """Cumulative encoder count of driven wheel ``i`` (0 when that wheel has no encoder)."""
        k = self._encoder_of_wheel[i]
        return 0 if k is None else self.sim.encoder_count(k)

    def tracking_count(self, j: int) -> int:
        """Cumulative encoder count of tracking wheel ``j``."""
        return self.sim.tracking_counts()[j]

    def gyro_rate_mdps(self) -> int | None:
        """The gyro's yaw rate in millidegrees/s, None when the robot has no gyro."""
        gyro = self.sim.gyro
        if gyro is None:
            return None
        return round(math.degrees(gyro.rate) * 1000.0)

    def sonar_start(self, s: int) -> None:
        """Fire sonar ``s``: its range (cm, -1 for no echo) is ready after the echo's round trip (or the
        echo timeout)."""
        reading = self.sim.sonar_ping(s)
        if reading is None:
            self._sonar_cm[s] = -1
            self._sonar_ready[s] = self.sim.time + ECHO_TIMEOUT
        else:
            self._sonar_cm[s] = round(reading * 100.0)
            self._sonar_ready[s] = self.sim.time + 2.0 * reading / SPEED_OF_SOUND

    def sonar_read(self, s: int) -> int | None:
        """Sonar ``s``'s range in cm (-1: no echo), None while its echo is still on the way."""
        if self.sim.time < self._sonar_ready[s]:
            return None
        return self._sonar_cm[s]

    def battery_mv(self) -> int:
        """The battery voltage in mV."""
        return round(self.sim.battery_voltage * 1000.0)


class SimDevice:
    """Firmware + simulator as one steppable device (a LockstepDevice)."""

    def __init__(
        self,
        robot: RobotDescription | str,
        *,
        surface: str | None = None,
        world: World | str | Path | None = None,
        seed: int = 0,
        dt: float = 0.001,
        start_pose: tuple[float, float, float] | None = None,
        truth_recorder: TruthRecorder | None = None,
        true_robot: RobotDescription | None = None,
        firmware_overrides: dict[str, Any] | None = None,
        clock: SimClock | None = None,
    ) -> None:
        """``robot`` is what the firmware is built for; ``true_robot`` (default: the same) is what the
        simulator simulates, so a robot whose real parameters differ from its description can be tested.
        """
        self.robot = load_robot(robot) if isinstance(robot, str) else robot
        self.sim = Simulator(
            true_robot or self.robot,
            surface=surface,
            world=world,
            seed=seed,
            dt=dt,
            start_pose=start_pose,
            truth_recorder=truth_recorder,
            clock=clock,
        )
        self.hal = SimHAL(self.sim)
        config = build_config(self.robot)
        config.update(firmware_overrides or {})
        self.controller = Controller(self.hal, config)
        self._poll_every = max(1, round(1.0 / (self.robot.controller.loop_hz * dt)))
        self._steps = 0
        self._tick = dt

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self.sim.clock.now()

    @property
    def tick(self) -> float:
        """The length of one simulator step, s."""
        return self._tick

    def receive(self, data: bytes) -> None:
        """Bytes from the host, for the firmware's next UART read."""
        self.hal.rx += data

    def step(self) -> None:
        """One simulator step, with a firmware poll (and its PWM handed over) at the controller's loop
        rate."""
        self.control()
        self.sim.step()

    def run_quiet(self, ticks: int) -> int:
        """Up to ``ticks`` steps, ending after the first in which the firmware sent bytes; the steps
        taken (the lockstep link's quiet stretches: no bytes on the line either way). Only a poll
        sends, so the simulator takes the steps from one poll to the next in one call."""
        tx, sim, every = self.hal.tx, self.sim, self._poll_every
        taken = 0
        while taken < ticks:
            phase = self._steps % every
            self.control()  # the poll due at this step, if any (it alone sends); counts one step
            n = 1 if tx else min(every - phase, ticks - taken)  # to the next poll
            sim.step(n)
            self._steps += n - 1
            taken += n
            if tx:
                break
        return taken

    def control(self) -> None:
        """The firmware's half of a step: a poll (and its PWM handed over) at the controller's loop rate.
        A fleet polls every robot's firmware first, then steps their physics together."""
        if self._steps % self._poll_every == 0:
            self.controller.poll()
            self.hal.apply_power()
        self._steps += 1

    def command(self, line: str, seconds: float = 0.0) -> bytes:
        """Send ``line`` (one protocol line, its terminator added) and :meth:`run` ``seconds``."""
        self.receive((line + "\n").encode())
        return self.run(seconds)

    def run(self, seconds: float) -> bytes:
        """Step ``seconds`` of simulated time (whole steps); everything the firmware sent meanwhile."""
        out = bytearray()
        for _ in range(round(seconds / self._tick)):
            self.step()
            out += self.transmit()
        return bytes(out)

    def transmit(self) -> bytes:
        """Take everything the firmware has sent (b"" when nothing)."""
        if not self.hal.tx:
            return b""
        data = bytes(self.hal.tx)
        self.hal.tx.clear()
        return data
