"""ROS map_server map files: a YAML description plus an image (PGM, or any image Pillow reads).

The YAML (what nav2's map_saver, slam_toolbox and cartographer write, and map_server reads)::

    image: map.pgm              # relative to the YAML's directory, or absolute
    mode: trinary               # trinary | scale | raw (optional, trinary by default)
    resolution: 0.05            # m per pixel
    origin: [-2.05, -2.05, 0.0] # pose of the lower-left pixel's lower-left corner: x, y, yaw
    negate: 0                   # 1: white is occupied
    occupied_thresh: 0.65
    free_thresh: 0.25

Reading (as nav2's map_server): each pixel's shade ``s`` is its grey value over the image's maximum
(colour pixels: the mean of their red, green and blue), its occupancy ``p = 1 - s`` (``s`` when
``negate``). ``trinary``: 100 where ``p > occupied_thresh``, 0 where ``p < free_thresh``, else -1.
``scale``: as trinary, with the values between the thresholds scaled linearly to 0..100, and a
pixel that is not opaque unknown. ``raw``: the pixel value itself when 0..100, else -1. The image's
top row is the map's top: rows are flipped into the grid's bottom-up order.

Writing (as ROS's map_saver in trinary mode): 254 for free cells (0..free_thresh*100, default 25),
0 for occupied ones (occupied_thresh*100..100, default 65), 205 for the rest; an 8-bit binary PGM
(P5). The YAML says ``free_thresh: 0.196`` whatever the cells were split by, as ROS 1's map_saver
and cartographer write it: 205 reads back as ``p = 50/255 = 0.19608``, so any ``free_thresh`` above
that (0.25, nav2's default) turns the unknown cells of a trinary image free when map_server loads
it. A file that says so is loaded as map_server loads it.

PGM is read here (P5 8 and 16 bit, and plain P2); other formats (PNG, BMP...) through Pillow.
Every bad file is one :class:`~omnibot.errors.ConfigError` naming the file and what is wrong.
"""

from __future__ import annotations

import difflib
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from omnibot.config_errors import read_yaml, suggest
from omnibot.errors import ConfigError
from omnibot.mapping.grid import UNKNOWN, OccupancyGrid
from omnibot.motion import Pose2D

MODES = ("trinary", "scale", "raw")
REQUIRED = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")
KNOWN = (*REQUIRED, "mode")
FREE_PIXEL, OCCUPIED_PIXEL, UNKNOWN_PIXEL = 254, 0, 205
SAVED_FREE_THRESH = 0.196
"""The free_thresh written in saved YAML: below 205's 0.19608, so unknown pixels stay unknown."""

FloatArray = NDArray[np.float64]


# --------------------------------------------------------------------------- PGM


def _pgm_tokens(raw: bytes, count: int, path: Path) -> tuple[list[int], int]:
    """The first ``count`` header integers of a PGM (comments skipped) and the offset after the
    single whitespace that ends the last one."""
    out: list[int] = []
    i = 2
    while len(out) < count:
        m = re.compile(rb"(?:\s|#[^\n]*\n?)*(\d+)").match(raw, i)
        if m is None:
            raise ConfigError(f"map image {path}: truncated or malformed PGM header")
        out.append(int(m.group(1)))
        i = m.end()
    if i >= len(raw) or raw[i : i + 1] not in (b" ", b"\n", b"\r", b"\t"):
        raise ConfigError(f"map image {path}: malformed PGM header")
    return out, i + 1


