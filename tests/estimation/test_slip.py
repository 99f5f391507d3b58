"""The wheel-slip model: its force-sharing patterns, the fit, and the creep it removes on carpet."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.errors import ConfigError
from omnibot.estimation.creep import SlipParameters
from omnibot.estimation.slip import SlipLeg, SlipModel, fit_slip, leg_error, leg_residual
from omnibot.motion import Twist
from omnibot.robot import load_robot


def _course(deg: float, speed: float = 0.4) -> tuple[float, float, float]:
    a = math.radians(deg)
    return (speed * math.cos(a), speed * math.sin(a), 0.0)


def test_omni4_pattern_matches_which_wheels_push() -> None:
    model = SlipModel(load_robot("omni4"))
    # course 0: m1 and m3 only roll (their rollers drag), m2 and m4 push against that drag
    p = model.patterns(_course(0)).roll
    assert np.allclose(np.abs(p), [0.0, 1.0, 0.0, 1.0], atol=1e-6)
    # course 30: every roller rolls, every wheel pushes one drag's worth
    p = model.patterns(_course(30)).roll
    assert np.allclose(np.abs(p), 1.0, atol=1e-3)
    # standing still, or turning in place (omni4's rollers do not roll then): no creep
    for still in ((0.0, 0.0, 0.0), (0.0, 0.0, 2.0)):
        patterns = model.patterns(still)
        assert np.allclose(patterns.roll, 0.0, atol=1e-9) and np.allclose(patterns.combined, 0.0, atol=1e-9)


def test_omni4_combined_drag_pattern_depends_on_the_course() -> None:
    model = SlipModel(load_robot("omni4"))
    # on an axis no wheel both drives and rolls: no combined drag
    assert np.allclose(model.patterns(_course(0, 0.5)).combined, 0.0, atol=1e-12)
    assert np.allclose(model.patterns(_course(90, 0.5)).combined, 0.0, atol=1e-12)
    # at 45 degrees every contact crosses its roller at 45 degrees (sin 2 beta = 1): each wheel
    # pushes against one roller's drag, its rolling speed 0.5 sin 45
    c45 = model.patterns(_course(45, 0.5)).combined
    assert np.allclose(np.abs(c45), 0.5 * math.sin(math.radians(45)), atol=1e-9)
    # at 30 degrees: sin 2 beta = sin 60 on every wheel; m2/m4 push against m1/m3's rollers (x)
    c30 = model.patterns(_course(30, 0.5)).combined
    s60 = math.sin(math.radians(60))
    assert np.allclose(
        np.abs(c30), [s60 * 0.5 * math.sin(math.radians(30)), s60 * 0.5 * math.cos(math.radians(30))] * 2
    )
    # viscous: twice the speed, twice the pattern; the rolling pattern does not change
    assert np.allclose(model.patterns(_course(30, 1.0)).combined, 2 * c30)
    assert np.allclose(model.patterns(_course(30, 1.0)).roll, model.patterns(_course(30, 0.5)).roll)


def test_creep_reverses_with_the_motion_and_scales_with_its_coefficient() -> None:
    robot = load_robot("omni3")
    model = SlipModel(robot, SlipParameters(roll=0.01))
    forward = model.creep(_course(40))
    assert np.allclose(model.creep(_course(220)), -forward)
    assert np.allclose(SlipModel(robot, SlipParameters(roll=0.02)).creep(_course(40)), 2 * forward)
    # the acceleration share: pushing the mass, split over the wheels by least norm
    accel_only = SlipModel(robot, SlipParameters(compliance=0.1)).creep((0, 0, 0), (1.0, 0.0, 0.0))
    J = robot.wheel_matrix
    rim = model.rim_per_rad
    body = np.linalg.pinv(J) @ (accel_only / rim)
    assert body[0] > 0 and abs(body[1]) < 1e-9 and abs(body[2]) < 1e-9


def _synthetic_leg(
    robot_name: str, params: SlipParameters, course: float, speed: float, ramp: float = 0.4
) -> SlipLeg:
    """A rest-to-rest run whose encoder displacement carries exactly the model's creep and scale
    (``ramp`` s up from rest and down to it)."""
    robot = load_robot(robot_name)
    model = SlipModel(robot, params)
    pinv = np.linalg.pinv(robot.wheel_matrix)
    dt, duration = 0.01, 2.0
    t = np.arange(0.0, duration, dt)
    v = speed * np.clip(np.minimum(t / ramp, (duration - t) / ramp), 0.0, 1.0)
    acc = np.gradient(v, dt)
    c, s = math.cos(course), math.sin(course)
    twists = np.column_stack((v * c, v * s, np.zeros_like(v)))
    accels = np.column_stack((acc * c, acc * s, np.zeros_like(v)))
    true = twists[:, :2].sum(axis=0) * dt
    extra = sum(pinv @ (model.wheel_correction(q, a)) * dt for q, a in zip(twists, accels, strict=True))
    enc = (true + np.asarray(extra)[:2]) / params.scale
    return SlipLeg(twists, accels, np.full(len(t), dt), np.zeros(len(t)), tuple(enc), tuple(true))


@pytest.mark.parametrize("robot", ["omni4", "omni3", "mecanum4"])
def test_fit_recovers_the_roll_coefficient_of_synthetic_runs(robot: str) -> None:
    truth = SlipParameters(roll=0.0123)
    legs = [_synthetic_leg(robot, truth, math.radians(deg), 0.3) for deg in (10, 75, 140, 200, 290)]
    fitted = fit_slip(load_robot(robot), legs)
    assert fitted.roll == pytest.approx(truth.roll, rel=1e-6)
    assert fitted.compliance == 0.0 and fitted.combined == 0.0  # not needed: not taken
    assert all(leg_error(leg) > 0.01 for leg in legs)
    assert all(leg_error(leg, fitted, load_robot(robot)) < 1e-8 for leg in legs)


@pytest.mark.parametrize("deg", [0, 20, 90, 165])
def test_mecanum_rolling_creep_is_sideways_only(deg: float) -> None:
    """A mecanum base's roller drag is balanced by a strafe's traction pattern: the encoders
    over-read the body's y on every course that moves it sideways and nothing along x, so a
    correction fitted on any courses cannot move the estimate along a heading-held route's x."""
    robot = load_robot("mecanum4")
    params = SlipParameters(roll=0.0014)
    leg = _synthetic_leg("mecanum4", params, math.radians(deg), 0.4)
    raw = leg_residual(leg)
    assert abs(raw[0]) < 1e-12
    assert (raw[1] > 1e-4) == (0 < deg < 180)  # y over-read while strafing, none straight ahead
    assert np.allclose(leg_residual(leg, params, robot), 0.0, atol=1e-12)
    assert leg_error(leg, params, robot) == pytest.approx(
        math.hypot(*leg_residual(leg, params, robot)) / math.hypot(*leg.true_disp)
    )


