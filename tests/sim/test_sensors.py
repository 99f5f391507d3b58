"""Sensor models: encoder quantisation, tracking wheels, gyro noise statistics, sonar echoes."""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
import pytest

from omnibot.robot import GyroSpec, SonarSpec, TrackingWheelSpec, load_robot
from omnibot.sim.sensors import Gyro, MotorEncoders, NormalBlock, Sonar, TrackingWheels
from omnibot.sim.world import load_world, parse_world

TWO_PI = 2 * math.pi


def rng(seed: int = 0) -> np.random.Generator:
    return np.random.default_rng(seed)


# --------------------------------------------------------------------------- motor encoders


def test_encoder_one_revolution_is_exactly_counts_per_rev() -> None:
    enc = MotorEncoders([440, 16000, 7], rng())
    assert enc.update([TWO_PI, TWO_PI, TWO_PI]).tolist() == [440, 16000, 7]
    assert enc.update([-TWO_PI, 10 * TWO_PI, 3 * TWO_PI]).tolist() == [-440, 160000, 21]


def test_encoder_floors_like_a_counter() -> None:
    enc = MotorEncoders([4], rng())
    quarter = TWO_PI / 4
    assert enc.update([0.99 * quarter]).tolist() == [0]
    assert enc.update([1.0 * quarter]).tolist() == [1]
    assert enc.update([1.99 * quarter]).tolist() == [1]
    assert enc.update([-0.01 * quarter]).tolist() == [-1]  # floor, not truncation toward zero


def test_encoder_counts_start_at_zero_and_are_monotone() -> None:
    enc = MotorEncoders([440], rng(), initial_angles=[1.234])
    assert enc.counts.tolist() == [0]
    angles = 1.234 + np.cumsum(np.full(3000, 0.003))
    counts = [int(enc.update([a])[0]) for a in angles]
    assert all(b >= a for a, b in itertools.pairwise(counts))
    assert counts[-1] == math.floor(angles[-1] * 440 / TWO_PI) - math.floor(1.234 * 440 / TWO_PI)


def test_encoder_missed_counts_statistics() -> None:
    enc = MotorEncoders([1000, 1000], rng(3), miss_probability=0.01)
    angles = np.linspace(0, 20 * TWO_PI, 5001)
    last = np.zeros(2, dtype=int)
    for a in angles:
        c = enc.update([a, -a])
        assert c[0] >= last[0] and c[1] <= last[1]  # lost counts never reverse a count
        last = c
    true = 20_000
    lost = true - np.abs(last)
    assert np.all(np.abs(lost - 200) < 5 * math.sqrt(200))  # binomial(20000, 0.01)
    again = MotorEncoders([1000, 1000], rng(3), miss_probability=0.01)
    for a in angles:
        again.update([a, -a])
    assert again.counts.tolist() == last.tolist()  # deterministic per seed


# --------------------------------------------------------------------------- tracking wheels


def test_tracking_wheels_during_pure_rotation_match_w_cross_p() -> None:
    robot = load_robot("omni3")
    specs = robot.encoders.tracking
    wheels = TrackingWheels(specs, rng(), slip_std=0.0)
    w, dt, steps = 1.5, 0.001, 2000
    for _ in range(steps):
        wheels.update((0.0, 0.0, w), dt)
    for spec, dist, count in zip(specs, wheels.distance, wheels.counts, strict=True):
        u = (math.cos(spec.direction), math.sin(spec.direction))
        rim = u[0] * (-w * spec.y) + u[1] * (w * spec.x)  # u . (w x p)
        assert dist == pytest.approx(rim * dt * steps)
        assert count == math.floor(rim * dt * steps / (TWO_PI * spec.radius) * spec.counts_per_rev + 1e-9)
    # seed 002's layout: the vertical wheel at y=+0.1 runs backwards, the horizontal at x=+0.1 forwards
    assert wheels.counts[0] < 0 < wheels.counts[1]


