"""The world file's format: its shapes (walls, obstacles, floor patches), the start pose and the whole
file, validated (docs/world_format.md)."""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, model_validator

from omnibot.config_errors import suggest
from omnibot.floor import SURFACES
from omnibot.sim.geometry import FloatArray, Point, ccw

CIRCLE_SEGMENTS = 64
"""Edges of the polygon standing in for a circle (radial error 0.12 % of the radius)."""

_SHAPE_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    # shape: (required keys, optional keys)
    "polyline": (("points",), ("closed",)),
    "polygon": (("points",), ()),
    "rectangle": (("min", "max"), ()),
    "box": (("center", "size"), ("angle_deg",)),
    "circle": (("center", "radius"), ()),
}
_GEOMETRY_KEYS = ("points", "closed", "min", "max", "center", "size", "angle_deg", "radius")


class _Spec(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class ShapeSpec(_Spec):
    """One outline: ``polyline`` (walls only), ``polygon``, ``rectangle``, ``box`` or ``circle``."""

    shape: Literal["polyline", "polygon", "rectangle", "box", "circle"]
    points: tuple[Point, ...] | None = None
    closed: bool | None = None
    min: Point | None = None
    max: Point | None = None
    center: Point | None = None
    size: Point | None = None
    angle_deg: float | None = None
    radius: float | None = Field(default=None, gt=0)

    @model_validator(mode="after")
    def _check_shape(self) -> ShapeSpec:
        need, optional = _SHAPE_KEYS[self.shape]
        takes = need + optional
        for key in need:
            if getattr(self, key) is None:
                raise ValueError(f"a {self.shape} needs '{key}'")
        for key in _GEOMETRY_KEYS:
            if key not in takes and getattr(self, key) is not None:
                raise ValueError(f"'{key}' does not apply to a {self.shape} (it takes {', '.join(takes)})")
        if self.points is not None:
            least = 2 if self.shape == "polyline" else 3
            if len(self.points) < least:
                raise ValueError(f"a {self.shape} needs at least {least} points, got {len(self.points)}")
        if (
            self.min is not None
            and self.max is not None
            and not (self.min[0] < self.max[0] and self.min[1] < self.max[1])
        ):
            raise ValueError(f"a rectangle needs min < max in x and y, got min {self.min}, max {self.max}")
        if self.size is not None and not (self.size[0] > 0 and self.size[1] > 0):
            raise ValueError(f"a box needs a positive size, got {self.size}")
        return self

    @property
    def is_closed(self) -> bool:
        """Whether the outline is closed (only a polyline may be open)."""
        return self.shape != "polyline" or bool(self.closed)

    def vertices(self) -> FloatArray:
        """(V, 2) vertices in the world frame; closed shapes counter-clockwise (circles as 64-gons)."""
        if self.shape in ("polyline", "polygon"):
            assert self.points is not None
            pts = np.array(self.points, dtype=float)
            return ccw(pts) if self.shape == "polygon" else pts
        if self.shape == "rectangle":
            assert self.min is not None and self.max is not None
            (x0, y0), (x1, y1) = self.min, self.max
            return np.array([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], dtype=float)
        assert self.center is not None
        if self.shape == "box":
            assert self.size is not None
            hx, hy = self.size[0] / 2, self.size[1] / 2
            local = np.array([(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)])
            a = math.radians(self.angle_deg or 0.0)
            rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
            return np.asarray(local @ rot.T + np.array(self.center), dtype=float)
        assert self.radius is not None
        k = np.arange(CIRCLE_SEGMENTS) * (2 * math.pi / CIRCLE_SEGMENTS)
        return np.asarray(np.column_stack((np.cos(k), np.sin(k))) * self.radius + np.array(self.center))

    def segments(self) -> FloatArray:
        """(K, 4) edges ``x0, y0, x1, y1`` (zero-length edges of repeated points left out)."""
        v = self.vertices()
        end = np.roll(v, -1, axis=0) if self.is_closed else v[1:]
        seg = np.hstack((v[: len(end)], end))
        return seg[np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]) > 1e-12]


class WallSpec(ShapeSpec):
    """A wall: a thin line (or closed loop) the robot collides with from either side."""


class ObstacleSpec(ShapeSpec):
    """A solid obstacle: any closed shape."""

    @model_validator(mode="after")
    def _check_closed(self) -> ObstacleSpec:
        if self.shape == "polyline":
            raise ValueError("an obstacle must be a closed shape (polygon, rectangle, box or circle)")
        return self


def _known_surface(name: str) -> str:
    if name not in SURFACES:
        raise ValueError(suggest(f"unknown surface '{name}'", name, list(SURFACES)))
    return name


SurfaceName = Annotated[str, AfterValidator(_known_surface)]


class PatchSpec(ShapeSpec):
    """A floor area of another surface; a later patch covers an earlier one."""

    surface: SurfaceName

    @model_validator(mode="after")
    def _check_closed(self) -> PatchSpec:
        if self.shape == "polyline":
            raise ValueError("a patch must be a closed shape (polygon, rectangle, box or circle)")
        return self


class StartSpec(_Spec):
    """The robot's start pose in the world: x, y (m) and heading (degrees)."""

    x: float
    y: float
    theta_deg: float = 0.0


class WorldSpec(_Spec):
    """A whole world file."""

    name: str
    summary: str = ""
    floor: SurfaceName = "wood"
    start: StartSpec | None = None
    walls: tuple[WallSpec, ...] = ()
    obstacles: tuple[ObstacleSpec, ...] = ()
    patches: tuple[PatchSpec, ...] = ()
