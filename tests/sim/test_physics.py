"""Physics core: API, stability at 1 kHz, symmetry, energy, faults, surfaces, batching, determinism."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
import yaml

from omnibot.errors import ConfigError, SimulationError
from omnibot.floor import GRAVITY
from omnibot.robot import RobotDescription, load_robot, parse_description
from omnibot.robot import kinematics as kin
from omnibot.robot.description import PRESET_DIR
from omnibot.sim.physics import Physics

PRESETS = ("omni4", "omni3", "mecanum4")


def preset_data(name: str) -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load((PRESET_DIR / f"{name}.yaml").read_text())
    return data


def variant(name: str, **changes: object) -> RobotDescription:
    """A preset with top-level keys, ``motor`` keys or every wheel's keys changed."""
    data = preset_data(name)
    for key, value in changes.items():
        if key in data["motor"]:
            data["motor"][key] = value
        elif key in data["wheels"][0]:
            for w in data["wheels"]:
                w[key] = value
        else:
            data[key] = value
    return parse_description(data)


def pattern(robot: RobotDescription, twist: tuple[float, float, float], power: float) -> np.ndarray:
    """PWM counts proportional to the wheel speeds of a body twist, the largest at ``power``."""
    w = kin.inverse(robot.wheel_matrix, twist)
    return np.asarray(power * w / np.abs(w).max())


def run(ph: Physics, pwm: np.ndarray, seconds: float, **kw: object) -> None:
    for _ in range(round(seconds / ph.dt)):
        ph.step(pwm, **kw)  # type: ignore[arg-type]


def kinetic_energy(ph: Physics, robot: RobotDescription) -> np.ndarray:
    J = np.array([w.inertia + w.motor.gear_ratio**2 * w.motor.rotor_inertia for w in robot.wheels])
    v2 = ph.twist[:, 0] ** 2 + ph.twist[:, 1] ** 2
    return np.asarray(
        0.5 * robot.mass * v2
        + 0.5 * robot.yaw_inertia * ph.twist[:, 2] ** 2
        + 0.5 * (J * ph.wheel_speed**2).sum(1)
    )


# ---------------------------------------------------------------------- API and construction


def test_state_shapes_and_initial_values() -> None:
    robot = load_robot("omni4")
    ph = Physics(robot, n=5)
    assert ph.pose.shape == (5, 3) and ph.twist.shape == (5, 3)
    for arr in (ph.wheel_angle, ph.wheel_speed, ph.motor_current, ph.lifted, ph.slip, ph.normal_load):
        assert arr.shape == (5, 4)
    assert ph.battery_voltage.shape == (5,)
    assert ph.contact_points_world().shape == (5, 4, 2)
    assert ph.time == 0.0
    np.testing.assert_allclose(ph.battery_voltage, robot.battery.voltage)
    assert [s.name for s in ph.surfaces] == ["wood"]


def test_construction_errors() -> None:
    omni4, omni3 = load_robot("omni4"), load_robot("omni3")
    with pytest.raises(SimulationError, match="same number of wheels"):
        Physics([omni4, omni3])
    with pytest.raises(SimulationError, match="2 robot descriptions for n=3"):
        Physics([omni4, omni4], n=3)
    with pytest.raises(SimulationError, match="dt"):
        Physics(omni4, dt=0.0)
    with pytest.raises(SimulationError, match="surface"):
        Physics(omni4, surfaces=())
    with pytest.raises(ConfigError, match="did you mean 'wood'"):
        Physics(omni4, surfaces=("wod",))
    with pytest.raises(SimulationError, match="at least one"):
        Physics([])


def test_time_counts_steps_and_reset_restores_rest() -> None:
    ph = Physics(load_robot("omni4"))
    run(ph, np.full(4, 200.0), 1.0)
    assert ph.time == 1.0
    assert abs(ph.twist[0, 2]) > 0.1
    ph.reset(pose=(1.0, 2.0, 3.0), wheel_angle=(0.1, 0.2, 0.3, 0.4))
    assert ph.time == 0.0
    np.testing.assert_array_equal(ph.pose, [[1.0, 2.0, 3.0]])
    np.testing.assert_array_equal(ph.wheel_angle, [[0.1, 0.2, 0.3, 0.4]])
    assert not ph.twist.any() and not ph.wheel_speed.any() and not ph.motor_current.any()


