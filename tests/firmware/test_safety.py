"""The sonar stop's guard (firmware/safety.py): stop distance, speed limit, uncovered directions, and
how the controller reports them (WARN 14/15/16, ERROR 41, MODE bit 3, the brake)."""

from __future__ import annotations

import math

import pytest

from omnibot.firmware.config import build_config
from omnibot.firmware.safety import LATENCY_MS, LIMITED, UNCOVERED, SonarGuard
from omnibot.firmware.sonar import Sonars
from omnibot.protocol import codes
from omnibot.robot import load_robot
from tests.firmware.conftest import Rig, make_rig

STOP = 25
PERIOD = 60
NEAR = 50  # cm: omni4 may close in at about 77 cm/s, then stop before STOP


def warn(code: int) -> str:
    return f"WARN,{code},{codes.TEXTS[code]}"


def err(code: int) -> str:
    return f"ERROR,{code},{codes.TEXTS[code]}"


@pytest.fixture
def guard() -> SonarGuard:
    config = build_config(load_robot("omni4"))
    sonars = Sonars(1)
    sonars.configure(0, PERIOD, 0, 0, STOP, 0)
    return SonarGuard(config, sonars)


def stop_distance(g: SonarGuard, c: float, r: float) -> float:
    """STOP + c T + c^2 / 2a, written out here (cm, cm/s)."""
    t = (PERIOD + 1000 / 500 + LATENCY_MS) / 1000 + 2 * r / 34300
    return STOP + c * t + c * c / (2 * g.decel)


def test_deceleration_comes_from_the_description(guard: SonarGuard) -> None:
    robot = load_robot("omni4")
    assert guard.decel == pytest.approx(100 * robot.stop_deceleration)
    assert 150 < guard.decel < 280  # a lower bound of the 2.8 m/s^2 the simulated robot coasts down at
    assert guard.width == [10.0] and guard.lead == [0.0]  # front sonar on the 20 cm box's front face


def test_closing_max_is_where_the_stop_distance_meets_the_room(guard: SonarGuard) -> None:
    for r in (40, 80, 150, 300):
        guard.reading(0, r)
        c = guard.closing_max(0)
        assert c > 0
        assert stop_distance(guard, c, r) == pytest.approx(guard.room[0], rel=1e-9)
    guard.reading(0, STOP - 1)
    assert guard.closing_max(0) == 0.0


def test_room_allows_for_a_slanted_wall(guard: SonarGuard) -> None:
    """A wall at incidence a to the axis, d from the sonar: the cone's edge reads r = d / cos(a - half);
    the footprint's corner, w to the side, meets it after (d - w sin a) / cos a of travel."""
    half, w = math.radians(7.5), 10.0
    for d in (30.0, 60.0, 120.0):
        worst = math.inf
        for deg in range(0, 61, 5):
            a = math.radians(deg)
            r = d / math.cos(a - half) if a > half else d
            guard.reading(0, round(r))
            corner = (d - w * math.sin(a)) / math.cos(a)
            assert guard.room[0] <= corner + 1.0, (d, deg)  # +1: the reading is rounded to cm
            worst = min(worst, corner)
        guard.reading(0, round(d))  # square on: the room is the worst slant's, not the range
        assert guard.room[0] < d


def test_far_is_full_speed_near_is_limited_too_near_stops(guard: SonarGuard) -> None:
    guard.reading(0, 400)
    assert guard.factor(100.0, 0.0) == 1.0 and guard.flags == 0
    guard.reading(0, NEAR)
    k = guard.factor(100.0, 0.0)
    assert 0.3 <= k < 1.0 and guard.flags == LIMITED
    assert stop_distance(guard, 100.0 * k, NEAR) == pytest.approx(guard.room[0])
    guard.reading(0, STOP + 2)
    assert guard.factor(100.0, 0.0) == 0.0 and guard.code == codes.W_SONAR_STOP


def test_the_limit_never_below_the_slowest_speed(guard: SonarGuard) -> None:
    guard.reading(0, NEAR)
    allowed = guard.factor(100.0, 0.0) * 100.0
    assert guard.factor(60.0, 0.0) * 60.0 == pytest.approx(min(allowed, 60.0))
    stopped = limited = 0
    for r in range(20, 80):
        guard.reading(0, r)
        k = guard.factor(100.0, 0.0)
        assert k == 0.0 or k * 100.0 >= 30.0, r  # omni4's slowest speed, or the stop
        stopped += k == 0.0
        limited += 0.0 < k < 1.0
    assert stopped and limited


