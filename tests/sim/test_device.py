"""The simulated controller: real firmware on the simulator, reached through sim:// in lockstep."""

from __future__ import annotations

import math

import pytest

from omnibot.errors import ConfigError
from omnibot.sim.device import SimDevice
from omnibot.transport import LockstepLink, open_link

from .linkio import read_until


def test_hello_at_power_up_and_a_move_moves_the_simulated_robot() -> None:
    device = SimDevice("omni4", seed=1)
    with LockstepLink(device) as link:
        assert read_until(link, b"\r\n").startswith(b"HELLO,2,omni4,4\r\n")
        link.write(b"MOVE,30,60,90,0;")
        out = read_until(link, b"IDLE\r\n")
        assert out == b"OK\r\nIDLE\r\n"
        # (how fast lockstep runs is a benchmark's matter; that it never waits for the wall clock,
        # tests/transport/test_lockstep.py's)
        pose = device.sim.pose
        assert 0.15 < pose.y < 0.45  # course 90: to the left; open loop, so only roughly 30 cm
        assert abs(pose.x) < 0.05 and abs(pose.theta) < 0.2


def test_rotate_turns_counter_clockwise() -> None:
    device = SimDevice("omni4", seed=2)
    with LockstepLink(device) as link:
        link.write(b"ROTATE,90,180;")
        read_until(link, b"IDLE\r\n")
        assert 0.5 < device.sim.pose.theta < 2.5


def test_simulation_mode_reaches_no_motor() -> None:
    device = SimDevice("omni4", seed=3)
    with LockstepLink(device) as link:
        link.write(b"MODE,1;MOVE,30,60,0,0;")
        read_until(link, b"IDLE\r\n")
        assert math.hypot(device.sim.pose.x, device.sim.pose.y) < 1e-4


def test_sim_url_options_and_errors() -> None:
    with open_link("sim://omni3?seed=4&surface=carpet&world=room&baud=0") as link:
        assert b"HELLO,2,omni3,3" in read_until(link, b"\r\n")
    with pytest.raises(ConfigError, match="did you mean"):
        open_link("sim://omni4?sead=1")
    with pytest.raises(ConfigError):
        open_link("sim://omni9")


def test_sonar_emergency_stop_in_the_corridor() -> None:
    device = SimDevice("omni4", seed=5, world="corridor")
    with LockstepLink(device) as link:
        read_until(link, b"\r\n")
        link.write(b"SONAR,1,60,0,0,40;MOVE,30000,60,0,0;")
        out = read_until(link, b"WARN,13", timeout=30.0)
        assert b"WARN,13" in out
        link.write(b"MOVE,10,40,0,0;")
        assert b"ERROR,40" in read_until(link, b"ERROR", timeout=1.0)
        assert device.sim.collisions == []


def test_command_runs_the_device_for_a_while_and_returns_what_it_sent() -> None:
    device = SimDevice("omni4", seed=1)
    assert device.run(0.01).startswith(b"HELLO,2,omni4,4\r\n")
    t0 = device.time
    assert device.command("MOVE,10,40,0,0", 0.5).startswith(b"OK\r\nIDLE\r\n")  # 0.25 s of MOVE
    assert device.time - t0 == pytest.approx(0.5)
    assert device.command("STATUS") == b"" and device.run(0.002).startswith(b"STATUS,1,")


class EveryTick:
    """The same device without :meth:`SimDevice.run_quiet`: the link steps it tick by tick."""

    def __init__(self, device: SimDevice) -> None:
        self.device = device
        self.tick = device.tick

    @property
    def time(self) -> float:
        return self.device.time

    def receive(self, data: bytes) -> None:
        self.device.receive(data)

    def step(self) -> None:
        self.device.step()

    def transmit(self) -> bytes:
        return self.device.transmit()


def session(device: SimDevice | EveryTick) -> tuple[list[tuple[float, bytes]], int]:
    """TEL every 20 ms, a MOVE, a wait and a STATUS: each chunk read with its time, and the steps."""
    reads: list[tuple[float, bytes]] = []
    with LockstepLink(device) as link:
        for line in (b"TELEM,20,255\n", b"MOVE,10,40,30,0\n", b"", b"STATUS\n"):
            link.write(line)
            link.clock.sleep(0.003)
            while (chunk := link.read(timeout=0.5)) and link.clock.now() < 3.0:
                reads.append((link.clock.now(), chunk))
        return reads, link.steps


def counted_quiet_runs(device: SimDevice) -> list[int]:
    """The ticks asked of each of ``device``'s :meth:`SimDevice.run_quiet` calls from now on."""
    calls: list[int] = []
    run_quiet = device.run_quiet

    def counted(ticks: int) -> int:
        calls.append(ticks)
        return run_quiet(ticks)

    device.run_quiet = counted  # type: ignore[method-assign]
    return calls


def test_quiet_runs_give_the_bytes_at_the_times_of_tick_by_tick_steps() -> None:
    quiet, ticked = SimDevice("omni4", seed=2), SimDevice("omni4", seed=2)
    calls = counted_quiet_runs(quiet)
    reads, steps = session(quiet)
    assert (reads, steps) == session(EveryTick(ticked)) and len(reads) > 100
    assert quiet.sim.pose == ticked.sim.pose and quiet.controller.now_ms == ticked.controller.now_ms
    assert calls and len(calls) < steps  # quiet stretches of several ticks in one call


def test_a_quiet_run_ends_on_the_tick_the_firmware_sends() -> None:
    device = SimDevice("omni4", seed=1)
    assert device.run_quiet(100) == 1 and device.transmit().startswith(b"HELLO")
    device.receive(b"TELEM,10,1\n")
    # read at the next poll: omni4 polls every other 1 ms step (500 Hz)
    assert device.run_quiet(100) == 2 and device.transmit().startswith(b"OK\r\nTEL,")
    assert device.run_quiet(3) == 3 and device.transmit() == b""
    t0 = device.time
    taken = device.run_quiet(100)
    assert device.transmit().startswith(b"TEL,") and device.time == pytest.approx(t0 + taken * device.tick)


def gathered_session(device: SimDevice | EveryTick) -> tuple[list[tuple[float, bytes]], int, bytes]:
    """TEL every 10 ms, a MOVE and a STATUS read a line at a time (as a client waiting reads), then
    a clock sleep over the line's bytes: each read with its time, the steps, what the sleep left."""
    reads: list[tuple[float, bytes]] = []
    with LockstepLink(device) as link:
        for line in (b"TELEM,10,255\n", b"MOVE,10,40,30,0\n", b"STATUS\n"):
            link.write(line)
            end = link.clock.now() + 0.4
            while (left := end - link.clock.now()) > 0:
                if chunk := link.read_gathered(b"\r\n", 256, timeout=left):
                    reads.append((link.clock.now(), chunk))
        link.clock.sleep(0.1)
        return reads, link.steps, link.read(timeout=0)


def test_quiet_runs_through_a_line_to_the_host_until_the_bytes_would_gather() -> None:
    quiet, ticked = SimDevice("omni4", seed=2), SimDevice("omni4", seed=2)
    calls = counted_quiet_runs(quiet)
    reads, steps, left = gathered_session(quiet)
    assert (reads, steps, left) == gathered_session(EveryTick(ticked)) and len(reads) > 100 and left
    assert sum(b"\r" not in chunk and b"\n" not in chunk for _, chunk in reads) <= 3  # at the 3 timeouts
    assert quiet.sim.pose == ticked.sim.pose and quiet.controller.now_ms == ticked.controller.now_ms
    assert len(calls) < steps / 4  # a TEL line's 5 ticks on the line mostly in one call