def test_state_arrays_are_stable_references_written_in_place() -> None:
    ph = Physics(load_robot("omni4"))
    pose, twist, speeds = ph.pose, ph.twist, ph.wheel_speed
    run(ph, np.full(4, 200.0), 0.1)
    assert ph.pose is pose
    np.testing.assert_array_equal(twist, ph.twist)
    np.testing.assert_array_equal(speeds, ph.wheel_speed)
    ph.twist[0, 0] = 0.3  # writable in place
    assert ph.twist[0, 0] == 0.3


def test_contact_points_follow_the_pose() -> None:
    ph = Physics(load_robot("omni4"))
    ph.reset(pose=(1.0, 2.0, math.pi / 2))
    # m1 sits at body (0.096, 0): after a quarter turn it is at world (1, 2.096)
    np.testing.assert_allclose(ph.contact_points_world()[0, 0], [1.0, 2.096], atol=1e-12)
    np.testing.assert_allclose(ph.contact_points_world()[0, 1], [1.096, 2.0], atol=1e-12)


# ---------------------------------------------------------------------- stability at 1 kHz


@pytest.mark.parametrize("name", PRESETS)
def test_ten_seconds_at_full_power_stay_finite_and_bounded(name: str) -> None:
    robot = load_robot(name)
    m = robot.n_wheels
    rng = np.random.default_rng(7)
    patterns = np.stack(
        [
            np.full(m, 255.0),  # spin on the spot
            pattern(robot, (1.0, 0.0, 0.0), 255.0),  # straight
            pattern(robot, (0.3, 1.0, 2.0), 255.0),  # everything at once
            rng.choice([-255.0, 255.0], size=m),  # wheels fighting each other
        ]
    )
    ph = Physics(robot, n=len(patterns))
    no_load = max(
        robot.battery.voltage / (w.motor.torque_constant * w.motor.gear_ratio) for w in robot.wheels
    )
    i_max = max(w.motor.current_max for w in robot.wheels)
    for k in range(10_000):
        # reverse everything at 5 s: plug braking from top speed, the hardest case for the integrator
        ph.step(patterns if k < 5000 else -patterns)
        if k % 500 == 0 or k in (5000, 5001, 5002):
            assert np.isfinite(ph.pose).all() and np.isfinite(ph.twist).all()
            assert np.abs(ph.wheel_speed).max() <= 1.05 * no_load
            assert np.abs(ph.motor_current).max() <= i_max + 1e-9
            assert np.hypot(ph.twist[:, 0], ph.twist[:, 1]).max() < 10.0
    assert np.isfinite(ph.wheel_angle).all()


def test_a_slipping_wheel_does_not_chatter() -> None:
    """omni3 at full power slips hard; the traction force must stay smooth and below mu N."""
    robot = load_robot("omni3")
    ph = Physics(robot)
    pwm = pattern(robot, (1.0, 0.0, 0.0), 255.0)
    forces = []
    for _ in range(500):
        ph.step(pwm)
        forces.append(ph.traction_force[0, 0])
    f = np.array(forces[50:])
    limit = 0.6 * 0.75 * ph.normal_load[0, 0]  # wood mu times the rollers' grip
    assert np.abs(f).max() <= limit * (1 + 1e-9)
    assert np.abs(np.diff(f)).max() < 0.01 * limit  # no step-to-step sign flipping


def test_a_lifted_unpowered_wheel_stops_without_oscillating() -> None:
    ph = Physics(load_robot("omni4"))
    ph.lifted = [True, False, False, False]
    ph.wheel_speed[0, 0] = 30.0
    speeds = []
    for _ in range(300):
        ph.step(np.zeros(4))
        speeds.append(ph.wheel_speed[0, 0])
    s = np.array(speeds)
    assert (s >= -1e-12).all() and (np.diff(s) <= 1e-12).all()  # rounding noise far below 1e-12
    assert s[-1] < 1e-3


# ---------------------------------------------------------------------- symmetry and directions


def test_omni4_equal_positive_power_turns_counter_clockwise_on_the_spot() -> None:
    ph = Physics(load_robot("omni4"))
    run(ph, np.full(4, 200.0), 1.0)
    x, y, theta = ph.pose[0]
    assert theta > 1.0
    assert math.hypot(x, y) < 1e-6
    assert (ph.wheel_speed[0] > 0).all()


