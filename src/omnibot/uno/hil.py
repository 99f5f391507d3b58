"""Hardware in the loop, simulated: the emulated UNO's PWM drives omnibot's physics, the physics
drives the UNO's encoder edges, sonar echo and battery voltage back.

::

    omnibot demo --port uno://omni4                 # seed 000's examples on the emulated UNO
    omnibot demo --port "uno://omni4?board=mega"    # ... on the Arduino Mega 2560 build
    python -m omnibot.uno.hil omni4 --world room    # or: print the UNO's pty path, run until Ctrl-C,
    omnibot demo --port serial://THAT_PATH          #     and drive it as any serial board

Importing this module registers the ``uno`` URL scheme, ``uno://ROBOT?world=room&seed=1&board=uno``: the
emulated UNO with the physics running in a thread, opened as a serial link whose ``device.sim`` is
the simulator (so the demo takes its ground truth from it, as for ``sim://``).

The physics (:class:`~omnibot.sim.simulator.Simulator`, 1 kHz) follows the emulated UNO's time in
lockstep (``unosim --lockstep``): the harness reports each duty change with its time (the signed
PWM each L298 channel's pins show) and every 2 emulated milliseconds; the loop steps the physics
to that time, applies the duties at their time, and answers with the motor encoders' counts (the
harness makes the edges), the sonar's range, the battery voltage on ADC7 and ``sync``, without
which the emulator does not run more than 3 ms ahead (the longest its encoders go without news:
the firmware takes a 5 ms pause for a wheel's turnaround). A busy host slows both alike instead of
letting them drift apart. The UNO wiring has no gyro and no tracking wheels, so its TEL sends 0
for them; the host's estimator finds the gyro silent once the body turns and keeps to the wheel
encoders (docs/navigation.md).
"""

from __future__ import annotations

import argparse
import select
import signal
import sys
import threading
from collections.abc import Sequence
from types import FrameType
from typing import TYPE_CHECKING

from omnibot.errors import ConfigError
from omnibot.robot import load_robot
from omnibot.sim import Simulator
from omnibot.transport import LinkUrl, SerialLink, register_scheme
from omnibot.uno.emulator import BOARDS, UnoEmulator, UnoError

if TYPE_CHECKING:
    from omnibot.client import RobotClient, Telemetry

SONAR_PERIOD = 0.002  # s between sonar range updates (the harness echoes the latest one)
BATTERY_PERIOD = 0.1  # s between battery updates


class UnoHil:
    """The emulated UNO of ``robot`` with omnibot's physics of the same robot in ``world``;
    ``board="mega"``: the Arduino Mega 2560 build of the firmware."""

    def __init__(
        self,
        robot: str,
        *,
        world: str | None = "room",
        seed: int = 1,
        start_pose: tuple[float, float, float] | None = None,
        board: str = "uno",
    ) -> None:
        self.robot = load_robot(robot)
        self.sim = Simulator(self.robot, world=world, seed=seed, start_pose=start_pose)
        self.emu = UnoEmulator(robot, lockstep=True, board=board)
        self.path = self.emu.path
        encoder_index = {e.wheel: k for k, e in enumerate(self.robot.encoders.motors)}
        self._encoder_of_wheel = [encoder_index.get(w.name) for w in self.robot.wheels]
        self._stop = threading.Event()

    def stop(self) -> None:
        """Ask :meth:`run` to return (thread-safe)."""
        self._stop.set()

    def _step_to(self, t_us: int) -> None:
        steps = int((t_us * 1e-6 - self.sim.time) / self.sim.dt + 1e-9)
        if steps > 0:
            self.sim.step(steps)

    def run(self) -> None:
        """Follow the harness's time until :meth:`stop` (or the harness ends): apply each duty report
        at its time, and at each time report step the physics there and answer."""
        sim = self.sim
        out = self.emu.proc.stdout
        assert out is not None
        next_sonar = next_battery = 0.0
        nominal = self.robot.battery.voltage
        while not self._stop.is_set() and self.emu.proc.poll() is None:
            try:
                if not select.select([out], [], [], 0.1)[0]:
                    continue
                fields = out.readline().decode().split()
            except (ValueError, OSError):  # closed under us: the emulator was stopped
                return
            if not fields:
                return  # the harness ended
            t_us = int(fields[1])
            self._step_to(t_us)
            if fields[0] == "pwm":
                sim.set_pwm([int(v) for v in fields[2:]])
                continue
            counts = sim.encoder_counts()
            answer = [
                "counts " + " ".join(str(0 if k is None else counts[k]) for k in self._encoder_of_wheel)
            ]
            if sim.sonars and sim.time >= next_sonar:
                # measured now, not rate-limited: the firmware's own ping period paces the HC-SR04
                pose = sim.pose
                reading = sim.sonars[0].measure((pose.x, pose.y, pose.theta), sim.world)
                answer.append(f"range {-1 if reading is None else round(reading * 100.0)}")
                next_sonar = sim.time + SONAR_PERIOD
            if sim.time >= next_battery:
                # ADC7 sees the pack through the divider: full scale (5 V) is twice the nominal voltage
                answer.append(f"battery {round(sim.battery_voltage / nominal * 2500)}")
                next_battery = sim.time + BATTERY_PERIOD
            answer.append(f"sync {t_us}")
            self.emu.command("\n".join(answer))  # one write

    def close(self) -> None:
        """Stop the run and close the emulator."""
        self.stop()
        self.emu.close()