def test_moving_away_or_aside_of_the_cone(guard: SonarGuard) -> None:
    guard.reading(0, STOP - 5)
    assert guard.factor(-25.0, 0.0) == 1.0  # backing away (uncovered, but slow enough)
    assert guard.factor(-50.0, 0.0) == pytest.approx(0.6) and guard.flags == UNCOVERED
    assert guard.factor(50.0, 0.0) == 0.0  # towards it


def test_uncovered_direction_is_limited_or_refused(guard: SonarGuard) -> None:
    guard.reading(0, 400)
    assert guard.covers(100.0, 0.0) and not guard.covers(0.0, 100.0)
    assert guard.factor(0.0, 100.0) == pytest.approx(0.3) and guard.flags == UNCOVERED
    assert guard.factor(0.0, 20.0) == 1.0  # slow enough already
    guard.refuse = True
    assert guard.factor(0.0, 100.0) == 0.0 and guard.code == codes.E_UNCOVERED
    assert guard.factor(100.0, 0.0) == 1.0


def test_nothing_armed_nothing_limited(guard: SonarGuard) -> None:
    guard.sonars.configure(0, PERIOD, 0, 100, 0, 0)  # RANGE events only, no stop
    guard.reading(0, 10)
    guard.refuse = True
    for vx, vy in ((100.0, 0.0), (0.0, 100.0), (-70.0, 70.0)):
        assert guard.covers(vx, vy) and guard.factor(vx, vy) == 1.0


def test_one_missed_echo_is_bridged(guard: SonarGuard) -> None:
    guard.reading(0, 200)
    guard.factor(100.0, 0.0)  # closing at 100 cm/s
    guard.reading(0, -1)
    assert guard.range[0] == pytest.approx(200 - 100 * PERIOD / 1000)
    guard.reading(0, -1)
    assert guard.range[0] == -1.0 and guard.room[0] == -1.0


# ------------------------------------------------------------------ through the controller


def approach(rig: Rig, start: int, step: int, until: int) -> list[str]:
    """Ranges falling by ``step`` cm every reading (60 ms) from ``start``; the lines written."""
    out = []
    r = start
    while r > until:
        rig.hal.ranges[0] = r
        out += rig.run(PERIOD)
        r -= step
    return out


def test_speed_limit_said_once_then_the_stop(rig: Rig) -> None:
    rig.cmd(f"SONAR,1,{PERIOD},0,0,{STOP}")
    rig.hal.ranges[0] = 300
    rig.run(100)
    assert rig.cmd("MOVE,30000,100,0,0") == ["OK"]
    full = max(abs(p) for p in rig.hal.powers)
    lines = approach(rig, 200, 5, 0)
    assert lines.count(warn(codes.W_SONAR_LIMIT)) == 1
    assert lines[-2:] == [warn(codes.W_SONAR_STOP), "IDLE"]
    assert lines.index(warn(codes.W_SONAR_LIMIT)) < lines.index(warn(codes.W_SONAR_STOP))
    assert rig.status().startswith("STATUS,3,")
    assert full > 0


def test_limited_speed_recovers_when_the_obstacle_goes(rig: Rig) -> None:
    rig.cmd(f"SONAR,1,{PERIOD},0,0,{STOP}")
    rig.hal.ranges[0] = 400
    rig.run(100)
    rig.cmd("MOVE,30000,100,0,0")
    full = max(abs(p) for p in rig.hal.powers)
    rig.hal.ranges[0] = NEAR
    rig.run(500)  # the coast down is over
    slow = max(abs(p) for p in rig.hal.powers)
    assert 0 < slow < full
    rig.hal.ranges[0] = 400
    rig.run(100)
    assert max(abs(p) for p in rig.hal.powers) == full


def test_lowering_the_speed_coasts_first(rig: Rig) -> None:
    rig.cmd(f"SONAR,1,{PERIOD},0,0,{STOP}")
    rig.hal.ranges[0] = 400
    rig.run(100)
    rig.cmd("MOVE,30000,100,0,0")
    rig.hal.ranges[0] = NEAR
    rig.run(70)  # a reading came: the guard lowered the speed
    assert rig.hal.powers == [0, 0, 0, 0]  # coasting down at the stop deceleration
    assert any(rig.ctrl.executor.powers)
    rig.run(400)
    assert any(rig.hal.powers)


def test_a_limited_finite_move_keeps_its_distance(rig: Rig) -> None:
    rig.cmd(f"SONAR,1,{PERIOD},0,0,{STOP}")
    rig.hal.ranges[0] = NEAR
    rig.run(100)
    assert rig.cmd("MOVE,60,100,0,0") == ["OK", warn(codes.W_SONAR_LIMIT)]
    k = rig.ctrl.executor._k
    assert 0.3 < k < 1.0
    ms = 0
    while "IDLE" not in rig.run(10):
        ms += 10
    assert ms == pytest.approx(600 / k, abs=15)  # 60 cm at 100 k cm/s