def test_omni4_opposite_motors_drive_along_the_course() -> None:
    ph = Physics(load_robot("omni4"), n=2)
    pwm = np.array([[0, 200, 0, -200], [200, 0, -200, 0]], dtype=float)  # course 0, course 90
    run(ph, pwm, 1.0)
    assert ph.pose[0, 0] > 0.5 and abs(ph.pose[0, 1]) < 1e-6
    assert ph.pose[1, 1] > 0.5 and abs(ph.pose[1, 0]) < 1e-6
    np.testing.assert_allclose(ph.pose[0, 0], ph.pose[1, 1], rtol=1e-9)  # the robot is symmetric
    assert np.abs(ph.pose[:, 2]).max() < 1e-9


@pytest.mark.parametrize(
    ("motion", "twist"),
    [
        ("forward", (1.0, 0.0, 0.0)),
        ("backward", (-1.0, 0.0, 0.0)),
        ("sideways", (0.0, 1.0, 0.0)),
        ("diagonal", (1.0, 1.0, 0.0)),
        ("rotate", (0.0, 0.0, 1.0)),
    ],
)
def test_mecanum4_main_directions(motion: str, twist: tuple[float, float, float]) -> None:
    """Seed 003's main directions (its Fig. 4), wheel patterns from the kinematics."""
    robot = load_robot("mecanum4")
    pwm = pattern(robot, twist, 200.0)
    if motion == "diagonal":
        assert np.sum(np.abs(pwm) < 1e-9) == 2  # two wheels stand still on the diagonal
    ph = Physics(robot)
    run(ph, pwm, 1.0)
    x, y, theta = ph.pose[0]
    if motion == "rotate":
        assert theta > 1.0 and math.hypot(x, y) < 1e-3
        return
    distance = math.hypot(x, y)
    assert distance > 0.2
    heading_error = math.atan2(y, x) - math.atan2(twist[1], twist[0])
    assert abs(math.remainder(heading_error, math.tau)) < math.radians(3)
    assert abs(theta) < 0.02


def test_omni3_drives_straight_forward_without_turning() -> None:
    robot = load_robot("omni3")
    ph = Physics(robot)
    run(ph, pattern(robot, (1.0, 0.0, 0.0), 150.0), 1.0)
    x, y, theta = ph.pose[0]
    assert x > 0.5 and abs(y) < 1e-3 * x and abs(theta) < 1e-3


# ---------------------------------------------------------------------- energy and momentum


@pytest.mark.parametrize("name", PRESETS)
def test_unpowered_robot_coasts_to_rest_without_reversing(name: str) -> None:
    robot = load_robot(name)
    twist0 = np.array([[0.6, 0.0, 0.0], [0.0, -0.5, 0.0], [0.4, 0.4, 0.0], [0.0, 0.0, 3.0], [0.6, -0.3, 2.0]])
    ph = Physics(robot, n=len(twist0))
    ph.twist[:] = twist0
    ph.wheel_speed[:] = kin.inverse(robot.wheel_matrix, twist0)  # rolling, no slip
    v0 = ph.velocity_world()
    energy = [kinetic_energy(ph, robot)]
    for _ in range(3000):
        ph.step(np.zeros(robot.n_wheels))
        energy.append(kinetic_energy(ph, robot))
        v = ph.velocity_world()
        # pure translations and the pure spin never turn back against the initial motion
        assert (v[:4, 0] * v0[:4, 0] + v[:4, 1] * v0[:4, 1] >= -1e-9).all()
        assert (v[:4, 2] * v0[:4, 2] >= -1e-9).all()
    e = np.array(energy)
    assert (np.diff(e, axis=0) <= 1e-12 * e[0]).all()  # friction only ever takes energy out
    assert (e[-1] < 1e-6 * e[0]).all()
    assert np.abs(ph.twist).max() < 1e-3


