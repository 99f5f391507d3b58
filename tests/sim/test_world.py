"""World files: validation errors, bundled worlds, ray casting, sonar cones, surfaces and contacts."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from omnibot.errors import ConfigError
from omnibot.robot import load_robot
from omnibot.sim.clock import Clock, SimClock, WallClock
from omnibot.sim.geometry import convex_hull
from omnibot.sim.world import (
    WORLD_DIR,
    World,
    load_world,
    parse_world,
    world_names,
)

ROOM = {"name": "box", "walls": [{"shape": "rectangle", "min": [0, 0], "max": [5, 4]}]}


def world(**extra) -> World:
    return parse_world({**ROOM, **extra})


def square(cx: float, cy: float, half: float) -> np.ndarray:
    return np.array(
        [(cx - half, cy - half), (cx + half, cy - half), (cx + half, cy + half), (cx - half, cy + half)]
    )


# --------------------------------------------------------------------------- clock


def test_sim_clock_counts_whole_microseconds() -> None:
    clock = SimClock()
    for _ in range(1000):
        clock.advance_us(1000)
    assert clock.ticks_us() == 1_000_000
    assert clock.now() == 1.0
    clock.advance(0.0015)
    assert clock.ticks_us() == 1_001_500
    with pytest.raises(ValueError, match="backwards"):
        clock.advance_us(-1)
    assert isinstance(clock, Clock) and isinstance(WallClock(), Clock)


def test_wall_clock_is_monotonic() -> None:
    clock = WallClock()
    a, b = clock.ticks_us(), clock.ticks_us()
    assert 0 <= a <= b
    assert clock.now() >= 0


# --------------------------------------------------------------------------- files


def test_the_slam_bench_worlds_are_bundled_at_their_sizes() -> None:
    assert {"house", "long_corridor"} <= set(world_names())
    house = load_world("house")
    assert house.bounds == (0.0, 0.0, 10.0, 8.0)
    assert len(house.spec.obstacles) >= 15 and {o.shape for o in house.spec.obstacles} == {"box", "circle"}
    corridor = load_world("long_corridor")
    assert corridor.bounds == (0.0, -1.0, 30.0, 1.0) and not corridor.spec.obstacles


@pytest.mark.parametrize("name", sorted(set(world_names()) - {"empty"}))
@pytest.mark.parametrize("preset", ["omni4", "omni3", "mecanum4"])
def test_every_preset_starts_clear_of_everything_in_every_bundled_world(name: str, preset: str) -> None:
    w = load_world(name)
    assert w.start is not None
    outline = convex_hull(load_robot(preset).footprint.outline())
    count, clearance = w.contacts_at(outline, w.start.x, w.start.y, w.start.theta, w.contact_buffer())
    assert count == 0 and clearance > 0.1


def test_bundled_worlds_load() -> None:
    assert {"empty", "room", "corridor"} <= set(world_names())
    empty = load_world("empty")
    assert len(empty.segments) == 0 and empty.surface_names == ("wood",) and empty.bounds is None
    room = load_world("room")
    assert room.surface_names == ("wood", "carpet")
    assert room.bounds == (0.0, 0.0, 5.0, 4.0)
    assert room.start is not None
    corridor = load_world("corridor")
    assert corridor.bounds is not None and corridor.bounds[2] - corridor.bounds[0] >= 8


def test_load_world_from_path(tmp_path: Path) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text("name: mine\nfloor: carpet\nstart: {x: 1, y: 2, theta_deg: 90}\n")
    w = load_world(path)
    assert w.name == "mine" and w.floor == "carpet"
    assert w.start is not None and w.start.theta == pytest.approx(math.pi / 2)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (
            {**ROOM, "obstacles": [{"shape": "circle", "center": [1, 1], "radus": 0.2}]},
            "obstacles[0].radus: unknown key; did you mean 'radius'?",
        ),
        ({**ROOM, "wals": []}, "wals: unknown key; did you mean 'walls'?"),
        ({"walls": []}, "name: required key is missing"),
        (
            {**ROOM, "obstacles": [{"shape": "circle", "center": [1, 1]}]},
            "obstacles[0]: a circle needs 'radius'",
        ),
        (
            {**ROOM, "obstacles": [{"shape": "box", "center": [1, 1], "size": [1, 1], "radius": 2}]},
            "obstacles[0]: 'radius' does not apply to a box",
        ),
        (
            {**ROOM, "obstacles": [{"shape": "rectangel", "min": [0, 0], "max": [1, 1]}]},
            "obstacles[0].shape: unknown value 'rectangel'; did you mean 'rectangle'?",
        ),
        (
            {**ROOM, "obstacles": [{"shape": "polyline", "points": [[0, 0], [1, 1]]}]},
            "obstacles[0]: an obstacle must be a closed shape",
        ),
        (
            {**ROOM, "patches": [{"surface": "carpt", "shape": "rectangle", "min": [0, 0], "max": [1, 1]}]},
            "patches[0].surface: unknown surface 'carpt'; did you mean 'carpet'?",
        ),
        ({**ROOM, "floor": "wod"}, "floor: unknown surface 'wod'; did you mean 'wood'?"),
        (
            {**ROOM, "walls": [{"shape": "rectangle", "min": [2, 0], "max": [1, 1]}]},
            "walls[0]: a rectangle needs min < max",
        ),
        (
            {**ROOM, "walls": [{"shape": "polygon", "points": [[0, 0], [1, 1]]}]},
            "walls[0]: a polygon needs at least 3 points",
        ),
        ({**ROOM, "start": {"x": 0, "y": 0, "heading": 3}}, "start.heading: unknown key; did you mean"),
        (
            {**ROOM, "patches": [{"surface": "wood", "shape": "circle", "center": [0, 0], "radius": -1}]},
            "patches[0].radius",
        ),
    ],
)
def test_bad_world_names_the_key(data: dict[str, Any], message: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_world(data, "test.yaml")
    assert message in str(info.value)
    assert "invalid world test.yaml" in str(info.value)


def test_bad_world_files(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="unknown world 'rooom'; did you mean 'room'"):
        load_world("rooom")
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: [unclosed\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_world(bad)
    listy = tmp_path / "list.yaml"
    listy.write_text("- 1\n- 2\n")
    with pytest.raises(ConfigError, match="must be a mapping"):
        load_world(listy)
    with pytest.raises(ConfigError, match="cannot read world"):
        load_world(tmp_path / "missing.yaml")


def test_a_key_given_twice_in_a_world_is_refused(tmp_path: Path) -> None:
    text = (WORLD_DIR / "room.yaml").read_text()
    start = text.splitlines().index("start: {x: 1.0, y: 1.0, theta_deg: 0}") + 1
    mine = tmp_path / "lab.yaml"
    mine.write_text(text.replace("theta_deg: 0}", "theta_deg: 0,\n  x: 4.0}"))
    with pytest.raises(ConfigError) as info:
        load_world(mine)
    assert (
        str(info.value)
        == f"invalid world {mine}: start.x: duplicate key on line {start + 1} (first on line {start})"
    )
    mine.write_text(text + "floor: carpet\n")
    with pytest.raises(
        ConfigError, match=r"lab\.yaml: floor: duplicate key on line \d+ \(first on line 5\)$"
    ):
        load_world(mine)


def test_with_floor_overrides_and_validates() -> None:
    room = load_world("room")
    tiled = room.with_floor("linoleum")
    assert tiled.surface_names == ("linoleum", "carpet") and len(tiled.segments) == len(room.segments)
    with pytest.raises(ConfigError, match="did you mean 'carpet'"):
        room.with_floor("carpt")


# --------------------------------------------------------------------------- rays


def test_raycast_inside_a_rectangle() -> None:
    w = world()
    angles = [0.0, math.pi / 2, math.pi, -math.pi / 2, math.atan2(3, 4)]
    d = w.raycast((1.0, 1.0), angles)
    np.testing.assert_allclose(d, [4.0, 3.0, 1.0, 1.0, 5.0], atol=1e-12)
    assert math.isinf(w.raycast((1.0, 1.0), 0.0, max_range=3.9)[0])
    assert math.isinf(load_world("empty").raycast((0, 0), 0.0)[0])
    np.testing.assert_allclose(w.raycast([(1.0, 1.0), (2.0, 3.0)], math.pi / 2), [3.0, 1.0])


def test_raycast_many_origins_and_a_circle() -> None:
    w = world(obstacles=[{"shape": "circle", "center": [3, 2], "radius": 0.5}])
    d = w.raycast([(1.0, 2.0), (4.5, 2.0), (3.0, 0.5)], [0.0, math.pi, math.pi / 2])
    np.testing.assert_allclose(d, [1.5, 1.0, 1.0], atol=0.5 * (1 - math.cos(math.pi / 64)) + 1e-9)
    # the nearest edge wins: a box in front hides the circle
    w2 = world(
        obstacles=[
            {"shape": "circle", "center": [3, 2], "radius": 0.5},
            {"shape": "box", "center": [2, 2], "size": [0.2, 0.2]},
        ]
    )
    assert w2.raycast((1.0, 2.0), 0.0)[0] == pytest.approx(0.9)


# --------------------------------------------------------------------------- sonar cones


def test_cone_sees_a_wall_at_its_perpendicular_distance() -> None:
    w = world()
    assert w.cone_range(1.0, 2.0, 0.0, math.radians(15)) == pytest.approx(4.0)
    # tilted 5 degrees: the foot of the perpendicular is still inside a 15 degree cone
    assert w.cone_range(1.0, 2.0, math.radians(5), math.radians(15)) == pytest.approx(4.0)
    # tilted 20 degrees: the nearest point in the cone is on the cone's edge
    expect = 4.0 / math.cos(math.radians(12.5))
    assert w.cone_range(1.0, 2.0, math.radians(20), math.radians(15)) == pytest.approx(expect)
    assert math.isinf(w.cone_range(1.0, 2.0, 0.0, math.radians(15), max_range=3.0))


@pytest.mark.parametrize(
    ("bearing_deg", "seen"), [(0, True), (6.0, True), (-6.0, True), (8.5, False), (-9, False)]
)
def test_cone_catches_an_off_axis_post_only_within_half_the_cone(bearing_deg: float, seen: bool) -> None:
    b = math.radians(bearing_deg)
    post = {"shape": "box", "center": [1 + 2 * math.cos(b), 2 + 2 * math.sin(b)], "size": [0.02, 0.02]}
    w = world(obstacles=[post])
    d = w.cone_range(1.0, 2.0, 0.0, math.radians(15))
    if seen:
        assert d == pytest.approx(2.0, abs=0.015)
    else:
        assert d == pytest.approx(4.0)  # the far wall, not the post


def test_cone_never_sees_behind_and_is_never_farther_than_its_axis_ray() -> None:
    w = world(obstacles=[{"shape": "circle", "center": [0.5, 2.0], "radius": 0.2}])
    assert w.cone_range(1.0, 2.0, 0.0, math.radians(15)) == pytest.approx(4.0)
    rng = np.random.default_rng(1)
    for _ in range(50):
        x, y, h = rng.uniform(0.5, 4.5), rng.uniform(0.5, 3.5), rng.uniform(-math.pi, math.pi)
        assert w.cone_range(x, y, h, math.radians(15)) <= w.raycast((x, y), h)[0] + 1e-9
    with pytest.raises(ValueError):
        w.cone_range(1, 1, 0, math.pi)


# --------------------------------------------------------------------------- surfaces


def test_surface_lookup_with_patches_later_wins() -> None:
    w = world(
        floor="wood",
        patches=[
            {"surface": "carpet", "shape": "rectangle", "min": [1, 1], "max": [3, 3]},
            {"surface": "concrete", "shape": "circle", "center": [3, 3], "radius": 0.5},
            {"surface": "carpet", "shape": "polygon", "points": [[4, 0], [5, 0], [5, 1]]},
        ],
    )
    assert w.surface_names == ("wood", "carpet", "concrete")
    pts = np.array([[0.5, 0.5], [2, 2], [2.9, 2.9], [3.3, 3.3], [4.9, 0.5], [4.1, 0.9]])
    assert [w.surface_names[i] for i in w.surface_ids(pts)] == [
        "wood",
        "carpet",
        "concrete",
        "concrete",
        "carpet",
        "wood",
    ]
    assert w.surface_ids(pts.reshape(2, 3, 2)).shape == (2, 3)
    assert w.surface_at(2.0, 1.5) == "carpet"
    assert load_world("room").surface_at(3.5, 3.0) == "carpet"
    assert load_world("room").surface_at(1.0, 1.0) == "wood"


# --------------------------------------------------------------------------- contacts


def test_no_contact_when_clear() -> None:
    assert world().contacts(square(2.5, 2.0, 0.1)) == []
    assert load_world("empty").contacts(square(0, 0, 0.1)) == []


def test_flat_contact_with_a_wall() -> None:
    (c,) = world().contacts(square(4.905, 2.0, 0.1))  # 5 mm into the east wall
    assert c.depth == pytest.approx(0.005)
    assert c.normal == pytest.approx((-1.0, 0.0))
    assert c.point == pytest.approx((5.0025, 2.0))  # middle of the face, half way into the wall
    (c,) = world().contacts(square(4.905, 0.3, 0.1))
    assert c.point == pytest.approx((5.0025, 0.3))
    assert c.owner == "walls[0]"


def test_corner_contact_gives_two_normals() -> None:
    contacts = world().contacts(square(4.905, 3.903, 0.1))
    normals = sorted(tuple(round(v, 6) for v in c.normal) for c in contacts)
    assert normals == [(-1.0, 0.0), (0.0, -1.0)]
    assert sorted(round(c.depth, 6) for c in contacts) == [0.003, 0.005]


def test_contact_with_solid_obstacles_pushes_out() -> None:
    w = world(
        obstacles=[
            {"shape": "box", "center": [2, 2], "size": [1, 1], "angle_deg": 0},
            {"shape": "circle", "center": [4, 1], "radius": 0.3},
        ]
    )
    (c,) = w.contacts(square(2.59, 2.0, 0.1))
    assert (
        c.owner == "obstacles[0]" and c.normal == pytest.approx((1.0, 0.0)) and c.depth == pytest.approx(0.01)
    )
    # a robot corner poking the circle from the north-west pushes it back along the diagonal
    d = 0.3 / math.sqrt(2) - 0.005
    outline = square(4 - d - 0.1, 1 + d + 0.1, 0.1)
    (c,) = w.contacts(outline)
    assert c.owner == "obstacles[1]"
    assert c.normal[0] < -0.6 and c.normal[1] > 0.6 and 0 < c.depth < 0.01
    # deep inside a solid still pushes out of it
    (c,) = w.contacts(square(2.3, 2.0, 0.1))
    assert c.normal == pytest.approx((1.0, 0.0)) and c.depth == pytest.approx(0.3)


def test_thin_wall_end_pushes_sideways() -> None:
    w = parse_world({"name": "fin", "walls": [{"shape": "polyline", "points": [[0, 0], [2, 0]]}]})
    (c,) = w.contacts(square(2.09, 0.0, 0.1))  # the wall's end pokes 1 cm into the robot's west face
    assert c.normal == pytest.approx((1.0, 0.0)) and c.depth == pytest.approx(0.01)
    assert c.point == pytest.approx((1.995, 0.0))
    (c,) = w.contacts(square(1.0, -0.095, 0.1))  # from below: pushed down
    assert c.normal == pytest.approx((0.0, -1.0)) and c.depth == pytest.approx(0.005)
