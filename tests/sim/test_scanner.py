"""The simulated laser scanner: ranges against analytic geometry, motion distortion against the true
trajectory, other robots seen, noise, dropouts and limits, determinism and its cost when unused."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from omnibot.errors import SimulationError
from omnibot.motion import Pose2D
from omnibot.robot import RobotDescription, load_robot, parse_description
from omnibot.scan import Scan
from omnibot.sim.fleet import Fleet
from omnibot.sim.kernels import layout
from omnibot.sim.scanner import BLOCK_PER_RAY, DRAW_BATCH, LaserScanner, PoseLog
from omnibot.sim.simulator import Simulator
from omnibot.sim.truth import Snapshot
from omnibot.sim.world import load_world, parse_world
from tests.sim.fakes import FakePhysics

EXACT: dict[str, Any] = {"noise_fraction": 0.0, "noise_std": 0.0, "resolution": 0.0, "dropout": 0.0}
BOX = parse_world({"name": "box", "walls": [{"shape": "rectangle", "min": [-2, -1.5], "max": [2, 1.5]}]})


def robot_with(**scanner: Any) -> RobotDescription:
    """omni4 with these scanner settings."""
    data = load_robot("omni4").model_dump(exclude_none=True)
    data["scanner"] = {**data["scanner"], **scanner}
    return parse_description(data, "test")


def scans_of(sim: Simulator, seconds: float) -> list[Scan]:
    got: list[Scan] = []
    sim.add_scan_listener(got.append)
    sim.advance(seconds)
    return got


def box_ranges(x: float, y: float, directions: np.ndarray) -> np.ndarray:
    """Distance from (x, y) inside BOX to its walls along each world direction."""
    c, s = np.cos(directions), np.sin(directions)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, (2 - x) / c, np.where(c < 0, (-2 - x) / c, np.inf))
        ty = np.where(s > 0, (1.5 - y) / s, np.where(s < 0, (-1.5 - y) / s, np.inf))
    return np.asarray(np.minimum(tx, ty))


def world_rays(scan: Scan, pose: Pose2D) -> tuple[float, float, np.ndarray]:
    """The scanner's origin and every ray's world direction for a robot standing at ``pose``."""
    m = scan.mount
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    ox, oy = pose.x + c * m.x - s * m.y, pose.y + s * m.x + c * m.y
    return ox, oy, pose.theta + m.theta + scan.angles


# --------------------------------------------------------------------------- geometry


@pytest.mark.parametrize("spin", ["clockwise", "counterclockwise"])
def test_a_standing_robot_measures_the_box_it_stands_in(spin: str) -> None:
    robot = robot_with(x=0.05, y=-0.02, yaw_deg=90, spin=spin, **EXACT)
    sim = Simulator(robot, world=BOX, start_pose=(0.3, 0.2, 0.4))
    scan = scans_of(sim, 0.25)[-1]
    assert len(scan) == 360 and scan.frame == "laser"
    assert scan.angle_increment == pytest.approx((-1 if spin == "clockwise" else 1) * 2 * math.pi / 360)
    assert scan.time_increment == pytest.approx(0.1 / 360) and scan.scan_time == pytest.approx(0.1)
    assert scan.mount == Pose2D(0.05, -0.02, math.pi / 2)
    ox, oy, directions = world_rays(scan, sim.pose)
    np.testing.assert_allclose(scan.ranges, box_ranges(ox, oy, directions), atol=1e-9)
    # the points, back in the world, lie on the walls
    c, s = math.cos(sim.pose.theta), math.sin(sim.pose.theta)
    world = scan.points("base") @ np.array([[c, s], [-s, c]]) + np.array([sim.pose.x, sim.pose.y])
    on_wall = np.isclose(np.abs(world[:, 0]), 2.0) | np.isclose(np.abs(world[:, 1]), 1.5)
    assert on_wall.all()


def test_noise_is_the_datasheet_share_of_the_range_and_quantised_to_quarter_millimetres() -> None:
    robot = robot_with(dropout=0.0)
    sim = Simulator(robot, world=BOX, seed=3)
    scans = scans_of(sim, 2.05)
    ox, oy, directions = world_rays(scans[0], sim.pose)
    true = box_ranges(ox, oy, directions)
    ranges = np.array([s.ranges for s in scans])
    z = (ranges - true) / (0.01 * true)
    assert abs(z.mean()) < 0.05 and 0.95 < z.std() < 1.05  # 7200 rays
    np.testing.assert_allclose(ranges / 0.00025, np.round(ranges / 0.00025), atol=1e-6)


def test_dropouts_and_returns_outside_the_range_limits_are_inf() -> None:
    robot = robot_with(**{**EXACT, "dropout": 0.3})
    ranges = np.array([s.ranges for s in scans_of(Simulator(robot, world=BOX, seed=5), 1.05)])
    missing = np.isinf(ranges).mean()
    assert 0.27 < missing < 0.33  # 3600 rays, 0.3 +- 4 sigma
    robot = robot_with(**{**EXACT, "range_min": 1.6, "range_max": 2.0})
    sim = Simulator(robot, world=BOX)
    scan = scans_of(sim, 0.15)[-1]
    ox, oy, directions = world_rays(scan, sim.pose)
    true = box_ranges(ox, oy, directions)
    inside = (true >= 1.6) & (true <= 2.0)
    assert inside.any() and (~inside).any()
    np.testing.assert_allclose(scan.ranges[inside], true[inside], atol=1e-9)
    assert np.isinf(scan.ranges[~inside]).all()


def test_nothing_in_range_is_inf_and_the_long_corridor_is_blind_along_its_axis() -> None:
    sim = Simulator(robot_with(**EXACT), world="empty")
    assert np.isinf(scans_of(sim, 0.15)[-1].ranges).all()
    sim = Simulator(robot_with(**EXACT), world="long_corridor", start_pose=(15.0, 0.0, 0.0))
    scan = scans_of(sim, 0.15)[-1]
    along = np.abs(np.cos(scan.angles)) > math.cos(math.radians(5))
    assert np.isinf(scan.ranges[along]).all()  # 15 m to either end, beyond 12 m
    assert np.isfinite(scan.ranges[~along]).mean() > 0.9


# --------------------------------------------------------------------------- motion distortion


def true_trajectory(sim: Simulator) -> list[Snapshot]:
    trajectory: list[Snapshot] = []
    sim.add_listener(trajectory.append)
    return trajectory


def pose_at(trajectory: list[Snapshot], t: float) -> Pose2D:
    ts = np.array([s.t for s in trajectory])
    return Pose2D(
        *(float(np.interp(t, ts, [getattr(s, k) for s in trajectory])) for k in ("x", "y", "theta"))
    )


@pytest.mark.parametrize("distortion", [True, False])
def test_each_ray_is_cast_from_where_the_robot_was_at_its_time(distortion: bool) -> None:
    robot = robot_with(x=0.08, motion_distortion=distortion, **EXACT)
    sim = Simulator(robot, world="room", start_pose=(2.0, 2.0, 0.0))
    trajectory = true_trajectory(sim)
    sim.set_pwm([200, 120, 200, 120])  # turning fast and drifting
    scans = scans_of(sim, 0.55)
    scan = scans[-1]
    assert abs(sim.twist.w) > 3.0
    room = load_world("room")
    times = scan.stamp + scan.time_increment * np.arange(len(scan))
    assert scan.time_increment == (pytest.approx(0.1 / 360) if distortion else 0.0)
    expected = np.empty(len(scan))
    for i, t in enumerate(times):
        ox, oy, directions = world_rays(scan, pose_at(trajectory, t))
        expected[i] = room.raycast([ox, oy], directions[i])[0]
    # the scanner interpolates poses recorded every 5 ms, the test the true pose of every 1 ms step
    np.testing.assert_allclose(scan.ranges, expected, atol=1e-4)


def test_a_turning_robot_sees_its_room_smeared_as_the_physics_says() -> None:
    """Spinning at w while the head turns clockwise at 2 pi f, the rays sweep the world at 2 pi f - w
    (counter-clockwise turn, clockwise head): the revolution covers only 360 (1 - w / 2 pi f) degrees
    of the world; the last rays measure what the first ones did."""
    robot = robot_with(**EXACT)
    spinning = Simulator(robot, world=BOX)
    spinning.set_pwm([200, 200, 200, 200])
    scan = scans_of(spinning, 1.05)[-1]
    w = spinning.twist.w
    assert w > 5.0
    still = Simulator(robot, world=BOX, start_pose=(0.0, 0.0, spinning.pose.theta))
    directions = world_rays(scan, Pose2D(0.0, 0.0, 0.0))[2]
    swept = directions + w * scan.time_increment * np.arange(len(scan))  # heading at each ray's time
    theta0 = spinning.pose.theta - w * (spinning.time - scan.stamp)
    np.testing.assert_allclose(scan.ranges, box_ranges(0.0, 0.0, swept + theta0), rtol=2e-3)
    static = scans_of(still, 0.15)[-1]
    assert np.max(np.abs(static.ranges - scan.ranges)) > 0.3  # the distortion is not small


# --------------------------------------------------------------------------- fleets


def test_every_robot_of_a_fleet_sees_the_others_and_never_itself() -> None:
    robot = robot_with(**EXACT)
    fleet = Fleet(load_world("empty"))
    a = fleet.add("a", robot, pose=Pose2D(0.0, 0.0, 0.0))
    b = fleet.add("b", robot, pose=Pose2D(1.0, 0.0, math.pi / 2))
    got: dict[str, list[Scan]] = {"a": [], "b": []}
    a.sim.add_scan_listener(got["a"].append)
    b.sim.add_scan_listener(got["b"].append)
    for _ in range(150):
        fleet.step()
    sa, sb = got["a"][-1], got["b"][-1]
    # a looks along +x at b's face at x = 0.9 (b is a 0.2 m square, turned 90 degrees)
    ahead = np.argmin(np.abs(np.remainder(sa.angles + math.pi, 2 * math.pi) - math.pi))
    assert sa.ranges[ahead] == pytest.approx(0.9, abs=1e-6)
    assert np.isfinite(sa.ranges).sum() == pytest.approx(2 * math.degrees(math.atan(0.1 / 0.9)), abs=2)
    # b sees a behind it (world direction pi is b's -pi/2)
    seen = np.isfinite(sb.ranges)
    assert seen.any() and np.allclose(np.cos(sb.angles[seen] + math.pi / 2), -1.0, atol=0.02)
    # nothing else is there: a robot alone sees nothing of itself
    alone = Simulator(robot, world="empty")
    assert np.isinf(scans_of(alone, 0.15)[-1].ranges).all()


# --------------------------------------------------------------------------- seeds and switching


def test_the_same_seed_gives_the_same_scans_whenever_the_scanner_was_switched_on() -> None:
    def run(seed: int, listen_at: float) -> dict[float, np.ndarray]:
        sim = Simulator(load_robot("omni4"), world="room", seed=seed)
        sim.set_pwm([80, 150, -60, -150])
        sim.advance(listen_at)
        return {round(s.stamp, 6): s.ranges for s in scans_of(sim, 0.65 - listen_at)}

    early, late = run(7, 0.0), run(7, 0.23)
    assert sorted(late) == [0.3, 0.4, 0.5]
    for stamp, ranges in late.items():
        np.testing.assert_array_equal(ranges, early[stamp])
    other = run(8, 0.0)
    assert not np.array_equal(other[0.3], early[0.3])


def test_the_scanner_changes_no_other_sensor_and_costs_nothing_unwanted() -> None:
    data = load_robot("omni4").model_dump(exclude_none=True)
    del data["scanner"]
    bare = Simulator(parse_description(data), world="room", seed=4)
    scanning = Simulator(load_robot("omni4"), world="room", seed=4)
    idle = Simulator(load_robot("omni4"), world="room", seed=4)
    scanning.add_scan_listener(lambda scan: None)
    readings = []
    for sim in (bare, scanning, idle):
        sim.set_pwm([60, 150, -40, -150])
        rows = []
        for _ in range(40):
            sim.step(10)
            rows.append((sim.gyro_rate(), sim.sonar_ping(0), *sim.encoder_counts(), sim.pose))
        readings.append(rows)
    assert readings[0] == readings[1] == readings[2]
    assert idle.scanner is not None and not idle.scanner.active and idle.scanner.scans == 0
    assert scanning.scanner is not None and scanning.scanner.scans == 4
    # a listener removed: the scanner stops; last_scan read: it runs for good
    fn = scanning._scan_listeners[0]
    scanning.remove_scan_listener(fn)
    assert not scanning.scanner.active
    assert idle.last_scan is None and idle.scanner.active
    idle.advance(0.21)
    assert idle.last_scan is not None and idle.last_scan.stamp == pytest.approx(0.5)


def test_a_robot_without_a_scanner_says_so() -> None:
    data = load_robot("omni4").model_dump(exclude_none=True)
    del data["scanner"]
    sim = Simulator(parse_description(data), world="room")
    assert sim.scanner is None and sim.last_scan is None
    with pytest.raises(SimulationError, match="robot 'omni4' has no scanner"):
        sim.add_scan_listener(lambda scan: None)


def test_a_rate_that_is_no_whole_number_of_steps_still_gives_every_revolution_on_time() -> None:
    robot = robot_with(rate_hz=5.5, **EXACT)
    sim = Simulator(robot, world=BOX)
    scans = scans_of(sim, 1.01)
    assert [round(s.stamp, 9) for s in scans] == [round(k / 5.5, 9) for k in range(5)]
    assert all(np.isfinite(s.ranges).all() for s in scans)


def test_a_robot_leaving_a_fleet_keeps_scanning_alone_and_the_others_drop_it() -> None:
    robot = robot_with(**EXACT)
    fleet = Fleet(load_world("empty"))
    a = fleet.add("a", robot, pose=Pose2D(0.0, 0.0, 0.0))
    fleet.add("b", robot, pose=Pose2D(1.0, 0.0, 0.0))
    got: list[Scan] = []
    a.sim.add_scan_listener(got.append)
    for _ in range(250):
        fleet.step()
    assert np.isfinite(got[-1].ranges).any()  # b is seen
    fleet.remove("b")
    count = len(got)
    for _ in range(250):
        fleet.step()
    assert len(got) > count and np.isinf(got[-1].ranges).all()  # alone in an empty world


def test_other_bodies_given_by_hand_are_seen_where_they_stand() -> None:
    sim = Simulator(robot_with(**EXACT), world="empty")
    sim.neighbours = lambda: np.array([[1.0, -5.0, 1.0, 5.0]])  # a wall 1 m ahead
    scan = scans_of(sim, 0.15)[-1]
    ahead = np.abs(np.cos(scan.angles)) > 0.999
    np.testing.assert_allclose(
        scan.ranges[ahead & (np.cos(scan.angles) > 0)],
        1.0 / np.cos(scan.angles[ahead & (np.cos(scan.angles) > 0)]),
        atol=1e-9,
    )


# --------------------------------------------------------------------------- the pose log


def test_a_fleet_whose_pose_logs_fill_before_a_slow_scanner_is_due_flushes_it_early_to_the_same_scans() -> (
    None
):
    def slow_scans(partner_rate_hz: float) -> tuple[list[Scan], int]:
        fleet = Fleet(load_world("room"))
        slow = fleet.add("a", robot_with(rate_hz=1.0, **EXACT), pose=Pose2D(1.0, 1.0, 0.0))
        fleet.add("b", robot_with(rate_hz=partner_rate_hz, **EXACT), pose=Pose2D(2.5, 2.0, 0.3))
        slow.sim.set_pwm([60, 150, -20, -150])
        got: list[Scan] = []
        slow.sim.add_scan_listener(got.append)
        flushes: list[int] = []
        flush = slow.sim.scan_flush

        def counted(now_us: int, *rest: Any) -> int:
            flushes.append(now_us)
            return flush(now_us, *rest)

        slow.sim.scan_flush = counted  # type: ignore[method-assign,assignment]
        for _ in range(2100):
            fleet.step()
        return got, len(flushes)

    # b's log holds 0.25 s at 10 Hz (two of its revolutions are less), two of a's revolutions at 1 Hz
    (early, flushed_early), (late, flushed_late) = slow_scans(10.0), slow_scans(1.0)
    assert [s.stamp for s in early] == [s.stamp for s in late] == [0.0, 1.0]
    assert flushed_late == 2 and flushed_early >= 8
    for a, b in zip(early, late, strict=True):
        np.testing.assert_allclose(a.ranges, b.ranges, rtol=0, atol=1e-9)
    assert np.isfinite(early[1].ranges).all()


def test_a_pose_log_that_overflowed_says_so() -> None:
    sim = Simulator(load_robot("omni4"), world="room")
    sim._pose_log_start(0)
    log = PoseLog([sim], sim._log_stride_us / 1e6)
    assert log.array().shape == (1, 3)
    sim.step(5 * log.capacity)
    with pytest.raises(SimulationError, match="pose log overflowed"):
        log.array()


def test_a_physics_of_another_kind_logs_the_poses_the_rays_are_cast_from_too() -> None:
    sim = Simulator(robot_with(**EXACT), world=BOX, physics_factory=FakePhysics)
    sim.set_pwm([120, 150, -60, -150])
    got: list[Scan] = []
    sim.add_scan_listener(got.append)
    poses = {}
    for _ in range(250):
        sim.step()
        p = sim.pose
        poses[sim.clock.ticks_us()] = [p.x, p.y, p.theta]
    assert [s.stamp for s in got] == [0.0, 0.1]
    rows, si = sim.pose_log()
    start = sim._scan_log.start_us
    n = int(si[layout.I_LOG_N])
    assert start == 200_000 and n == 11  # trimmed at the last flush to the rays still to come
    np.testing.assert_array_equal(rows[:n], [poses[start + 5000 * j] for j in range(n)])
    assert poses[250_000] != poses[5000]  # it moved


def test_a_revolution_whose_rays_were_all_cast_before_its_end_is_measured_at_its_end_the_same() -> None:
    def scans(cast_early: bool) -> list[Scan]:
        sim = Simulator(robot_with(rays=3), world=BOX, seed=5)
        sim.set_pwm([120, 150, -60, -150])
        got: list[Scan] = []
        sim.add_scan_listener(got.append)
        sim.step(70)
        if cast_early:  # the third ray (66.7 ms) is due: every ray of revolution 0 cast, none delivered
            sim.scan_flush(sim.clock.ticks_us(), sim._scan_log)
            assert not got
        sim.step(150)
        return got

    early, usual = scans(True), scans(False)
    assert [s.stamp for s in early] == [s.stamp for s in usual] == [0.0, 0.1]
    for a, b in zip(early, usual, strict=True):
        np.testing.assert_array_equal(a.ranges, b.ranges)
    assert np.isfinite(early[0].ranges).all()


def test_the_noise_of_a_revolution_is_its_own_place_in_the_stream_whichever_came_before() -> None:
    spec = load_robot("omni4").scanner
    assert spec is not None
    scanner = LaserScanner(spec, seed=4, key=200)
    n, batch = spec.rays, DRAW_BATCH
    block = batch * BLOCK_PER_RAY * n

    def alone(revolution: int) -> tuple[np.ndarray, np.ndarray]:
        """The layout the scanner's docstring gives: the batch's block, uniforms then normals."""
        bits = np.random.PCG64(np.random.SeedSequence(4, spawn_key=(200,)))
        bits.advance(revolution // batch * block)
        gen = np.random.Generator(bits)
        uniforms, normals = gen.random((batch, n)), gen.standard_normal((batch, n))
        return normals[revolution % batch], uniforms[revolution % batch]

    seen = []
    for revolution in (0, 1, 7, 8, 30, 31, 2, 40):  # in order, across batches, jumped ahead and back
        normals, uniforms = scanner._draws(revolution)
        want_normals, want_uniforms = alone(revolution)
        np.testing.assert_array_equal(normals, want_normals)
        np.testing.assert_array_equal(uniforms, want_uniforms)
        seen.append(normals.copy())
    assert len({row.tobytes() for row in seen}) == len(seen)  # no two revolutions share their draws
    # a batch's normals take about 1.02 outputs each: well inside the block's room for them
    bits = np.random.PCG64(np.random.SeedSequence(4, spawn_key=(200,)))
    gen = np.random.Generator(bits)
    gen.random(batch * n)
    gen.standard_normal(batch * n)
    after = bits.random_raw()
    probe = np.random.PCG64(np.random.SeedSequence(4, spawn_key=(200,)))
    used = int(np.flatnonzero(probe.random_raw(block) == after)[0]) - batch * n
    assert batch * n < used < 1.1 * batch * n <= block - batch * n
