"""The Simulator facade, against the kinematic stand-in and against the real physics."""

from __future__ import annotations

import io
import math
from functools import partial
from pathlib import Path

import numpy as np
import pytest

from omnibot.errors import ConfigError, SimulationError
from omnibot.motion import Pose2D
from omnibot.robot import RobotDescription, load_robot
from omnibot.robot import kinematics as kin
from omnibot.sim.geometry import convex_hull
from omnibot.sim.simulator import PwmRangeError, Simulator
from omnibot.sim.truth import CollisionEvent, Snapshot, TruthRecorder
from tests.sim.fakes import FakePhysics, ScriptedPhysics


def real_physics(robot, **kwargs):
    from omnibot.sim.physics import Physics

    kwargs.pop("seed", None)
    return Physics(robot, **kwargs)


BACKENDS = {"fake": FakePhysics, "physics": real_physics}


@pytest.fixture(params=sorted(BACKENDS))
def backend(request):
    return BACKENDS[request.param]


@pytest.fixture(scope="module")
def omni4() -> RobotDescription:
    return load_robot("omni4")


def pwm_for(robot: RobotDescription, twist, peak: int = 200) -> list[int]:
    """PWM proportional to the wheel speeds of a twist, the largest at ``peak``."""
    speeds = kin.inverse(robot.wheel_matrix, twist)
    return [round(v) for v in speeds / np.abs(speeds).max() * peak]


# --------------------------------------------------------------------------- basics


def test_time_moves_only_with_steps(omni4, backend) -> None:
    sim = Simulator(omni4, physics_factory=backend)
    assert sim.time == 0.0 and sim.clock.ticks_us() == 0
    sim.step(5)
    assert sim.clock.ticks_us() == 5000
    sim.advance(1.0)
    assert sim.time == pytest.approx(1.005) and sim.clock.ticks_us() == 1_005_000
    assert sim.pose == Pose2D(0.0, 0.0, 0.0)  # no PWM, nothing moves
    with pytest.raises(SimulationError, match="microseconds"):
        Simulator(omni4, dt=1.5e-7, physics_factory=backend)


def test_set_pwm_rejects_instead_of_clamping(omni4) -> None:
    sim = Simulator(omni4, physics_factory=FakePhysics)
    sim.set_pwm([255, -255, 0, 10])
    assert sim.pwm == [255, -255, 0, 10]
    with pytest.raises(ValueError, match=r"PWM 256 for wheel 'm1' is outside \+-255"):
        sim.set_pwm([256, 0, 0, 0])
    with pytest.raises(PwmRangeError, match="needs 4 values"):
        sim.set_pwm([1, 2, 3])
    with pytest.raises(PwmRangeError, match="whole number"):
        sim.set_pwm([1.5, 0, 0, 0])  # type: ignore[list-item]
    assert sim.pwm == [255, -255, 0, 10]  # unchanged by the rejected calls


def test_drives_where_the_kinematics_says(omni4, backend) -> None:
    sim = Simulator(omni4, physics_factory=backend)
    sim.set_pwm(pwm_for(omni4, (0.0, 1.0, 0.0)))
    sim.advance(1.0)
    p = sim.pose
    x, y, th = p.x, p.y, p.theta
    assert y > 0.3 and abs(x) < 0.01 * y and abs(th) < 0.01
    assert sim.twist.vy > 0.3
    assert len(sim.wheel_speeds) == 4


def test_start_pose_from_world_and_argument(omni4) -> None:
    sim = Simulator(omni4, world="room", physics_factory=FakePhysics)
    assert sim.pose == Pose2D(1.0, 1.0, 0.0)
    sim = Simulator(omni4, world="room", start_pose=(2.0, 2.0, 1.0), physics_factory=FakePhysics)
    assert sim.pose == Pose2D(2.0, 2.0, 1.0)
    with pytest.raises(SimulationError, match=r"overlaps walls\[0\]"):
        Simulator(omni4, world="room", start_pose=(0.05, 2.0, 0.0), physics_factory=FakePhysics)


def test_a_start_pose_in_a_wall_is_told_in_metres_and_degrees(omni4) -> None:
    """The pose is told as the user gives it (pose=X,Y,THETA in degrees), not as radians' repr."""
    with pytest.raises(SimulationError) as caught:
        Simulator(omni4, world="room", start_pose=(0.05, 2.0, math.radians(45)), physics_factory=FakePhysics)
    assert "start pose (0.05, 2, 45 deg) overlaps walls[0] of world 'room'" in str(caught.value)


