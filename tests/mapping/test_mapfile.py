"""map_server files: against Pillow's images and hand-written YAML as other tools write it, round trips,
and one clear error for every bad file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from omnibot.errors import ConfigError
from omnibot.mapping.grid import OccupancyGrid
from omnibot.mapping.mapfile import load_map, read_pgm, save_map
from omnibot.motion import Pose2D

ROS1_MAP_SAVER = """image: {image}
resolution: 0.050000
origin: [-1.500000, -2.250000, 0.000000]
negate: 0
occupied_thresh: 0.65
free_thresh: 0.196

"""
NAV2 = """image: {image}
mode: trinary
resolution: 0.05
origin: [-1.5, -2.25, 0]
negate: 0
occupied_thresh: 0.65
free_thresh: 0.25
"""
CARTOGRAPHER = """image: {image}
resolution: 0.050000
origin: [-1.500000, -2.250000, 0.000000]
negate: 0
occupied_thresh: 0.65
free_thresh: 0.196
"""


def image_top_first() -> np.ndarray:
    """3 rows x 4 cols: the top row has an occupied pixel at its left, the bottom row is free."""
    return np.array([[0, 205, 205, 254], [205, 205, 254, 254], [254, 254, 254, 254]], np.uint8)


@pytest.mark.parametrize("text", [ROS1_MAP_SAVER, CARTOGRAPHER])
@pytest.mark.parametrize("ext", ["pgm", "png"])
def test_maps_written_by_other_tools_load_with_rows_bottom_up(tmp_path: Path, text: str, ext: str) -> None:
    Image.fromarray(image_top_first(), "L").save(tmp_path / f"m.{ext}")
    (tmp_path / "m.yaml").write_text(text.format(image=f"m.{ext}"))
    g = load_map(tmp_path / "m.yaml")
    assert g.resolution == 0.05 and g.origin == Pose2D(-1.5, -2.25, 0.0)
    assert g.data.tolist() == [[0, 0, 0, 0], [-1, -1, 0, 0], [100, -1, -1, 0]]


def test_free_thresh_above_205s_shade_reads_unknown_pixels_as_free_as_map_server_does(tmp_path: Path) -> None:
    Image.fromarray(image_top_first(), "L").save(tmp_path / "m.pgm")
    (tmp_path / "m.yaml").write_text(NAV2.format(image="m.pgm"))
    assert load_map(tmp_path / "m.yaml").data.tolist() == [[0, 0, 0, 0], [0, 0, 0, 0], [100, 0, 0, 0]]


def test_keys_map_server_does_not_read_are_ignored(tmp_path: Path) -> None:
    Image.fromarray(image_top_first(), "L").save(tmp_path / "m.pgm")
    extra = "elevation_image: e.pgm\nmin_height: -1.0\nmax_height: 2.0\nbinary: false\n"
    (tmp_path / "m.yaml").write_text(CARTOGRAPHER.format(image="m.pgm") + extra)
    assert load_map(tmp_path / "m.yaml").shape == (3, 4)


def test_saved_maps_are_read_by_pillow_as_map_saver_writes_them(tmp_path: Path) -> None:
    data = np.array([[0, 10, 25, 26], [50, 64, 65, 100], [-1, -1, 0, 100]], np.int8)
    image = save_map(OccupancyGrid(data, 0.1, Pose2D(1.0, -2.0, 0.5)), tmp_path / "out.yaml")
    with Image.open(image) as img:
        assert img.format == "PPM" and img.mode == "L"
        pixels = np.asarray(img)
    assert image.read_bytes().startswith(b"P5")
    assert pixels.tolist() == [[205, 205, 254, 0], [205, 205, 0, 0], [254, 254, 254, 205]]
    text = (tmp_path / "out.yaml").read_text()
    assert "image: out.pgm\nmode: trinary\nresolution: 0.1\norigin: [1.0, -2.0, 0.5]\nnegate: 0\n" in text
    assert "occupied_thresh: 0.65\nfree_thresh: 0.196\n" in text


def test_round_trip_keeps_trinary_maps_exactly(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    data = rng.choice(np.array([-1, 0, 100], np.int8), size=(37, 53))
    grid = OccupancyGrid(data, 0.05, Pose2D(-2.05, 3.1, 0.0))
    save_map(grid, tmp_path / "r.yaml")
    back = load_map(tmp_path / "r.yaml")
    assert np.array_equal(back.data, grid.data) and back.origin == grid.origin and back.resolution == 0.05


def test_round_trip_of_a_probability_map_keeps_what_the_thresholds_decide(tmp_path: Path) -> None:
    data = np.arange(-1, 101, dtype=np.int8).reshape(6, 17)
    save_map(OccupancyGrid(data, 0.05), tmp_path / "p.yaml")
    back = load_map(tmp_path / "p.yaml").data
    assert (back[(data >= 0) & (data <= 25)] == 0).all() and (back[data >= 65] == 100).all()
    assert (back[(data > 25) & (data < 65)] == -1).all() and (back[data == -1] == -1).all()


def test_scale_raw_negate_and_absolute_paths(tmp_path: Path) -> None:
    pixels = np.array([[0, 51, 102, 153, 204, 255]], np.uint8)  # p = 1 - s: 1, .8, .6, .4, .2, 0
    Image.fromarray(pixels, "L").save(tmp_path / "s.pgm")
    absolute = (tmp_path / "s.pgm").resolve()
    base = f"image: {absolute}\nresolution: 1\norigin: [0, 0, 0]\noccupied_thresh: 0.7\nfree_thresh: 0.3\n"
    sub = tmp_path / "elsewhere"
    sub.mkdir()
    for mode, negate, expect in [
        ("scale", 0, [100, 100, 75, 25, 0, 0]),
        ("trinary", 0, [100, 100, -1, -1, 0, 0]),
        ("trinary", 1, [0, 0, -1, -1, 100, 100]),
        ("raw", 0, [0, 51, -1, -1, -1, -1]),
    ]:
        (sub / "m.yaml").write_text(base + f"mode: {mode}\nnegate: {negate}\n")
        assert load_map(sub / "m.yaml").data.tolist() == [expect], mode


def test_scale_mode_makes_transparent_pixels_unknown(tmp_path: Path) -> None:
    rgba = np.array([[[0, 0, 0, 255], [0, 0, 0, 0], [255, 255, 255, 255], [255, 0, 0, 255]]], np.uint8)
    Image.fromarray(rgba, "RGBA").save(tmp_path / "a.png")
    text = "image: a.png\nresolution: 1\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\n"
    (tmp_path / "a.yaml").write_text(text + "mode: scale\n")
    assert load_map(tmp_path / "a.yaml").data.tolist() == [[100, -1, 0, 100]]  # red: mean shade 1/3
    (tmp_path / "a.yaml").write_text(text)
    assert load_map(tmp_path / "a.yaml").data.tolist() == [[100, 100, 0, 100]]


def test_plain_and_16_bit_pgm_are_read_as_pillow_reads_them(tmp_path: Path) -> None:
    (tmp_path / "p2.pgm").write_bytes(b"P2\n# a comment\n3 2\n# another\n15\n0 15 7\n15 15 0\n")
    values, maxval = read_pgm(tmp_path / "p2.pgm")
    assert maxval == 15 and values.tolist() == [[0, 15, 7], [15, 15, 0]]
    with Image.open(tmp_path / "p2.pgm") as img:
        assert np.array_equal(np.asarray(img, dtype=np.int64) * 15 // 255, values)
    wide = np.array([[0, 1000, 65535]], np.uint16)
    (tmp_path / "w.pgm").write_bytes(b"P5 3 1 65535\n" + wide.astype(">u2").tobytes())
    assert read_pgm(tmp_path / "w.pgm")[0].tolist() == [[0, 1000, 65535]]
    (tmp_path / "w.yaml").write_text(
        "image: w.pgm\nresolution: 1\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\n"
    )
    assert load_map(tmp_path / "w.yaml").data.tolist() == [[100, 100, 0]]


GOOD = (
    "image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\n"
)


@pytest.mark.parametrize(
    ("yaml_text", "image_bytes", "message"),
    [
        ("image: [m.pgm\n", None, "is not valid YAML"),
        ("- a\n- b\n", None, "expected a mapping"),
        ("# nothing\n", None, "the file is empty"),
        (GOOD.replace("m.pgm", "."), None, "is not a file"),
        (GOOD.replace("resolution: 0.05\n", ""), None, "missing key resolution"),
        (
            GOOD.replace("negate: 0\n", "").replace("origin: [0, 0, 0]\n", ""),
            None,
            "missing keys origin, negate",
        ),
        (GOOD + "mode: trinry\n", None, "unknown mode 'trinry'; did you mean 'trinary'"),
        (GOOD + "occupied_tresh: 0.5\n", None, "occupied_tresh: unknown key; did you mean 'occupied_thresh'"),
        (GOOD.replace("0.65", "1.5"), None, "occupied_thresh: must lie in [0, 1], got 1.5"),
        (GOOD.replace("0.25", "0.7"), None, "free_thresh 0.7 must be below occupied_thresh 0.65"),
        (GOOD.replace("0.25", "low"), None, "free_thresh: expected a number"),
        (GOOD.replace("0.05", "-1"), None, "resolution: must be positive"),
        (GOOD.replace("[0, 0, 0]", "[0, 0]"), None, "origin: expected [x, y, yaw]"),
        (GOOD.replace("negate: 0", "negate: 2"), None, "negate: expected 0 or 1"),
        (GOOD, None, "m.pgm does not exist"),
        (GOOD, b"P5\n4 4\n255\n\x00", "1 bytes of pixels, 4x4 need 16"),
        (GOOD, b"P5\n4 \n", "malformed PGM header"),
        (GOOD.replace("m.pgm", "m.png"), b"not an image", "cannot read map image"),
    ],
)
def test_every_bad_file_is_one_config_error_naming_the_file(
    tmp_path: Path, yaml_text: str, image_bytes: bytes | None, message: str
) -> None:
    if image_bytes is not None:
        name = "m.png" if "m.png" in yaml_text else "m.pgm"
        (tmp_path / name).write_bytes(image_bytes)
    (tmp_path / "bad.yaml").write_text(yaml_text)
    with pytest.raises(ConfigError) as err:
        load_map(tmp_path / "bad.yaml")
    assert message in str(err.value)
    assert "bad.yaml" in str(err.value)


def test_a_missing_yaml_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"nothere\.yaml"):
        load_map(tmp_path / "nothere.yaml")