def test_an_external_push_moves_the_robot_along_the_world_force() -> None:
    ph = Physics(load_robot("omni4"), n=2)
    ph.reset(pose=(0.0, 0.0, math.pi / 2))
    push = np.array([[0.0, 10.0, 0.0], [0.0, 0.0, 1.0]])  # 10 N along world y; 1 N m about z
    run(ph, np.zeros((2, 4)), 0.3, external_force=push)
    assert ph.pose[0, 1] > 0.01 and abs(ph.pose[0, 0]) < 1e-9
    assert ph.pose[1, 2] > math.pi / 2 + 0.05 and np.hypot(*ph.pose[1, :2]) < 1e-9


def test_a_push_below_the_breakaway_force_leaves_the_robot_still() -> None:
    ph = Physics(load_robot("omni4"))
    run(ph, np.zeros(4), 0.5, external_force=(0.5, 0.0, 0.0))  # less than the motors' friction
    assert abs(ph.pose[0, 0]) < 1e-3


# ---------------------------------------------------------------------- loads and lifted wheels


@pytest.mark.parametrize("name", PRESETS)
def test_static_loads_share_the_weight(name: str) -> None:
    robot = load_robot(name)
    ph = Physics(robot)
    np.testing.assert_allclose(ph.normal_load.sum(), robot.mass * GRAVITY)
    if name != "omni3":  # symmetric four-wheel layouts: equal shares
        np.testing.assert_allclose(ph.normal_load, robot.mass * GRAVITY / 4)
    else:  # three wheels: the unique statically determinate solution, moments balance
        x = np.array([w.position[0] for w in robot.wheels])
        np.testing.assert_allclose((ph.normal_load[0] * x).sum(), 0.0, atol=1e-9)


def test_lifted_wheel_carries_no_load_and_the_rest_carry_the_weight() -> None:
    robot = load_robot("omni4")
    ph = Physics(robot)
    ph.lifted = [True, False, False, False]
    load = ph.normal_load[0]
    assert load[0] == 0.0
    np.testing.assert_allclose(load.sum(), robot.mass * GRAVITY)
    # centre of mass on the diagonal m2-m4: the rigid robot rests on those two
    np.testing.assert_allclose(
        load, [0.0, robot.mass * GRAVITY / 2, 0.0, robot.mass * GRAVITY / 2], atol=1e-9
    )
    with pytest.raises(ValueError):
        ph.lifted[0, 1] = True  # read-only: assign a whole mask instead
    ph.lifted = np.zeros((1, 4), dtype=bool)
    np.testing.assert_allclose(ph.normal_load, robot.mass * GRAVITY / 4)


def test_a_lifted_wheel_changes_the_motion() -> None:
    ph = Physics(load_robot("omni4"), n=3)
    ph.lifted = [[False] * 4, [True, False, False, False], [False, True, False, False]]
    run(ph, np.array([0, 200, 0, -200], dtype=float), 1.0)  # course 0 on m2/m4
    normal, m1_lifted, m2_lifted = ph.pose
    # m1 lifted: the robot rests on m2/m4, the rolling m3 goes light too: it runs further
    assert m1_lifted[0] > normal[0] * 1.02
    # m2 lifted: it rests on m1/m3, so the driven m4 has no grip: the robot hardly moves
    assert m2_lifted[0] < 0.1 * normal[0]
    assert ph.wheel_speed[2, 1] > ph.wheel_speed[0, 1]  # the lifted wheel spins free


# ---------------------------------------------------------------------- motors, driver, battery


def test_current_limit_and_battery_sag() -> None:
    robot = load_robot("omni4")
    ph = Physics(robot)
    ph.step(np.full(4, 255.0))
    ph.step(np.full(4, 255.0))
    limit = robot.wheels[0].motor.current_max
    np.testing.assert_allclose(np.abs(ph.motor_current), limit)
    assert ph.battery_voltage[0] < robot.battery.voltage - 0.5


def test_a_weak_battery_sags_smoothly_without_oscillating() -> None:
    """A soft battery feeding stiff motors (R_batt * sum(1/R) = 9) must not ring step to step."""
    data = preset_data("omni3")
    data["battery"]["internal_resistance"] = 0.3
    data["motor"]["current_limit"] = 1000.0
    robot = parse_description(data)
    ph = Physics(robot)
    volts = []
    for _ in range(300):
        ph.step(np.full(3, 255.0))
        volts.append(ph.battery_voltage[0])
    v = np.array(volts)
    assert np.isfinite(v).all() and (v >= 0).all() and (v <= robot.battery.voltage + 1e-9).all()
    assert v.min() < 0.7 * robot.battery.voltage  # it does sag hard
    assert np.sum(np.diff(np.sign(np.diff(v))) != 0) <= 2  # and recovers without ringing