# --------------------------------------------------------------------------- surfaces


def test_surface_ids_follow_the_patches(omni4, backend) -> None:
    sim = Simulator(omni4, world="room", start_pose=(2.5, 3.0, 0.0), physics_factory=backend)
    sim.step()
    # m1 at +x (2.596) is on the carpet (x >= 2.5), m3 at -x (2.404) is on wood, m2/m4 on the edge x=2.5
    assert sim.wheel_surfaces[0] == "carpet" and sim.wheel_surfaces[2] == "wood"
    sim.physics.reset(pose=(4.0, 3.0, 0.0))
    sim.step()
    assert sim.wheel_surfaces == ["carpet"] * 4


def test_the_physics_gets_the_surfaces_under_the_wheels() -> None:
    """A physics of another kind is stepped with the surface ids the compiled part found."""
    omni4 = load_robot("omni4")
    sim = Simulator(omni4, world="room", start_pose=(2.5, 3.0, 0.0), physics_factory=FakePhysics)
    names = [s.name for s in sim.physics.surfaces]
    seen: list[list[str]] = []
    original = sim.physics.step

    def spy(pwm, surface_ids=None, external_force=None):
        seen.append([names[i] for i in np.asarray(surface_ids).reshape(-1)])
        original(pwm, surface_ids, external_force)

    sim.physics.step = spy  # type: ignore[method-assign]
    sim.step()
    assert seen == [sim.wheel_surfaces] and seen[0][0] == "carpet" and seen[0][2] == "wood"


def test_floor_override(omni4) -> None:
    sim = Simulator(omni4, surface="carpet", physics_factory=FakePhysics)
    assert sim.world.surface_names == ("carpet",)
    assert [s.name for s in sim.physics.surfaces] == ["carpet"]
    with pytest.raises(ConfigError, match="did you mean 'carpet'"):
        Simulator(omni4, surface="carpt", physics_factory=FakePhysics)


# --------------------------------------------------------------------------- collisions


@pytest.mark.parametrize("robot_name", ["omni4", "omni3", "mecanum4"])
def test_driving_into_a_wall_stops_without_explosion(robot_name, backend) -> None:
    robot = load_robot(robot_name)
    front = max(x for x, _ in robot.footprint.outline())
    sim = Simulator(robot, world="corridor", start_pose=(9.5 - front, 0.0, 0.0), physics_factory=backend)
    events: list[CollisionEvent] = []
    sim.on_collision(events.append)
    sim.set_pwm(pwm_for(robot, (1.0, 0.0, 0.0), peak=robot.wheels[0].motor.pwm_max))
    xs = []
    for _ in range(150):
        sim.step(10)
        xs.append(sim.pose.x)
        assert np.all(np.isfinite(sim.physics.pose)) and np.all(np.isfinite(sim.physics.twist))
    assert max(xs) + front < 10.0 + 0.01  # less than a centimetre into the end wall
    assert abs(xs[-1] - xs[-30]) < 1e-3  # at rest against it, still pushing
    assert abs(sim.twist.vx) < 0.01 and abs(sim.pose.theta) < 0.05
    assert len(sim.collisions) == 1 and events == sim.collisions
    ev = sim.collisions[0]
    assert ev.owner == "walls[0]" and ev.x == pytest.approx(10.0, abs=0.01) and ev.speed > 0.2
    assert ev.normal == pytest.approx((-1.0, 0.0))


def test_sliding_along_a_wall_at_an_angle_keeps_out(omni4, backend) -> None:
    sim = Simulator(omni4, world="room", start_pose=(2.5, 3.6, 0.3), physics_factory=backend)
    sim.set_pwm(pwm_for(omni4, (0.6, 0.6, 0.0), peak=220))
    for _ in range(150):
        sim.step(10)
        outline = np.array(omni4.footprint.outline())
        y, th = sim.pose.y, sim.pose.theta
        c, s = math.cos(th), math.sin(th)
        ys = y + s * outline[:, 0] + c * outline[:, 1]
        assert ys.max() < 4.0 + 0.01
    assert sim.collisions and sim.collisions[0].owner == "walls[0]"


def test_reversing_away_from_the_wall(omni4) -> None:
    sim = Simulator(omni4, world="corridor", start_pose=(9.7, 0.0, 0.0))
    sim.set_pwm(pwm_for(omni4, (1.0, 0.0, 0.0)))
    sim.advance(1.0)
    sim.set_pwm(pwm_for(omni4, (-1.0, 0.0, 0.0)))
    sim.advance(1.0)
    assert sim.pose.x < 9.5 and not sim.contacts