def test_tracking_wheels_translation_and_slip_noise() -> None:
    spec = TrackingWheelSpec(name="v", x=0.0, y=0.1, direction_deg=0, radius=0.029, counts_per_rev=2400)
    exact = TrackingWheels([spec], rng(), slip_std=0.0)
    noisy = TrackingWheels([spec], rng(5), slip_std=0.02)
    for _ in range(1000):
        exact.update((0.5, 0.3, 0.0), 0.001)
        noisy.update((0.5, 0.3, 0.0), 0.001)
    assert exact.distance[0] == pytest.approx(0.5)
    assert noisy.distance[0] != exact.distance[0]
    assert noisy.distance[0] == pytest.approx(0.5, rel=5 * 0.02 / math.sqrt(1000))
    assert exact.counts[0] == math.floor(0.5 / (TWO_PI * 0.029) * 2400 + 1e-9)
    assert TrackingWheels([], rng()).update((1, 0, 0), 0.1).tolist() == []


# --------------------------------------------------------------------------- gyro


def quiet(**changes: float) -> GyroSpec:
    base = dict(rate_hz=1000.0, bias_std=0.0, bias_walk=0.0, scale_error_std=0.0)
    return GyroSpec(model="MPU6050", **{**base, **changes})


def test_gyro_white_noise_mean_over_one_second_matches_noise_density() -> None:
    spec = quiet()
    gyro = Gyro(spec, rng(11))
    seconds = 120
    samples = np.array([gyro.measure(0.0) for _ in range(int(spec.rate_hz) * seconds)])
    per_second = samples.reshape(seconds, -1).mean(axis=1)
    assert per_second.std() == pytest.approx(spec.noise_density, rel=0.2)
    assert samples.std() == pytest.approx(spec.noise_density * math.sqrt(spec.rate_hz), rel=0.05)
    # quantised to the LSB
    lsb = samples / spec.resolution
    np.testing.assert_allclose(lsb, np.round(lsb), atol=1e-6)


def test_gyro_turn_on_bias_scale_error_and_saturation() -> None:
    spec = GyroSpec(model="MPU6050", noise_density=0.0, bias_walk=0.0, resolution=0.0)
    biases = [Gyro(spec, rng(s)).bias for s in range(400)]
    assert np.std(biases) == pytest.approx(spec.bias_std, rel=0.15)
    g = Gyro(spec, rng(7))
    assert g.measure(1.0) == pytest.approx((1 + g.scale_error) * 1.0 + g.bias)
    assert g.measure(100.0) == spec.range and g.measure(-100.0) == -spec.range


def test_gyro_bias_random_walk_grows_with_sqrt_time() -> None:
    spec = quiet(rate_hz=100.0, noise_density=0.0, bias_walk=2e-4, resolution=0.0)
    seconds = 25
    drifts = []
    for s in range(60):
        g = Gyro(spec, rng(100 + s))
        for _ in range(int(spec.rate_hz * seconds)):
            g.measure(0.0)
        drifts.append(g.bias)
    assert np.std(drifts) == pytest.approx(spec.bias_walk * math.sqrt(seconds), rel=0.3)


def test_gyro_samples_at_its_rate_and_averages_the_true_rate() -> None:
    g = Gyro(quiet(rate_hz=100.0, noise_density=0.0, resolution=0.0), rng())
    new = [g.update(0.001, 0.0 if k < 5 else 1.0) for k in range(10)]
    assert new == [False] * 9 + [True]
    assert g.rate == pytest.approx(0.5)  # half the period at 0, half at 1
    g.update(0.02, 2.0)  # a long step yields two samples
    assert g.samples == 3 and g.rate == pytest.approx(2.0)
    assert g.angle == pytest.approx((0.5 + 2.0 + 2.0) * 0.01)


# --------------------------------------------------------------------------- sonar


def corridor_sonar(**changes: float) -> Sonar:
    spec = SonarSpec(name="front", x=0.1, y=0.0, angle_deg=0.0, **changes)
    return Sonar(spec, rng(2))


def test_sonar_range_noise_and_limits() -> None:
    w = load_world("corridor")  # end wall at x = 10
    s = corridor_sonar(miss_probability=0.0)
    readings = [s.measure((7.9, 0.0, 0.0), w) for _ in range(2000)]
    values = np.array([r for r in readings if r is not None])
    assert len(values) == 2000
    assert values.mean() == pytest.approx(2.0, abs=4 * 0.003 / math.sqrt(2000))
    assert values.std() == pytest.approx(0.003, rel=0.1)
    assert s.measure((5.0, 0.0, 0.0), w) is None  # 4.9 m: beyond max_range 4 m
    assert s.measure((9.895, 0.0, 0.0), w) == s.spec.min_range  # 5 mm: clamped at 2 cm
    assert s.measure((2.0, 0.0, math.pi), w) == pytest.approx(1.9, abs=0.02)  # turned around