def test_driver_off_means_no_current() -> None:
    ph = Physics(load_robot("omni4"))
    run(ph, np.full(4, 200.0), 0.5)
    ph.step(np.zeros(4))
    assert not ph.motor_current.any()  # coasting, not braking
    assert (ph.wheel_speed > 0).all()


def test_deadband_gives_no_output_below_it() -> None:
    ph = Physics(variant("omni4", deadband=50), n=2)
    run(ph, np.array([[40.0] * 4, [60.0] * 4]), 0.2)
    assert not ph.motor_current[0].any() and abs(ph.pose[0, 2]) < 1e-12
    assert (ph.motor_current[1] > 0).all() and ph.pose[1, 2] > 0


def test_a_weaker_battery_drives_slower() -> None:
    ph = Physics(load_robot("omni4"), n=2)
    ph.battery_open_voltage[1] = 6.5
    run(ph, np.array([0, 255, 0, -255], dtype=float), 1.0)
    assert ph.pose[1, 0] < 0.9 * ph.pose[0, 0]


def test_roller_friction_depends_on_the_wheel_angle() -> None:
    """Seed 000: the unpowered wheels' angle changes the straight-line distance (up to 2x friction)."""
    ph = Physics(load_robot("omni4"), n=2)
    worst = math.pi / 8  # 8 rollers: the friction peak lies half a roller pitch away
    ph.reset(wheel_angle=np.array([[0.0] * 4, [worst, 0.0, worst, 0.0]]))
    run(ph, np.array([0, 150, 0, -150], dtype=float), 1.0)
    assert ph.pose[1, 0] < 0.97 * ph.pose[0, 0]


# ---------------------------------------------------------------------- surfaces


def test_surface_ids_select_the_floor_per_wheel() -> None:
    robot = load_robot("omni4")
    pwm = np.array([0, 200, 0, -200], dtype=float)
    carpet_only = Physics(robot, surfaces=("carpet",))
    run(carpet_only, pwm, 1.0)
    mixed = Physics(robot, n=3, surfaces=("wood", "carpet"))
    ids = np.array([[1, 1, 1, 1], [0, 0, 0, 0], [1, 0, 0, 0]])
    run(mixed, pwm, 1.0, surface_ids=ids)
    np.testing.assert_allclose(mixed.pose[0], carpet_only.pose[0], rtol=1e-9, atol=1e-12)
    assert mixed.pose[1, 0] > mixed.pose[0, 0]  # wood beats carpet
    assert mixed.pose[2, 2] != 0.0  # one rolling wheel on carpet drags the robot round
    mixed.step(pwm)  # no ids: back to surface 0 everywhere
    with pytest.raises(SimulationError, match="surface_ids"):
        mixed.step(pwm, surface_ids=np.full((3, 4), 2))


# ---------------------------------------------------------------------- batching and determinism


def _scenario(ph: Physics, pwm: np.ndarray, ids: np.ndarray, steps: int = 600) -> np.ndarray:
    out = []
    for k in range(steps):
        ph.step(pwm * math.sin(k * 0.01), surface_ids=ids, external_force=np.array([0.2, -0.1, 0.01]))
        out.append(np.concatenate([ph.pose.ravel(), ph.wheel_speed.ravel(), ph.motor_current.ravel()]))
    return np.array(out)


