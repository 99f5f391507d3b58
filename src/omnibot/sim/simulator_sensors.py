"""The simulated robot's sensors: motor encoders, tracking wheels, gyro and sonars read from the
simulator (the laser scanner's feed: :mod:`omnibot.sim.simulator_scan`), each sensor on a random
stream of its own of the simulator's seed."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import SimulationError
from omnibot.robot import RobotDescription
from omnibot.sim.clock import SimClock
from omnibot.sim.physics_like import PhysicsLike
from omnibot.sim.scanner import LaserScanner
from omnibot.sim.sensors import Gyro, MotorEncoders, Sonar, TrackingWheels
from omnibot.sim.world import World

FloatArray = NDArray[np.float64]

# fixed RNG stream keys, so that adding one sensor does not change another's noise
_RNG_ENCODERS, _RNG_TRACKING, _RNG_GYRO, _RNG_SONAR, _RNG_SCANNER = 0, 1, 2, 100, 200


def _rng(seed: int, key: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(key,)))


class SensorReadings:
    """:class:`~omnibot.sim.simulator.Simulator`'s sensors and what they read now."""

    robot: RobotDescription
    clock: SimClock
    seed: int
    dt: float
    world: World
    neighbours: Callable[[], FloatArray] | None
    _physics: PhysicsLike
    _wheel_names: list[str]

    def _make_sensors(self) -> LaserScanner | None:
        """The encoders, tracking wheels, gyro, sonars and laser scanner (returned: the host's scan
        feed holds it), each on its own random stream of the seed."""
        robot, seed = self.robot, self.seed
        enc_index = np.array(
            [self._wheel_names.index(e.wheel) for e in robot.encoders.motors], dtype=np.int64
        )
        angles = self._physics.wheel_angle
        self._encoder_wheels: list[int] = enc_index.tolist()
        self.encoders = MotorEncoders(
            [e.counts_per_rev for e in robot.encoders.motors],
            _rng(seed, _RNG_ENCODERS),
            initial_angles=angles[0, enc_index],
            source=lambda: self._physics.wheel_angle[0, enc_index],
        )
        self.tracking = TrackingWheels(robot.encoders.tracking, _rng(seed, _RNG_TRACKING))
        self.gyro = Gyro(robot.gyro, _rng(seed, _RNG_GYRO)) if robot.gyro is not None else None
        if self.gyro is not None:
            self.gyro.refill(self.dt)
        self._no_gyro = np.zeros(0)
        self.sonars = [Sonar(s, _rng(seed, _RNG_SONAR + i)) for i, s in enumerate(robot.sonars)]
        return LaserScanner(robot.scanner, seed, _RNG_SCANNER) if robot.scanner is not None else None

    def encoder_counts(self) -> list[int]:
        """Motor encoder counts in robot.encoders.motors order."""
        return [int(c) for c in self.encoders.counts]

    def encoder_count(self, index: int) -> int:
        """Motor encoder ``index``'s count: ``encoder_counts()[index]``, the others not counted (unless
        edges may be missed: those are drawn for all at once)."""
        encoders = self.encoders
        if encoders.miss_probability > 0.0:
            return self.encoder_counts()[index]
        return encoders.count_at(index, float(self._physics.wheel_angle[0, self._encoder_wheels[index]]))

    def tracking_counts(self) -> list[int]:
        """Tracking-wheel encoder counts in robot.encoders.tracking order."""
        return [int(c) for c in self.tracking.counts]

    def gyro_rate(self) -> float:
        """Latest gyro sample, rad/s."""
        if self.gyro is None:
            raise SimulationError(f"robot '{self.robot.name}' has no gyro")
        return self.gyro.rate

    def sonar_ping(self, index: int | str = 0) -> float | None:
        """Range (m) from sonar ``index`` (position or name), or None for no echo.

        Pinging again within the sonar's ``period_min`` returns the previous result (see
        :meth:`omnibot.sim.sensors.Sonar.ping`).
        """
        if isinstance(index, str):
            names = [s.spec.name for s in self.sonars]
            if index not in names:
                raise SimulationError(f"robot '{self.robot.name}' has no sonar '{index}' (has {names})")
            index = names.index(index)
        if not 0 <= index < len(self.sonars):
            raise SimulationError(
                f"robot '{self.robot.name}' has {len(self.sonars)} sonars, no index {index}"
            )
        others = self.neighbours() if self.neighbours is not None else None
        return self.sonars[index].ping(self.clock.now(), self._physics.pose[0], self.world, others)


__all__ = ["SensorReadings"]