def read_pgm(path: Path) -> tuple[NDArray[np.int64], int]:
    """(rows x cols values, top row first; maxval) of a binary (P5) or plain (P2) PGM."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ConfigError(f"cannot read map image {path}: {exc.strerror}") from None
    magic = raw[:2]
    if magic not in (b"P5", b"P2"):
        raise ConfigError(f"map image {path}: not a PGM (magic {magic!r}, expected P5 or P2)")
    (width, height, maxval), start = _pgm_tokens(raw, 3, path)
    if width < 1 or height < 1 or not 0 < maxval < 65536:
        raise ConfigError(f"map image {path}: bad PGM size {width}x{height} or maxval {maxval}")
    n = width * height
    if magic == b"P5":
        dtype = np.dtype(">u2") if maxval > 255 else np.dtype(np.uint8)
        body = raw[start : start + n * dtype.itemsize]
        if len(body) < n * dtype.itemsize:
            raise ConfigError(
                f"map image {path}: {len(body)} bytes of pixels, {width}x{height} need {n * dtype.itemsize}"
            )
        values = np.frombuffer(body, dtype=dtype).astype(np.int64)
    else:
        words = raw[start:].split()
        if len(words) < n or not all(w.isdigit() for w in words[:n]):
            raise ConfigError(f"map image {path}: plain PGM needs {n} pixel values")
        values = np.array([int(w) for w in words[:n]], dtype=np.int64)
    if (values > maxval).any():
        raise ConfigError(f"map image {path}: a pixel exceeds maxval {maxval}")
    return values.reshape(height, width), maxval


def write_pgm(path: Path, pixels: NDArray[np.uint8], comment: str = "") -> None:
    """An 8-bit binary PGM (P5) of rows x cols ``pixels``, top row first."""
    rows, cols = pixels.shape
    note = f"# {comment}\n" if comment else ""
    path.write_bytes(
        f"P5\n{note}{cols} {rows}\n255\n".encode("ascii") + np.ascontiguousarray(pixels, np.uint8).tobytes()
    )


def _read_image(path: Path) -> tuple[FloatArray, NDArray[np.bool_], NDArray[np.int64]]:
    """(shade 0..1, opaque, 8-bit value) per pixel, top row first."""
    if not path.exists():
        raise ConfigError(f"map image {path} does not exist")
    if not path.is_file():
        raise ConfigError(f"map image {path} is not a file")
    with path.open("rb") as f:
        magic = f.read(2)
    if magic in (b"P5", b"P2"):
        values, maxval = read_pgm(path)
        shade = values / float(maxval)
        return shade, np.ones(values.shape, bool), np.rint(shade * 255).astype(np.int64)
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as img:
            img.load()
            mode = img.mode
            if mode in ("I;16", "I;16B", "I"):
                arr = np.asarray(img, dtype=np.float64)
                shade = arr / (65535.0 if mode.startswith("I;16") else max(float(arr.max()), 1.0))
                return shade, np.ones(arr.shape, bool), np.rint(shade * 255).astype(np.int64)
            rgba = np.asarray(img.convert("RGBA"), dtype=np.float64)
    except (OSError, UnidentifiedImageError, ValueError) as exc:
        raise ConfigError(f"cannot read map image {path}: {exc}") from None
    grey = rgba[..., :3].mean(axis=2) if mode not in ("L", "LA", "1") else rgba[..., 0]
    return grey / 255.0, rgba[..., 3] == 255, np.rint(grey).astype(np.int64)


# --------------------------------------------------------------------------- YAML


def _number(doc: dict[str, Any], key: str, source: Path) -> float:
    value = doc[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(f"invalid map {source}: {key}: expected a number, got {value!r}")
    return float(value)


def read_map_yaml(path: str | Path) -> dict[str, Any]:
    """The validated YAML of a map: image (a resolved Path), mode, resolution, origin (Pose2D),
    negate (bool), occupied_thresh, free_thresh."""
    source = Path(path)
    doc = read_yaml(source, "map")
    if doc is None:
        raise ConfigError(f"invalid map {source}: the file is empty")
    if not isinstance(doc, dict):
        raise ConfigError(f"invalid map {source}: expected a mapping of keys, got {type(doc).__name__}")
    missing = [k for k in REQUIRED if k not in doc]
    if missing:
        raise ConfigError(f"invalid map {source}: missing key{'s' * (len(missing) > 1)} {', '.join(missing)}")
    for key in doc:
        # map_server ignores keys it does not know (other tools add theirs); so do we, unless one is
        # a near miss of a key map_server reads
        near = difflib.get_close_matches(str(key), KNOWN, n=1, cutoff=0.8)
        if key not in KNOWN and near:
            raise ConfigError(f"invalid map {source}: {key}: unknown key; did you mean '{near[0]}'?")
    image = doc["image"]
    if not isinstance(image, str) or not image:
        raise ConfigError(f"invalid map {source}: image: expected a file name, got {image!r}")
    mode = doc.get("mode", "trinary")
    if mode not in MODES:
        raise ConfigError(
            f"invalid map {source}: mode: " + suggest(f"unknown mode {mode!r}", str(mode), MODES)
        )
    resolution = _number(doc, "resolution", source)
    if resolution <= 0:
        raise ConfigError(f"invalid map {source}: resolution: must be positive, got {resolution}")
    origin = doc["origin"]
    if (
        not isinstance(origin, list)
        or len(origin) != 3
        or not all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in origin
        )
    ):
        raise ConfigError(f"invalid map {source}: origin: expected [x, y, yaw], got {origin!r}")
    negate = doc["negate"]
    if negate not in (0, 1):  # also True / False
        raise ConfigError(f"invalid map {source}: negate: expected 0 or 1, got {negate!r}")
    occ, free = _number(doc, "occupied_thresh", source), _number(doc, "free_thresh", source)
    for key, value in (("occupied_thresh", occ), ("free_thresh", free)):
        if not 0.0 <= value <= 1.0:
            raise ConfigError(f"invalid map {source}: {key}: must lie in [0, 1], got {value}")
    if free >= occ:
        raise ConfigError(f"invalid map {source}: free_thresh {free} must be below occupied_thresh {occ}")
    image_path = Path(image).expanduser()
    if not image_path.is_absolute():
        image_path = source.parent / image_path
    return {
        "image": image_path,
        "mode": mode,
        "resolution": resolution,
        "origin": Pose2D(float(origin[0]), float(origin[1]), float(origin[2])),
        "negate": bool(negate),
        "occupied_thresh": occ,
        "free_thresh": free,
    }


def load_map(path_yaml: str | Path, frame: str = "map") -> OccupancyGrid:
    """The occupancy grid a map_server YAML + image describe (see the module docstring)."""
    meta = read_map_yaml(path_yaml)
    try:
        shade, opaque, value = _read_image(meta["image"])
    except ConfigError as exc:
        raise ConfigError(f"invalid map {path_yaml}: {exc}") from None
    occ_t, free_t = meta["occupied_thresh"], meta["free_thresh"]
    p = shade if meta["negate"] else 1.0 - shade
    if meta["mode"] == "raw":
        data = np.where((value >= 0) & (value <= 100), value, UNKNOWN)
    else:
        middle = UNKNOWN if meta["mode"] == "trinary" else np.rint((p - free_t) / (occ_t - free_t) * 100.0)
        data = np.where(p > occ_t, 100, np.where(p < free_t, 0, middle))
        if meta["mode"] == "scale":
            data = np.where(opaque, data, UNKNOWN)
    return OccupancyGrid(data[::-1].astype(np.int8), meta["resolution"], meta["origin"], frame)


def _yaml_float(v: float) -> str:
    return repr(float(v)).replace("inf", ".inf")


def save_map(
    grid: OccupancyGrid,
    path_yaml: str | Path,
    *,
    occupied_thresh: float = 0.65,
    free_thresh: float = 0.25,
) -> Path:
    """Write ``grid`` as path_yaml + a trinary P5 PGM beside it (same stem); returns the image's path.

    The thresholds split the grid's cells into free / occupied / unknown pixels; the YAML gets
    ``occupied_thresh`` and :data:`SAVED_FREE_THRESH` (see the module docstring).
    """
    if not 0.0 <= free_thresh < occupied_thresh <= 1.0:
        raise ValueError(
            f"need 0 <= free_thresh < occupied_thresh <= 1, not {free_thresh}, {occupied_thresh}"
        )
    yaml_path = Path(path_yaml)
    image = yaml_path.with_suffix(".pgm")
    d = grid.data.astype(np.int16)
    pixels = np.full(d.shape, UNKNOWN_PIXEL, np.uint8)
    pixels[(d >= 0) & (d <= round(free_thresh * 100))] = FREE_PIXEL
    pixels[(d >= round(occupied_thresh * 100)) & (d <= 100)] = OCCUPIED_PIXEL
    write_pgm(
        image, pixels[::-1], f"omnibot map {grid.shape[1]}x{grid.shape[0]} at {grid.resolution} m/pixel"
    )
    o = grid.origin
    yaml_path.write_text(
        f"image: {image.name}\n"
        "mode: trinary\n"
        f"resolution: {_yaml_float(grid.resolution)}\n"
        f"origin: [{_yaml_float(o.x)}, {_yaml_float(o.y)}, {_yaml_float(o.theta)}]\n"
        "negate: 0\n"
        f"occupied_thresh: {_yaml_float(occupied_thresh)}\n"
        f"free_thresh: {SAVED_FREE_THRESH}\n",
        encoding="utf-8",
    )
    return image