def test_fit_recovers_rolling_and_combined_creep_of_synthetic_runs() -> None:
    robot = load_robot("omni4")
    truth = SlipParameters(roll=0.015, combined=0.03)
    legs = [
        _synthetic_leg("omni4", truth, math.radians(deg), speed)
        for deg in (11.25, 191.25, 33.75, 213.75, 56.25, 236.25)
        for speed in (0.5, 0.25)
    ]
    fitted = fit_slip(robot, legs)
    assert fitted.roll == pytest.approx(0.015, rel=1e-6) and fitted.combined == pytest.approx(0.03, rel=1e-6)
    assert all(leg_error(leg, fitted, robot) < 1e-8 for leg in legs)
    # the older form (no combined term) cannot: its error depends on the course
    rolling_only = fit_slip(robot, legs, combined=False)
    assert rolling_only.combined == 0.0
    assert max(leg_error(leg, rolling_only, robot) for leg in legs) > 0.005


def test_fit_needs_runs_and_leg_error_needs_the_robot() -> None:
    with pytest.raises(ConfigError, match="at least one run"):
        fit_slip(load_robot("omni4"), [])
    leg = _synthetic_leg("omni4", SlipParameters(roll=0.01), 0.3, 0.3)
    with pytest.raises(ValueError, match="needs the robot"):
        leg_error(leg, SlipParameters(roll=0.01))
    with pytest.raises(ValueError, match="needs the robot"):
        leg_residual(leg, SlipParameters(roll=0.01))


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ([1, 2], "expected a mapping"),
        ({"roll": 0.01, "rol": 0.0}, r"unknown key\(s\) \['rol'\]"),
        ({"roll": "fast"}, "slip.roll: 'fast' is not a number"),
        ({"compliance": float("nan")}, "must be a finite number"),
        ({"combined": "lots"}, "slip.combined: 'lots' is not a number"),
        ({"combined": float("inf")}, "combined must be a finite number"),
    ],
)
def test_parameters_from_a_file_give_clear_errors(data: object, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        SlipParameters.from_mapping(data)


def test_parameters_round_trip() -> None:
    p = SlipParameters(roll=0.0161, compliance=0.002, combined=0.031)
    assert SlipParameters.from_mapping(p.as_dict()) == p
    assert list(p.as_dict()) == ["roll", "combined", "compliance", "scale", "ramp"]
    ramped = SlipParameters(roll=0.0036, compliance=0.014, ramp=0.000768)
    assert SlipParameters.from_mapping(ramped.as_dict()) == ramped
    assert SlipParameters.from_mapping({"roll": 0.01}) == SlipParameters(0.01, 0.0)


def test_the_ramp_term_is_the_drags_share_times_the_squared_acceleration() -> None:
    model = SlipModel(load_robot("omni3"), SlipParameters(roll=0.004, ramp=0.0008))
    q, accel = _course(30, 0.5), (0.6, -0.8, 3.0)  # |a| 1 m/s^2 along the floor; the turn's adds none
    p = model.patterns(q, accel)
    assert np.allclose(p.ramp, p.roll)
    assert np.allclose(model.creep(q, accel), 0.0048 * p.roll)
    assert np.allclose(model.creep(q), 0.004 * p.roll)  # steady: the drag's alone


def test_fit_tells_a_ramps_extra_creep_from_the_steady_drag() -> None:
    """Runs on two ramps (0.4 and 1.0 s: 1 and 0.2 m/s^2 at 0.4 and 0.2 m/s) tell them apart; one
    roll alone fits the same runs too high for a steady speed and too low for a steep ramp."""
    truth = SlipParameters(roll=0.004, ramp=0.003)
    legs = [
        _synthetic_leg("omni3", truth, math.radians(deg), speed, ramp)
        for deg in (15, 100, 190, 280)
        for speed, ramp in ((0.4, 0.4), (0.2, 1.0))
    ]
    fitted = fit_slip(load_robot("omni3"), legs, ramp=True)
    assert fitted.roll == pytest.approx(0.004, rel=1e-6) and fitted.ramp == pytest.approx(0.003, rel=1e-6)
    alone = fit_slip(load_robot("omni3"), legs)
    assert alone.ramp == 0.0 and 0.0041 < alone.roll < 0.0048


def test_files_with_the_older_three_keys_still_load() -> None:
    # written before the combined drag: the model they were fitted with, combined 0
    old = SlipParameters.from_mapping({"roll": 0.0199, "compliance": 0.0153, "scale": 1.0})
    assert old == SlipParameters(roll=0.0199, compliance=0.0153, scale=1.0, combined=0.0)
    model = SlipModel(load_robot("omni4"), old)
    p = model.patterns(_course(45))
    assert np.allclose(model.creep(_course(45)), 0.0199 * p.roll)


def test_fit_never_returns_a_negative_coefficient() -> None:
    # encoders that under-read (a negative creep) are not creep: the fit says none rather than < 0
    legs = [_synthetic_leg("omni4", SlipParameters(roll=-0.01), math.radians(d), 0.3) for d in (20, 200)]
    fitted = fit_slip(load_robot("omni4"), legs, compliance=True)
    assert fitted == SlipParameters(0.0, 0.0)


def test_fit_tells_a_radius_error_from_creep_with_two_speeds() -> None:
    truth = SlipParameters(roll=0.01, scale=1.04)
    legs = [
        _synthetic_leg("omni4", truth, math.radians(deg), speed)
        for deg in (15, 100, 190, 280)
        for speed in (0.4, 0.2)
    ]
    fitted = fit_slip(load_robot("omni4"), legs, scale=True)
    assert fitted.roll == pytest.approx(0.01, rel=0.05)
    assert fitted.scale == pytest.approx(1.04, abs=0.002)
    assert all(leg_error(leg, fitted, load_robot("omni4")) < 0.003 for leg in legs)


def test_scale_out_of_range_is_refused() -> None:
    with pytest.raises(ConfigError, match=r"scale must be between 0\.5 and 2"):
        SlipParameters.from_mapping({"roll": 0.01, "scale": 3})


def test_fit_keeps_scale_1_when_a_radius_error_explains_nothing() -> None:
    rng = np.random.default_rng(5)
    legs = []
    for deg in (15, 100, 190, 280):
        for speed in (0.4, 0.2):
            leg = _synthetic_leg("omni4", SlipParameters(roll=0.01), math.radians(deg), speed)
            noisy = tuple(np.asarray(leg.true_disp) + rng.normal(0.0, 3e-4, 2))
            legs.append(SlipLeg(leg.twists, leg.accels, leg.dt, leg.headings, leg.encoder_disp, noisy))
    fitted = fit_slip(load_robot("omni4"), legs, scale=True)
    assert fitted.scale == 1.0 and fitted.roll == pytest.approx(0.01, rel=0.1)
    assert fitted.combined < 0.002  # noise, not a combined drag: at most a trace of one


@pytest.mark.parametrize("robot", ["omni4", "mecanum4", "omni3"])
def test_commanded_asks_each_wheel_for_its_creep_on_top(robot: str) -> None:
    """The wheel speeds of the commanded twist are the asked twist's, plus each wheel's creep, over
    the tyres' scale (exactly where the creep is a rigid motion: omni4 at 45 degrees)."""
    description = load_robot(robot)
    params = SlipParameters(roll=0.015, combined=0.03, compliance=0.02, scale=0.98)
    model = SlipModel(description, params)
    J = np.asarray(description.wheel_matrix)
    asked = Twist(0.3 * math.cos(math.pi / 4), 0.3 * math.sin(math.pi / 4), 0.0)
    q = np.array(asked)
    want = (J @ q + model.wheel_correction(q)) / params.scale
    got = J @ np.array(model.commanded(asked))
    residual = want - J @ np.linalg.pinv(J) @ want  # the part no twist can ask for
    assert got == pytest.approx(want - residual, abs=1e-9)
    if robot == "omni4":
        assert np.abs(residual).max() < 1e-9
    assert SlipModel(description).commanded(asked) == pytest.approx(asked)  # no slip: as asked
    accel = np.array([1.5, -0.5, 2.0])  # accelerating: each wheel's creep under its share of the force too
    want = (J @ q + model.wheel_correction(q, accel)) / params.scale
    got = J @ np.array(model.commanded(asked, accel))
    assert got == pytest.approx(J @ np.linalg.pinv(J) @ want, abs=1e-9)  # the least-squares twist's
    assert not np.allclose(model.commanded(asked, accel), model.commanded(asked))