def test_uncovered_travel_limited_by_default(rig: Rig) -> None:
    rig.cmd("MOVE,30000,100,90,0")
    full = max(abs(p) for p in rig.hal.powers)
    rig.cmd("STOP")
    rig.cmd(f"SONAR,1,{PERIOD},0,0,{STOP}")
    assert rig.cmd("MOVE,30000,100,90,0") == ["OK", warn(codes.W_UNCOVERED)]
    assert max(abs(p) for p in rig.hal.powers) == pytest.approx(0.3 * full, abs=1)
    assert rig.run(500) == []  # said once
    assert rig.cmd("ROTATE,90,90") == ["OK"]  # turning in place is not travel


def test_uncovered_travel_refused_with_mode_bit_3(rig: Rig) -> None:
    assert rig.cmd("MODE,8") == ["OK"]
    assert rig.status().startswith("STATUS,1,0,16,8;")
    assert rig.cmd("MOVE,10,40,90,0") == ["OK"]  # nothing armed: nothing refused
    rig.run(500)
    rig.cmd(f"SONAR,1,{PERIOD},0,0,{STOP}")
    assert rig.cmd("MOVE,10,40,90,0") == [err(codes.E_UNCOVERED)]
    assert rig.cmd("MOVE,-10,40,180,0") == ["OK"]  # backwards along course 180: ahead
    rig.run(500)
    assert rig.cmd("VEL,0,30,0,100") == [err(codes.E_UNCOVERED)]
    assert rig.cmd("VEL,30,0,0,100") == ["OK"]
    rig.cmd("STOP")
    # a DELTA's course runs out of the cone while it runs: stopped and said so
    assert rig.cmd("MOVE,2,40,0,0;DELTA,0,0,10,0,3") == ["OK", "OK"]
    lines = rig.run(500)
    assert lines == [warn(codes.W_UNCOVERED_STOP), "IDLE"]
    assert rig.hal.powers == [0, 0, 0, 0] and rig.status().startswith("STATUS,1,0,")
    assert rig.cmd("MODE,0") == ["OK"] and rig.cmd("MOVE,10,40,90,0") == ["OK", warn(codes.W_UNCOVERED)]


def test_stop_off_behaves_as_before() -> None:
    plain, ranging = make_rig(), make_rig()
    ranging.cmd(f"SONAR,1,{PERIOD},0,100,0")  # RANGE events, no stop
    for rig in (plain, ranging):
        rig.hal.ranges[0] = 30
        rig.run(100)
        rig.cmd("MOVE,100,100,90,0")
    for _ in range(10):
        assert plain.run(100) == [x for x in ranging.run(100) if not x.startswith("RANGE")]
        assert plain.hal.powers == ranging.hal.powers


def test_emergency_stop_brakes_where_the_driver_can() -> None:
    for can in (True, False):
        rig = make_rig()
        rig.hal.can_brake = can
        rig.cmd(f"SONAR,1,{PERIOD},0,0,{STOP}")
        rig.hal.ranges[0] = 300
        rig.run(100)
        rig.cmd("MOVE,30000,100,0,0")
        rig.hal.ranges[0] = 20
        assert rig.run(100)[-2:] == [warn(codes.W_SONAR_STOP), "IDLE"]
        assert rig.hal.braked == [can] * 4
        rig.cmd("STOP")  # releases the brake (power 0: coasting)
        assert rig.hal.braked == [False] * 4 and rig.hal.powers == [0] * 4


def test_robot_without_sonars_keeps_working() -> None:
    rig = make_rig("omni3")
    assert rig.cmd("MODE,8") == ["OK"]
    assert rig.cmd("MOVE,100,100,90,0") == ["OK"]
    assert any(rig.hal.powers)
    assert rig.cmd("SONAR,1,60,0,0,25") == [err(codes.E_SONAR)]


def test_arming_and_disarming_limit_a_running_travel(rig: Rig) -> None:
    rig.cmd("MOVE,30000,100,90,0")
    full = max(abs(p) for p in rig.hal.powers)
    assert rig.cmd(f"SONAR,1,{PERIOD},0,0,{STOP}") == ["OK", warn(codes.W_UNCOVERED)]
    assert max(abs(p) for p in rig.hal.powers) < full
    assert rig.cmd("SONAR,1,0,0,0,0") == ["OK"]
    assert max(abs(p) for p in rig.hal.powers) == full
    rig.cmd(f"SONAR,1,{PERIOD},0,0,{STOP}")
    assert rig.cmd("MODE,8") == ["OK", warn(codes.W_UNCOVERED_STOP), "IDLE"]
    assert rig.hal.powers == [0, 0, 0, 0]