def test_sonar_sees_an_off_axis_obstacle_within_the_cone() -> None:
    def post(bearing_deg: float) -> dict[str, Any]:
        b = math.radians(bearing_deg)
        return {"shape": "circle", "center": [1.1 + 1.5 * math.cos(b), 1.5 * math.sin(b)], "radius": 0.01}

    for bearing, seen in [(5.0, True), (-5.0, True), (10.0, False)]:
        w = parse_world({"name": "post", "obstacles": [post(bearing)]})
        r = corridor_sonar(miss_probability=0.0, noise_std=0.0).measure((1.0, 0.0, 0.0), w)
        assert (r is not None) == seen
        if seen:
            assert r == pytest.approx(1.49, abs=0.002)


def test_sonar_miss_statistics() -> None:
    w = load_world("corridor")
    s = corridor_sonar(miss_probability=0.1)
    readings = [s.measure((7.9, 0.0, 0.0), w) for _ in range(4000)]
    misses = sum(r is None for r in readings)
    assert misses == pytest.approx(400, abs=4 * math.sqrt(4000 * 0.1 * 0.9))


def test_sonar_ping_respects_the_minimum_cycle() -> None:
    w = load_world("corridor")
    s = corridor_sonar(miss_probability=0.0)
    first = s.ping(0.0, (7.9, 0.0, 0.0), w)
    assert first is not None
    assert s.ping(0.03, (7.0, 0.0, 0.0), w) == first  # too soon: the previous result
    assert s.ping(0.059, (7.0, 0.0, 0.0), w) == first
    second = s.ping(0.060, (7.0, 0.0, 0.0), w)
    assert second == pytest.approx(2.9, abs=0.02)
    assert s.last_time == 0.060


def test_sonar_pose_in_world() -> None:
    s = Sonar(SonarSpec(name="side", x=0.1, y=0.05, angle_deg=90), rng())
    p = s.pose_in_world((1.0, 2.0, math.pi / 2))
    assert p.x == pytest.approx(0.95) and p.y == pytest.approx(2.1) and p.theta == pytest.approx(math.pi)


# --------------------------------------------------------------------------- cost-saving helpers


def test_normal_block_draws_the_same_numbers_as_one_at_a_time() -> None:
    block = NormalBlock(rng(9), block=7)
    one_by_one = rng(9)
    assert [block() for _ in range(30)] == [one_by_one.standard_normal() for _ in range(30)]


def test_encoders_with_a_source_count_when_read() -> None:
    angles = np.array([0.3, -0.2])
    enc = MotorEncoders([440, 440], rng(), initial_angles=angles, source=lambda: angles)
    assert enc.counts.tolist() == [0, 0]
    angles += [TWO_PI, -TWO_PI / 2]  # the wheels turn; nothing is fed
    assert enc.counts.tolist() == [440, -220]


def test_one_encoder_counted_alone_matches_counting_them_all() -> None:
    """``count_at`` (the firmware reads one encoder at a time) gives :attr:`counts`' number bit for bit,
    on the edges too: the angles that land exactly on an edge, just below and above it, and at random."""
    cpr = [440, 16000, 7, 1633]
    start = np.array([0.3, -1.7, 12.0, 1e-12])
    angles = start.copy()
    enc = MotorEncoders(cpr, rng(), initial_angles=start, source=lambda: angles)
    draws = rng(5)
    edges = np.array([k * TWO_PI / c for c in cpr for k in (-3, -1, 1, 7, 1000)])
    near = np.concatenate((edges, np.nextafter(edges, np.inf), np.nextafter(edges, -np.inf)))
    for a in [*near, *draws.uniform(-1e3, 1e3, 400)]:
        angles[:] = start + a * np.array([1.0, -1.0, 0.5, 3.0])
        assert [enc.count_at(i, float(angles[i])) for i in range(4)] == enc.counts.tolist()


def test_the_simulator_counts_one_encoder_as_it_counts_them_all() -> None:
    from omnibot.sim.simulator import Simulator

    sim = Simulator(load_robot("omni4"), surface="carpet", seed=2)
    sim.set_pwm([120, -90, 200, -60])
    for _ in range(40):
        sim.step(7)
        assert [sim.encoder_count(k) for k in range(4)] == sim.encoder_counts()