# --------------------------------------------------------------------------- faults and hands


def test_push_moves_the_robot_with_motors_off(omni4, backend) -> None:
    sim = Simulator(omni4, physics_factory=backend)
    sim.set_pwm([100, 100, 100, 100])
    sim.push((8.0, 0.0), duration=0.5)
    assert sim.pwm == [0, 0, 0, 0]
    sim.advance(0.5)
    moved, speed = sim.pose.x, sim.twist.vx
    assert moved > 0.02 and abs(sim.pose.y) < 0.1 * moved
    sim.advance(0.5)  # the push is over: the robot coasts and slows down
    assert 0 <= sim.twist.vx < speed
    assert sim.encoder_counts()[1] > 0 > sim.encoder_counts()[3]  # the wheels along x rolled with it


def test_push_torque_turns_it(omni4, backend) -> None:
    sim = Simulator(omni4, physics_factory=backend)
    sim.push((0.0, 0.0), torque=1.0, duration=0.3)
    sim.advance(0.3)
    assert sim.pose.theta > 0.05


def test_lifted_wheel(omni4, backend) -> None:
    sim = Simulator(omni4, physics_factory=backend)
    sim.lift_wheel("m2")
    assert sim.physics.lifted[0].tolist() == [False, True, False, False]
    sim.lift_wheel("m2", lifted=False)
    assert not sim.physics.lifted.any()
    with pytest.raises(ConfigError, match="did you mean 'm2'"):
        sim.lift_wheel("m22")


def test_battery_voltage_sags_under_load(omni4) -> None:
    sim = Simulator(omni4)
    assert sim.battery_voltage == pytest.approx(7.4)
    sim.set_pwm([255, 255, 255, 255])
    sim.step(2)
    assert sim.battery_voltage < 7.4


# --------------------------------------------------------------------------- sensors through the facade


def test_encoder_counts_follow_the_wheel_angles(omni4, backend) -> None:
    sim = Simulator(omni4, physics_factory=backend)
    sim.set_pwm(pwm_for(omni4, (0.0, 0.0, 3.0)))
    sim.advance(0.5)
    angles = sim.physics.wheel_angle[0]
    assert sim.encoder_counts() == [math.floor(a * 440 / (2 * math.pi) + 1e-9) for a in angles]


def test_tracking_counts_and_gyro_during_a_pure_rotation() -> None:
    robot = load_robot("omni3")
    w = 2.0
    sim = Simulator(robot, seed=4, physics_factory=partial(ScriptedPhysics, twist=(0.0, 0.0, w)))
    sim.advance(1.0)
    counts = sim.tracking_counts()
    for spec, count in zip(robot.encoders.tracking, counts, strict=True):
        rim = math.cos(spec.direction) * (-w * spec.y) + math.sin(spec.direction) * (w * spec.x)
        expect = rim * 1.0 / (2 * math.pi * spec.radius) * spec.counts_per_rev
        assert count == pytest.approx(expect, rel=0.01)
    assert counts[0] < 0 < counts[1]
    assert robot.gyro is not None
    assert sim.gyro_rate() == pytest.approx(w, rel=0.05, abs=0.05)
    assert sim.gyro is not None and sim.gyro.angle == pytest.approx(sim.pose.theta, rel=0.05)
    mecanum = Simulator(load_robot("mecanum4"), physics_factory=FakePhysics)
    assert mecanum.tracking_counts() == []


def test_sonar_ping_approaching_the_end_wall(omni4) -> None:
    sim = Simulator(omni4, world="corridor", start_pose=(5.5, 0.0, 0.0), physics_factory=FakePhysics)
    sensor_x = 5.5 + omni4.sonars[0].x
    assert sim.sonar_ping(0) in (None, pytest.approx(10.0 - sensor_x, abs=0.02))
    sim.advance(0.1)
    readings = []
    sim.set_pwm(pwm_for(omni4, (1.0, 0.0, 0.0)))
    for _ in range(40):
        sim.advance(0.06)
        readings.append((sim.pose.x, sim.sonar_ping("front")))
    hits = [(x, r) for x, r in readings if r is not None]
    assert len(hits) >= 35
    for x, r in hits:
        assert r == pytest.approx(10.0 - x - omni4.sonars[0].x, abs=0.02)
    first = sim.sonar_ping(0)
    sim.step(1)
    assert sim.sonar_ping(0) == first  # 1 ms later: inside the 60 ms cycle, the previous result
    with pytest.raises(SimulationError, match="no sonar 'back'"):
        sim.sonar_ping("back")
    with pytest.raises(SimulationError, match="no index 3"):
        sim.sonar_ping(3)