def test_two_runs_are_identical() -> None:
    robot = load_robot("mecanum4")
    rng = np.random.default_rng(1)
    pwm = rng.uniform(-255, 255, size=(3, 4))
    ids = rng.integers(0, 2, size=(3, 4))
    a = _scenario(Physics(robot, n=3, surfaces=("wood", "carpet")), pwm, ids)
    b = _scenario(Physics(robot, n=3, surfaces=("wood", "carpet")), pwm, ids)
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("vary", ["mass", "geometry"])
def test_a_batch_equals_single_runs(vary: str) -> None:
    """N robots with different commands, floors and true parameters in one batch equal N single runs."""
    if vary == "mass":
        robots = [variant("omni4", mass=m) for m in (1.4, 1.6, 1.9)]
    else:  # different wheel radii: each robot has its own contact geometry
        robots = [variant("omni4", radius=r) for r in (0.024, 0.025, 0.026)]
    rng = np.random.default_rng(2)
    pwm = rng.uniform(-255, 255, size=(3, 4))
    ids = rng.integers(0, 2, size=(3, 4))
    batch = Physics(robots, surfaces=("wood", "carpet"))
    assert batch.n == 3
    b_pose = []
    for k in range(600):
        batch.step(pwm * math.sin(k * 0.01), surface_ids=ids, external_force=np.array([0.2, -0.1, 0.01]))
        b_pose.append(batch.pose.copy())
    for i, robot in enumerate(robots):
        single = Physics(robot, surfaces=("wood", "carpet"))
        for k in range(600):
            single.step(
                pwm[i : i + 1] * math.sin(k * 0.01),
                surface_ids=ids[i : i + 1],
                external_force=np.array([0.2, -0.1, 0.01]),
            )
            if k % 100 == 99:
                np.testing.assert_allclose(single.pose[0], b_pose[k][i], rtol=1e-9, atol=1e-12)
    assert not np.allclose(batch.pose[0], batch.pose[2])  # the robots really differ


def test_the_step_kernel_compiles_once_whatever_the_inputs() -> None:
    """Every input is copied into a typed buffer, so the kernel never recompiles (lists, ints, broadcasts)."""
    from omnibot.sim import kernels

    robot = load_robot("omni4")
    for n in (1, 3):
        ph = Physics(robot, n=n, surfaces=("wood", "carpet"))
        ph.step([10, 20, 30, 40])
        ph.step(np.full((n, 4), 100, dtype=np.int64), surface_ids=[1, 0, 1, 0], external_force=(1, 0, 0))
        ph.step(np.float32(50.0), surface_ids=np.ones((n, 4)), external_force=np.zeros((n, 3)))
    assert len(kernels.physics_step.signatures) == 1


# --------------------------------------------------------------------------- batch


def _batch(n: int, **battery: Any) -> Physics:
    robots = [load_robot("omni4"), load_robot("omni4").model_copy(update={"mass": 2.3})]
    if battery:
        robots = [r.model_copy(update={"battery": r.battery.model_copy(update=battery)}) for r in robots]
    return Physics([robots[i % 2] for i in range(n)], surfaces=("wood", "carpet"))


def test_run_is_step_repeated_bit_for_bit_on_every_core() -> None:
    rng = np.random.default_rng(4)
    n = 37  # not a whole number of the kernel's chunks of robots
    pwm = rng.integers(-255, 256, size=(n, 4))
    ids = rng.integers(0, 2, size=(n, 4))
    force = rng.normal(0.0, 2.0, size=(n, 3))
    batch, single = _batch(n), _batch(n)
    batch.run(pwm, 150, surface_ids=ids, external_force=force)
    for _ in range(150):
        single.step(pwm, ids, force)
    for name in ("pose", "twist", "wheel_angle", "wheel_speed", "motor_current", "battery_voltage"):
        assert np.array_equal(getattr(batch, name), getattr(single, name)), name
    assert batch.time == single.time == pytest.approx(0.15)
    assert len(np.unique(batch.pose[:, 0])) > n // 2  # the robots went their own ways
    batch.run(pwm, 0)
    assert batch.time == pytest.approx(0.15)


def test_run_drains_a_battery_with_a_charge_step_by_step() -> None:
    pwm = np.full((3, 4), 200)
    batch, single = _batch(3, charge=0.5, capacity_ah=0.001), _batch(3, charge=0.5, capacity_ah=0.001)
    batch.run(pwm, 200)
    for _ in range(200):
        single.step(pwm)
    assert np.array_equal(batch.battery_charge, single.battery_charge)
    assert (batch.battery_charge < 0.5).all() and np.array_equal(batch.pose, single.pose)


def test_run_refuses_bad_input() -> None:
    batch = _batch(2)
    with pytest.raises(SimulationError, match="steps must be >= 0"):
        batch.run(np.zeros((2, 4)), -1)
    with pytest.raises(SimulationError, match="must index the 2 surfaces"):
        batch.run(np.zeros((2, 4)), 3, surface_ids=np.full((2, 4), 2))
    assert batch.time == 0.0 and not batch.pose.any()
