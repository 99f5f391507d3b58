"""landing.py and the executor's closed-loop landing: in MODE 2 a finite MOVE, each DELTA repetition and
a ROTATE end on the distance (angle) their encoders measure, with the speed ramped up and down.

Two rigs: the simulator in lockstep, where the landing is judged from its ground truth on every
preset and floor (with the floor's creep as ``omnibot calibrate``'s slip runs fit it), and the
FakeHAL (scripted time, encoders that follow the powers) for the executor's semantics: the queue,
DELTA, STOP, the sonar guard, the modes (the creep terms and CAL table 9: test_landing_creep.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.firmware.config import build_config
from omnibot.firmware.config_loops import LAND_ACCEL
from omnibot.firmware.landing import Landing
from omnibot.protocol import codes
from omnibot.robot import load_robot
from omnibot.sim import SimDevice
from tests.firmware.conftest import Rig, make_rig

SLIP = {
    ("omni4", "wood"): [0.001731, 0.013454, 1.0, 0.0],
    ("omni4", "carpet"): [0.006818, 0.027463, 1.0, 0.0],
    ("omni3", "wood"): [0.001047, 0.0, 1.0, 0.0],
    ("omni3", "carpet"): [0.003634, 0.0, 1.0, 0.0007676],
    ("mecanum4", "wood"): [0.001477, 0.0, 1.0, 0.0],
    ("mecanum4", "carpet"): [0.005314, 0.0, 1.0, 0.0],
}
"""Each floor's creep (roll, combined, scale, ramp) as the slip runs fit it (``benchmarks.move_landing``'s
``floor_slip``: simulator seed 1000)."""
EXACT = 440 / (2 * math.pi * 220.0 * 0.025)
"""FakeHAL encoder counts per PWM count per second of a wheel that turns as the rig's calibration
plans (tests/firmware/test_progress.py)."""
STOP = 25
PERIOD = 60


def warn(code: int) -> str:
    return f"WARN,{code},{codes.TEXTS[code]}"


# ---------------------------------------------------------------------- the simulator's truth


def drive(
    robot: str, surface: str, command: str, mode: int = 2
) -> tuple[SimDevice, tuple[float, float, float]]:
    """Run ``command`` on the simulated robot (its floor's creep uploaded) until IDLE and 1 s of
    coast after it; the device and the true start pose."""
    dev = SimDevice(robot, surface=surface, seed=1, firmware_overrides={"slip": SLIP[robot, surface]})
    dev.receive(f"MODE,{mode}\n".encode())
    for _ in range(5):
        dev.step()
    p = dev.sim.pose
    dev.receive((command + "\n").encode())
    out = b""
    for _ in range(30000):
        dev.step()
        out += dev.transmit()
        if b"IDLE" in out:
            break
    for _ in range(1000):
        dev.step()
    assert b"IDLE" in out and b"WARN" not in out, out
    return dev, (p.x, p.y, p.theta)


CASES = {
    # each case one the timed MODE 2 missed by more than 2 % (benchmarks/move_landing.py, main at 6a593b1)
    ("omni4", "wood"): ("MOVE,30,90,45,0", "MOVE,30,60,0,0"),  # -30.5 %, +11.0 %
    ("omni4", "carpet"): ("MOVE,100,60,45,0", "MOVE,30,90,0,0"),  # -9.9 %, -37.3 %
    ("omni3", "wood"): ("MOVE,30,100,90,0", "MOVE,100,30,0,0"),  # +108 %, +12.8 %
    ("omni3", "carpet"): ("MOVE,100,100,45,0", "MOVE,30,30,90,0"),  # +33.2 %, +11.4 %
    ("mecanum4", "wood"): ("MOVE,30,60,0,0", "MOVE,30,30,45,0"),  # +15.1 %, +2.5 %
    ("mecanum4", "carpet"): ("MOVE,30,60,45,0", "MOVE,100,10,90,0"),  # -31.1 %, -19.2 %
}


@pytest.mark.parametrize(("robot", "surface"), list(CASES))
def test_closed_loop_moves_land_within_2_percent(robot: str, surface: str) -> None:
    for command in CASES[robot, surface]:
        dev, (x0, y0, th0) = drive(robot, surface, command)
        length, _, course = (int(v) for v in command.split(",")[1:4])
        p = dev.sim.pose
        a = th0 + math.radians(course)
        along = (p.x - x0) * math.cos(a) + (p.y - y0) * math.sin(a)
        assert along * 100 / length == pytest.approx(1.0, abs=0.02), command


@pytest.mark.parametrize(
    ("robot", "surface"), [("omni3", "wood"), ("omni4", "carpet"), ("mecanum4", "carpet")]
)
def test_closed_loop_rotates_land_within_2_percent(robot: str, surface: str) -> None:
    # omni3 wood: the timed ROTATE went 41 % too far (30 kg coasting on)
    for angle, rate in ((90, 90), (360, 180)):
        dev, (_, _, th0) = drive(robot, surface, f"ROTATE,{angle},{rate}")
        turned = math.degrees(dev.sim.pose.theta - th0)
        turned += 360.0 * round((angle - turned) / 360.0)
        assert turned / angle == pytest.approx(1.0, abs=0.02), (angle, rate)


def test_seed_circle_closes_at_its_size_in_closed_loop() -> None:
    """37 moves of 2 cm, each its distance on the encoders: a 36-gon 22.86 cm across (the timed MODE 2
    drove it 25.7 cm across on omni4 wood, open loop 19.3)."""
    dev = SimDevice("omni4", surface="wood", seed=1, firmware_overrides={"slip": SLIP["omni4", "wood"]})
    dev.receive(b"MODE,2\nMOVE,2,40,0,0;DELTA,0,0,10,0,36\n")
    trail = []
    out = b""
    for _ in range(4000):
        dev.step()
        p = dev.sim.pose
        trail.append((p.x, p.y))
        out += dev.transmit()
        if b"IDLE" in out:
            break
    xy = np.array(trail)
    a = np.column_stack((2.0 * xy, np.ones(len(xy))))
    cx, cy, c = np.linalg.lstsq(a, (xy * xy).sum(axis=1), rcond=None)[0]
    across = 2.0 / math.tan(math.radians(5.0))
    assert 200.0 * math.sqrt(c + cx * cx + cy * cy) == pytest.approx(across, rel=0.03)


def test_open_loop_keeps_seed_000s_timeline() -> None:
    """MODE 0 is seed 000's controller: the circle's 37 moves take 50 ms each, IDLE at 1850 ms."""
    dev = SimDevice("omni4", surface="wood", seed=1)
    dev.receive(b"MOVE,2,40,0,0;DELTA,0,0,10,0,36\n")
    t0 = dev.time
    out = b""
    while b"IDLE" not in out:
        dev.step()
        out += dev.transmit()
    assert dev.time - t0 == pytest.approx(1.85, abs=0.003)


# ---------------------------------------------------------------------- the config


def test_config_turn_and_ramps() -> None:
    description = load_robot("omni4")
    cfg = build_config(description)
    # a full turn in place: every wheel turns R_c / r of a revolution the same way
    counts = [440 * 0.096 / 0.025] * 4
    assert sum(a * n for a, n in zip(cfg["turn"], counts, strict=True)) == pytest.approx(2 * math.pi)
    limits = description.limits
    assert cfg["land_accel"] == pytest.approx(
        [LAND_ACCEL * limits.acceleration_max, LAND_ACCEL * limits.angular_acceleration_max]
    )
    bare = description.model_copy(update={"encoders": description.encoders.model_copy(update={"motors": ()})})
    assert not Landing(build_config(bare)).available


# ---------------------------------------------------------------------- the executor (FakeHAL)


def closed(share: float = 1.0) -> Rig:
    """The omni4 rig in MODE 2 whose wheels turn ``share`` of what the feedforward plans."""
    rig = make_rig()
    rig.hal.enc_gain = share * EXACT
    assert rig.cmd("MODE,2") == ["OK"]
    return rig


def travelled(rig: Rig, start: list[int], course: float) -> float:
    """cm along ``course`` on the encoders since ``start``."""
    tx, ty = rig.config["travel"]
    a = math.radians(course)
    return 100.0 * sum(
        (float(x) * math.cos(a) + float(y) * math.sin(a)) * (n - n0)
        for x, y, n, n0 in zip(tx, ty, rig.hal.enc, start, strict=True)
    )


def until_idle(rig: Rig, limit_ms: int = 10000) -> tuple[int, list[str]]:
    """Run until IDLE: the ms it took and the lines written."""
    out: list[str] = []
    for ms in range(limit_ms):
        out += rig.run(1)
        if "IDLE" in out:
            return ms + 1, out
    raise AssertionError(out)


def test_a_move_ends_on_its_encoders_not_its_time() -> None:
    """Wheels that turn 80 % of what the powers plan: the timed MOVE ended 20 % short (WARN 17); now the
    loop drives them and the MOVE ends where its encoders say 100 cm, after its ramps."""
    rig = closed(0.8)
    start = list(rig.hal.enc)
    assert rig.cmd("MOVE,100,50,30,0") == ["OK"]
    ms, lines = until_idle(rig)
    assert lines == ["IDLE"]
    assert travelled(rig, start, 30) == pytest.approx(100.0, abs=0.2)
    accel = LAND_ACCEL * load_robot("omni4").limits.acceleration_max * 100  # cm/s^2
    assert 2000 < ms < 2000 + 1000 * 50 / accel + 150  # 100 cm at 50 cm/s, and the ramps' 0.5 s
    assert rig.run(300) == []  # no WARN 17: it did not fall short


def test_rotate_ends_on_its_angle() -> None:
    rig = closed(1.2)
    start = list(rig.hal.enc)
    assert rig.cmd("ROTATE,-90,90") == ["OK"]
    until_idle(rig)
    turn = sum(w * (n - n0) for w, n, n0 in zip(rig.config["turn"], rig.hal.enc, start, strict=True))
    assert math.degrees(turn) == pytest.approx(-90.0, abs=0.3)


def test_the_command_queued_behind_starts_when_the_move_lands() -> None:
    rig = closed(0.8)
    start = list(rig.hal.enc)
    assert rig.send("MOVE,50,50,0,0;ROTATE,90,90\n") == ["OK", "OK"]
    ex = rig.ctrl.executor
    while ex.kind == codes.MOVE:
        rig.run(1)
    assert ex.kind == codes.ROTATE
    assert travelled(rig, start, 0) == pytest.approx(50.0, abs=0.3)
    assert ex.remembered == [50, 50, 0, 0]
    until_idle(rig)


def test_a_move_queued_behind_on_the_same_course_is_not_slowed_for() -> None:
    rig = closed()
    rig.send("MOVE,50,50,0,0;MOVE,50,50,0,0\n")
    ex = rig.ctrl.executor
    while ex.kind == codes.MOVE and ex.remembered[0] == 50 and len(rig.ctrl.queue):
        rig.run(1)
    assert ex.landing.plan == pytest.approx(0.5)  # handed over at full speed
    until_idle(rig)
    # the other way: it ramps down to a stop first
    rig.send("MOVE,50,50,0,0;MOVE,-50,50,0,0\n")
    while len(rig.ctrl.queue):
        rig.run(1)
    assert ex.landing.plan < 0.1


@pytest.mark.parametrize("poll_us", [1000, 3700])
def test_delta_repetitions_each_end_on_their_distance(poll_us: int) -> None:
    rig = closed(0.9)
    start = list(rig.hal.enc)
    assert rig.send("MOVE,2,40,0,0;DELTA,0,0,10,0,36\n") == ["OK", "OK"]
    ex = rig.ctrl.executor
    path = 0.0
    course = 0
    last = list(start)
    while ex.moving:
        rig.run(poll_us // 1000 or 1, step_us=poll_us)
        if ex.remembered[2] != course or not ex.moving:  # a repetition ended
            path += travelled(rig, last, course)
            last = list(rig.hal.enc)
            course = ex.remembered[2]
    assert ex.remembered == [2, 40, 0, 0]  # 36 repetitions of 10 degrees: round to course 0
    assert path == pytest.approx(74.0, abs=0.2)  # 37 moves of 2 cm, along each one's course


def test_an_infinite_delta_finishes_its_repetition_when_a_command_comes() -> None:
    rig = closed()
    rig.send("MOVE,30,40,0,0;DELTA,0,0,10,0,INF\n")
    ex = rig.ctrl.executor
    course = 0
    start = list(rig.hal.enc)
    queued = None
    for ms in range(5000):
        rig.run(1)
        if ex.kind not in (codes.DELTA, codes.MOVE):
            break
        if ex.remembered[2] != course:  # a repetition began
            course = ex.remembered[2]
            start = list(rig.hal.enc)
        if ms == 1200:  # 10 cm into the DELTA's first repetition (course 10)
            assert rig.cmd("ROTATE,90,90") == ["OK"]
            queued = course
    assert ex.kind == codes.ROTATE
    assert course == queued == 10  # no repetition began after it came
    assert travelled(rig, start, course) == pytest.approx(30.0, abs=0.3)  # the one running went its 30 cm
    until_idle(rig)


def test_stop_mid_move() -> None:
    rig = closed()
    rig.cmd("MOVE,100,50,0,0")
    rig.run(500)
    assert rig.cmd("STOP") == ["OK", "IDLE"]
    ex = rig.ctrl.executor
    assert rig.hal.powers == [0, 0, 0, 0] and not ex.landing.active and ex.remembered == [0, 0, 0, 0]
    assert rig.run(500) == []
    start = list(rig.hal.enc)
    rig.cmd("MOVE,20,50,90,0")  # the next starts from rest
    until_idle(rig)
    assert travelled(rig, start, 90) == pytest.approx(20.0, abs=0.2)


def test_simulation_and_open_loop_keep_the_timeline() -> None:
    rig = closed()
    assert rig.cmd("MODE,3") == ["OK"]  # simulation: no power, nothing to measure
    rig.send("MOVE,2,40,0,0;DELTA,0,0,10,0,36\n")
    assert until_idle(rig)[0] == 1850
    # switched to open loop halfway through a landing: the rest on the timeline at the speed asked
    rig.cmd("MODE,2")
    start = list(rig.hal.enc)
    rig.cmd("MOVE,100,50,0,0")
    rig.run(1000)
    left = 100.0 - travelled(rig, start, 0)
    assert rig.cmd("MODE,0") == ["OK"]
    ms, _ = until_idle(rig)
    assert ms == pytest.approx(10 * left / 0.5, abs=3)


def test_wheels_that_do_not_turn_end_the_move_short() -> None:
    """Blocked wheels (no counts): the MOVE ends after twice its time and its ramps and a second, short
    (WARN 17), not never."""
    rig = closed(0.0)
    rig.cmd("MOVE,20,50,0,0")
    ms, lines = until_idle(rig)
    accel = LAND_ACCEL * load_robot("omni4").limits.acceleration_max * 100
    assert ms == pytest.approx(2 * (400 + 2000 * 50 / accel) + 1000, abs=15)
    assert lines == ["IDLE"]
    assert rig.run(100) == [warn(codes.W_SHORT)]


def test_the_sonar_guard_slows_a_landing_move_which_still_lands() -> None:
    rig = closed()
    rig.cmd(f"SONAR,1,{PERIOD},0,0,{STOP}")
    rig.hal.ranges[0] = 50  # the guard lets omni4 close in at about 77 cm/s
    rig.run(100)
    start = list(rig.hal.enc)
    assert rig.cmd("MOVE,100,100,0,0") == ["OK"]
    ex = rig.ctrl.executor
    assert rig.run(1000) == [warn(codes.W_SONAR_LIMIT)]  # as the ramp up passes what the guard allows
    assert 0.5 < ex._k < 1.0
    assert 0.3 < ex.landing.speed < 0.79  # m/s: no faster than the guard allows
    until_idle(rig)
    assert travelled(rig, start, 0) == pytest.approx(100.0, abs=0.3)
    # and a reading below what the slowest speed can stop in still stops it at once
    rig.cmd("MOVE,100,100,0,0")
    rig.run(200)
    rig.hal.ranges[0] = 20
    lines = rig.run(200)
    assert lines[-2:] == [warn(codes.W_SONAR_STOP), "IDLE"]
    assert rig.hal.powers == [0, 0, 0, 0] and not ex.landing.active
