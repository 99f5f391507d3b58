"""The motor map on the host: the firmware's formula mirrored, offsets, balance courses, tables."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnibot.calibration.motorfit import (
    Balance,
    balance_courses,
    effective_gains,
    emf_counts,
    gain_fit_step,
    gain_origin,
    gain_rows,
    identity,
    information,
    offsets_from_deadbands,
    stand_torque,
)
from omnibot.calibration.motors import fit_motor_map
from omnibot.calibration.patterns import Geometry, apply_map, course_pattern, map_power, top_power
from omnibot.calibration.perturb import parse_perturbation, perturbed_robot
from omnibot.calibration.plan import Plan
from omnibot.calibration.runner import Runner
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.truth import TruthContext, make_truth
from omnibot.firmware.calibration import Calibration
from omnibot.protocol import codes
from omnibot.robot import MotorMapSpec, PiecewiseLinear, RobotDescription, load_robot
from tests.calibration.conftest import sim_client

MAP = MotorMapSpec(
    offset=(36.2, 44.5, 0.0, 40.0),
    gain=(
        PiecewiseLinear(x=(21.0, 105.0, 178.0), y=(0.98, 1.02, 1.0)),
        PiecewiseLinear(x=(0.0,), y=(1.0,)),
        PiecewiseLinear(x=(50.0,), y=(1.2,)),
        PiecewiseLinear(x=(10.0, 200.0), y=(0.9, 1.1)),
    ),
)

SPEEDY = MAP.model_copy(update={"speed": (21.6, -23.9, 0.0, 150.0)})


@given(st.integers(0, 3), st.floats(-255, 255, allow_nan=False), st.floats(-2, 2, allow_nan=False))
def test_map_power_is_the_firmwares(i: int, a: float, u: float) -> None:
    fw = Calibration(
        {
            "k": 100.0,
            "kl_courses": [0],
            "kl_tables": [[[0], [1.0]]],
            "kt": [[0], [1.0]],
            "kr": [[0], [1.0]],
            "motor_offset": list(MAP.offset),
            "motor_gain": [[list(g.x), list(g.y)] for g in MAP.gain],
            "motor_speed": list(SPEEDY.speed or ()),
        }
    )
    assert map_power(SPEEDY, i, a, u) == pytest.approx(fw.motor_power(i, a, u), abs=1e-9)


def test_patterns_through_the_map(omni4: RobotDescription) -> None:
    geo = Geometry.of(omni4)
    assert map_power(None, 0, -12.5) == -12.5 and map_power(identity(4), 2, 7.0) == 7.0
    assert course_pattern(geo, 0.0, 100, MAP) == [0, 144, 0, -round(40 + 100 * (0.9 + 0.2 * 90 / 190))]
    assert apply_map(MAP, [250.0, 0.0, 0.0, 0.0], 255) == [255, 0, 0, 0]  # clipped
    assert top_power(MAP, 255) == 195  # motor 4: (255 - 40) / 1.1
    assert top_power(None, 255) == 255


def test_offsets_scale_the_motor_dead_bands_to_rotation() -> None:
    assert offsets_from_deadbands([50, 60, 62, 50], 40, 255) == (36.0, 43.2, 44.7, 36.0)
    assert offsets_from_deadbands([50, 256, 62, 50], 40, 255) == (0.0,) * 4  # a motor never moved it
    assert offsets_from_deadbands([50, 60, 62, 50], 256, 255) == (0.0,) * 4


def test_balance_courses_and_tables() -> None:
    assert balance_courses(Geometry.of(load_robot("omni4"))) == [
        0.0,
        45.0,
        90.0,
        135.0,
        180.0,
        225.0,
        270.0,
        315.0,
    ]
    assert len(balance_courses(Geometry.of(load_robot("omni3")))) == 12
    b = Balance(powers=[50, 100], log_gains=[[0.1, -0.1], [0.0, 0.0]])
    tables = b.tables(2)
    assert tables[0] == PiecewiseLinear(x=(50.0, 100.0), y=(round(math.exp(0.1), 3), 1.0))
    assert Balance().tables(3) == identity(3).gain


def test_emf_counts() -> None:
    emf = emf_counts(load_robot("omni4"))
    assert emf == pytest.approx((255 * 0.006 * 10 / (0.025 * (7.4 - 2.0)),) * 4)  # 113 counts per m/s


@pytest.mark.parametrize("bus", [1.0, 0.85])
def test_stand_torque_finds_the_torque_constants(bus: float) -> None:
    """Free wheels on a stand: a motor with s times the torque constant turns at the speed where its
    voltage (the bus, here ``bus`` times the described one, less nothing else) meets back-EMF and the
    current its own friction draws; ``stand_torque`` finds s (their geometric mean 1: the common
    share, such as the bus sagging, is the K_l tables')."""
    robot = load_robot("omni4")
    m = robot.wheels[0].motor
    s = np.array([1.1, 0.9, 0.95, 1.05])
    s_norm = s / np.exp(np.mean(np.log(s)))
    kg = m.torque_constant * m.gear_ratio
    volts = bus * (robot.battery.voltage - m.driver_drop)
    powers = [102.0, 166.0, 230.0]
    speeds = []
    for p in powers:
        v = volts * p / m.pwm_max
        # v = s kG w + R (tau_c + b w) / (eta s kG)  ->  w
        w = (v - m.resistance * m.friction_static / (m.gear_efficiency * s * kg)) / (
            s * kg + m.resistance * m.friction_viscous / (m.gear_efficiency * s * kg)
        )
        speeds.append(list(w))
    stand = stand_torque(robot, powers, speeds)
    tol = 0.002 if bus == 1.0 else 0.01  # the sag scales the viscous share a little unevenly
    assert stand.torque == pytest.approx(s_norm, abs=tol)
    assert stand.bus == pytest.approx(bus * np.exp(np.mean(np.log(s))), rel=0.02)
    assert max(stand.stderr) < 1e-6  # the speeds lie on a line
    assert set(stand.as_dict()) == {"powers", "speeds", "torque", "stderr", "bus"}


def test_gain_fit_finds_the_gains_with_their_speed_terms_tied() -> None:
    """Motors with torque constants s (known from the stand) and load factors r: the map they need
    is gain r / s and speed term (s - r/s) E. On errors that respond linearly to each motor's
    effective gain, one step from runs through the offsets alone (gains 1, no speed term) lands on
    them, at any mix of load shares rho."""
    rng = np.random.default_rng(7)
    n, k = 4, 190.0
    emf = np.full(n, 113.0)
    s = np.array([1.1, 0.9, 0.9, 1.1])
    r = np.array([1.05, 0.98, 1.0, 0.97])
    r *= n / np.sum(r)  # the load factors average the nominal
    truth = r / s
    jac = rng.normal(size=(64, n))
    ratios = rng.uniform(0.1, 1.2, size=(64, n))
    ratios[::4, 1] = 0.0  # motor 2 does not drive in every run
    true_acted = effective_gains(truth, (s - truth) * emf, ratios, k)
    acted = effective_gains(np.ones(n), np.zeros(n), ratios, k)
    e = np.sum(jac * (acted - true_acted), axis=1)  # errors vanish where the motors act as they need
    origin = gain_origin(e, jac, acted, ratios, s, emf, k)
    rows = gain_rows(jac, ratios, emf, k)
    got = gain_fit_step(rows, origin, np.ones(64), s, ridge=1e-6)
    assert got == pytest.approx(truth, abs=1e-4)
    info = information(rows, np.ones(64), 0.01, s)
    assert info.condition < 20 and max(info.stderr) < 0.01
    # two motors that never drive are not told apart (one alone is: the common share is held)
    blind = rows.copy()
    blind[:, 2:] = 0.0
    assert math.isinf(information(blind, np.ones(64), 0.01, s).condition)


def test_balance_rate_interpolates_the_runs() -> None:
    b = Balance(rates=[(0.0, 50, 0.2), (0.0, 50, 0.3), (0.0, 100, 0.5), (45.0, 100, 0.3), (45.0, 200, 0.5)])
    assert b.rate(50, 10.0) == pytest.approx(0.25)  # the median of course 0's runs at 50
    assert b.rate(25, 0.0) == pytest.approx(0.125)  # through 0 below the lowest power
    assert b.rate(75, 0.0) == pytest.approx(0.375)
    assert b.rate(150, 0.0) == pytest.approx(0.75)  # along the last segment above
    assert b.rate(150, 40.0) == pytest.approx(0.4)
    assert Balance().rate(100, 0.0) == 0.0


def test_the_motor_map_finds_a_perturbed_robots_motors(omni4: RobotDescription) -> None:
    """Motors apart in torque constant (-8..+6 %) and resistance (+-5 %) on carpet, seed 3: the stand
    test finds the torque constants s within 0.02 (their geometric mean 1: the common share is the K_l
    tables'), the balance runs the gains r / s within 0.03 and with them the speed terms (s - g) E
    within 5 counts per m/s (measured 0.013, 0.017, 3.5). The same runs could not tell both numbers
    apart without the stand: the Fisher information's condition number is far larger."""
    spec = "torque_constant=0.92,1.06,1.0,1.04;resistance=1.05,0.95,1.0,1.0"
    factors = parse_perturbation(spec, 4)
    s = np.array(factors["torque_constant"])
    s /= np.exp(np.mean(np.log(s)))
    gains = np.array(factors["resistance"]) / s
    speed = (s - gains) * np.array(emf_counts(omni4))
    with sim_client(omni4, "carpet", true_robot=perturbed_robot(omni4, spec), seed=3) as client:
        client.mode(client.status().mode & ~codes.MODE_CLOSED_LOOP)
        tap = TelemetryTap(client, omni4)
        tap.start()
        runner = Runner(client, omni4, make_truth("sim", TruthContext(client, omni4, tap, input)), tap)
        motors, balance = fit_motor_map(runner, Plan(), [])
        tap.stop()
    assert balance.stand is not None and balance.information is not None and balance.floor_only is not None
    assert balance.stand.torque == pytest.approx(s, abs=0.02)
    assert [g(100.0) for g in motors.gain] == pytest.approx(gains, abs=0.03)
    assert motors.speed == pytest.approx(speed, abs=5.0)
    assert (
        balance.information.condition
        < 100
        < 10 * balance.information.condition
        < balance.floor_only.condition
    )