class UnoLink(SerialLink):
    """The serial link to a :class:`UnoHil` that runs in a thread; closing it stops both."""

    def __init__(self, hil: UnoHil, url: str) -> None:
        self.device = hil
        self._runner = threading.Thread(target=hil.run, name="uno-hil", daemon=True)
        self._runner.start()
        try:
            super().__init__(hil.path, url=url)
        except BaseException:
            self._stop_hil()
            raise

    def _stop_hil(self) -> None:
        self.device.stop()
        self._runner.join(timeout=5)
        self.device.close()

    def _close(self) -> None:
        try:
            super()._close()
        finally:
            self._stop_hil()


def counts_at_rest(
    client: RobotClient, sim: Simulator, samples: Sequence[Telemetry]
) -> tuple[list[int], list[int] | None]:
    """Wait (at most 10 s of the host's clock) until the simulated encoders have stood still for
    0.1 s of the emulated time and a TEL in ``samples`` (the client's telemetry, encoders on) was
    sampled since; the simulated counts and the firmware's (None: no TEL with encoders came)."""
    counts, still_since = sim.encoder_counts(), sim.time
    for _ in range(100):
        client.sleep(0.1)
        now = sim.encoder_counts()
        if now != counts:
            counts, still_since = now, sim.time
        elif sim.time - still_since >= 0.1 and samples and samples[-1].controller_time >= sim.time - 0.02:
            break
    firmware = samples[-1].encoders if samples else None
    return list(counts), None if firmware is None else list(firmware)


def _open_uno(u: LinkUrl) -> UnoLink:
    if not u.target:
        raise ConfigError("uno:// needs a robot: uno://omni4 or uno://mecanum4")
    board = u.get_str("board", "uno")
    if board not in BOARDS:
        raise ConfigError(f"uno:// board {board!r}: the firmware is built for {', '.join(BOARDS)}")
    hil = UnoHil(
        u.target, world=u.get_str("world", "room") or None, seed=u.get_int("seed", 1, minimum=0), board=board
    )
    return UnoLink(hil, u.url)


register_scheme(
    "uno",
    _open_uno,
    options=("world", "seed", "board"),
    help="uno://ROBOT?world=room&seed=1&board=uno: the Arduino UNO (board=mega: Mega 2560) firmware in simavr, "
    "hardware in the loop",
)


def main(argv: list[str] | None = None) -> int:
    """Run the hardware-in-the-loop UNO and print its pty's path for a host to open; the exit status."""
    ap = argparse.ArgumentParser(prog="python -m omnibot.uno.hil", description=__doc__.split("\n")[0])
    ap.add_argument("robot", nargs="?", default="omni4", help="omni4 (seed 000) or mecanum4 (seed 003)")
    ap.add_argument("--world", default="room", help="simulator world (default room)")
    ap.add_argument("--seed", type=int, default=1, help="simulator seed (default 1)")
    ap.add_argument(
        "--board", choices=list(BOARDS), default="uno", help="uno (default) or mega (Arduino Mega 2560)"
    )
    args = ap.parse_args(argv)
    try:
        hil = UnoHil(args.robot, world=args.world, seed=args.seed, board=args.board)
    except UnoError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1

    def on_signal(signum: int, frame: FrameType | None) -> None:
        hil.stop()

    signal.signal(signal.SIGTERM, on_signal)
    print(hil.path, flush=True)
    try:
        hil.run()
    except KeyboardInterrupt:
        pass
    finally:
        hil.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