def test_same_seed_same_sensors_other_seed_other_noise(omni4) -> None:
    def run(seed):
        sim = Simulator(omni4, seed=seed, world="corridor", physics_factory=FakePhysics)
        sim.set_pwm(pwm_for(omni4, (0.3, 0.0, 0.5)))
        out = []
        for _ in range(8):
            sim.advance(0.06)
            out.append((sim.gyro_rate(), sim.sonar_ping(0)))
        return out

    assert run(1) == run(1)
    assert run(1) != run(2)


def test_robot_without_gyro(omni4) -> None:
    bare = omni4.model_copy(update={"gyro": None})
    sim = Simulator(bare, physics_factory=FakePhysics)
    with pytest.raises(SimulationError, match="has no gyro"):
        sim.gyro_rate()


# --------------------------------------------------------------------------- listeners and truth


def test_listeners_every_step_and_decimated(omni4) -> None:
    sim = Simulator(omni4, physics_factory=FakePhysics)
    every: list[Snapshot] = []
    tenth: list[Snapshot] = []
    sim.add_listener(every.append)
    sim.add_listener(tenth.append, period=0.1)
    sim.advance(1.0)
    assert len(every) == 1001 and every[0].t == 0.0 and every[-1].t == pytest.approx(1.0)
    assert [round(s.t, 6) for s in tenth] == [round(0.1 * k, 6) for k in range(11)]
    sim.remove_listener(every.append)
    sim.step(10)
    assert len(every) == 1001


def test_truth_recorder_writes_csv(omni4, tmp_path: Path) -> None:
    path = tmp_path / "truth.csv"
    rec = TruthRecorder(path, period=0.05)
    sim = Simulator(omni4, truth_recorder=rec, physics_factory=FakePhysics)
    sim.set_pwm(pwm_for(omni4, (0.5, 0.0, 0.0)))
    sim.advance(0.5)
    rec.close()
    lines = path.read_text().splitlines()
    assert lines[0] == "t,x,y,theta"
    rows = [tuple(float(v) for v in line.split(",")) for line in lines[1:]]
    assert [r[0] for r in rows] == pytest.approx([0.05 * k for k in range(11)])
    assert rows[-1][1] == pytest.approx(sim.pose.x, abs=1e-6)
    # called every step, it still writes one row per period
    stream = io.StringIO()
    rec2 = TruthRecorder(stream, period=0.1)
    sim.add_listener(rec2)
    sim.advance(0.35)
    rec2.close()
    assert len(stream.getvalue().splitlines()) == 1 + 4  # header, t = 0.5, 0.6, 0.7, 0.8


# --------------------------------------------------------------------------- broad phases


def test_cached_surfaces_and_contacts_equal_a_full_test_every_step(omni4) -> None:
    """The surface and contact broad phases skip work but never change what the physics gets."""
    sim = Simulator(omni4, world="room", start_pose=(2.0, 2.5, 0.3))
    world, ph = sim.world, sim.physics
    outline = convex_hull(omni4.footprint.outline())
    surfaces_seen: set[tuple[str, ...]] = set()
    steps_touching = []
    for twist in [(0.6, 0.3, 0.5), (0.2, -0.8, -1.0), (-0.7, 0.2, 2.0)]:
        sim.set_pwm(pwm_for(omni4, twist, peak=220))
        for _ in range(2000):
            x, y, th = ph.pose[0]
            expect = world.surface_ids(ph.contact_points_world()[0])
            c, s = math.cos(th), math.sin(th)
            contacts = world.contacts(outline @ np.array([[c, s], [-s, c]]) + (x, y))
            sim.step()  # tests the pose it started from
            assert sim.wheel_surfaces == [world.surface_names[i] for i in expect]
            assert [k.owner for k in sim.contacts] == [k.owner for k in contacts]
            assert [k.depth for k in sim.contacts] == pytest.approx([k.depth for k in contacts], abs=1e-12)
            surfaces_seen.add(tuple(sim.wheel_surfaces))
            steps_touching.append(bool(contacts))
    assert len(surfaces_seen) > 2  # wood, carpet and wheels on both
    assert sum(steps_touching) > 100 and sim.collisions
