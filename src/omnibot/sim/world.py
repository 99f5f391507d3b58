"""The simulated room: a small YAML format, its validation, and the geometry the simulator needs.

A world file (see docs/world_format.md) names a default ``floor`` surface, ``walls`` (thin lines the
robot may be on either side of), solid ``obstacles``, floor ``patches`` of other surfaces and an
optional ``start`` pose. Lengths in metres, angles in degrees where the key ends in ``_deg``::

    name: room
    floor: wood
    start: {x: 1.0, y: 1.0, theta_deg: 0}
    walls:
      - {shape: rectangle, min: [0, 0], max: [5, 4]}
    obstacles:
      - {shape: circle, center: [1.2, 3.0], radius: 0.25}
    patches:
      - {surface: carpet, shape: rectangle, min: [2.5, 2.2], max: [4.5, 3.6]}

Errors name the bad key and suggest the right one, as robot descriptions do::

    omnibot: invalid world room.yaml:
      obstacles[0].radus: unknown key; did you mean 'radius'?

Geometry (numpy, vectorised over segments, or compiled kernels from :mod:`omnibot.sim.kernels`
where the simulator calls it every step):

* :meth:`World.raycast` - distance along rays to the first wall or obstacle edge;
* :meth:`World.cone_range` - distance to the nearest point of any edge inside a sensor's cone
  (exact, not sampled by rays; the nearest point in a cone is never hidden behind another edge);
* :meth:`World.surface_ids` - surface under points (point in polygon; later patches win);
  :meth:`World.surface_probe` also returns how far the points may move without changing surface;
* :meth:`World.contacts` - a convex robot outline against walls and obstacles: the direction that
  pushes the robot out (unit normal), the penetration depth and a contact point;
  :meth:`World.contacts_at` does the same for a body-frame outline at a pose, into a preallocated
  buffer, and also returns how far the robot may move before it could touch anything (the
  simulator's broad phase: it skips the test while the robot stays within that distance).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import ValidationError

from omnibot.config_errors import explain, read_yaml, suggest
from omnibot.errors import ConfigError
from omnibot.motion import Pose2D
from omnibot.sim import jit
from omnibot.sim.geometry import FloatArray, IntArray, Point, cone_range, is_convex, pack_polygons
from omnibot.sim.world_spec import WorldSpec

WORLD_DIR = Path(__file__).with_name("worlds")


# --------------------------------------------------------------------------- loading


def parse_world(data: Any, source: str = "") -> World:
    """Validate a mapping (e.g. parsed YAML) into a :class:`World`."""
    if not isinstance(data, Mapping):
        raise ConfigError(f"a world must be a mapping, got {type(data).__name__} {source}".strip())
    try:
        spec = WorldSpec.model_validate(data)
    except ValidationError as exc:
        raise explain(exc, WorldSpec, "world", source) from None
    return World(spec)


def world_names() -> list[str]:
    """Names of the bundled worlds."""
    return sorted(p.stem for p in WORLD_DIR.glob("*.yaml"))


def load_world(name_or_path: str | Path) -> World:
    """A bundled world by name (``empty``, ``room``, ``corridor``, ``house``, ``long_corridor``) or a
    world file by path."""
    text = str(name_or_path)
    if text in world_names():
        path = WORLD_DIR / f"{text}.yaml"
    else:
        path = Path(text)
        if path.suffix not in {".yaml", ".yml"} and not path.exists():
            raise ConfigError(suggest(f"unknown world '{text}'", text, world_names()))
    return parse_world(read_yaml(path, "world"), str(path))


# --------------------------------------------------------------------------- geometry


@dataclass(frozen=True)
class Contact:
    """The robot outline overlapping a wall or obstacle.

    ``normal`` is the unit vector (world frame) along which the robot must move to get free,
    ``depth`` how far (m), ``point`` where the two touch (world frame), ``owner`` which item of the
    world file it is (``walls[0]``, ``obstacles[2]``).
    """

    point: Point
    normal: Point
    depth: float
    owner: str


@dataclass
class _Edges:
    """A world's wall and obstacle edges, each with its owner, and sorted for the contact tests."""

    segments: list[FloatArray] = field(default_factory=list)
    owners: list[str] = field(default_factory=list)
    thin: list[FloatArray] = field(default_factory=list)
    """Walls and non-convex obstacles, checked edge by edge."""
    thin_owner: list[int] = field(default_factory=list)
    solids: list[FloatArray] = field(default_factory=list)
    """Convex obstacles (counter-clockwise), tested whole."""
    solid_owner: list[int] = field(default_factory=list)

    @classmethod
    def of(cls, spec: WorldSpec) -> _Edges:
        """The edges of ``spec``'s walls, then its obstacles (owner ids in that order)."""
        out = cls()
        for i, wall in enumerate(spec.walls):
            s = wall.segments()
            out.segments.append(s)
            out.owners += [f"walls[{i}]"] * len(s)
            out.thin.append(s)
            out.thin_owner += [i] * len(s)
        for i, obstacle in enumerate(spec.obstacles):
            s = obstacle.segments()
            out.segments.append(s)
            out.owners += [f"obstacles[{i}]"] * len(s)
            v = obstacle.vertices()
            owner = len(spec.walls) + i
            if is_convex(v):
                out.solids.append(v)
                out.solid_owner.append(owner)
            else:
                out.thin.append(s)
                out.thin_owner += [owner] * len(s)
        return out


class World:
    """A validated world, with its geometry as numpy arrays."""

    def __init__(self, spec: WorldSpec) -> None:
        self.spec = spec
        self.name = spec.name
        self.floor = spec.floor
        names = [spec.floor]
        for patch in spec.patches:
            if patch.surface not in names:
                names.append(patch.surface)
        self.surface_names: tuple[str, ...] = tuple(names)
        """Surface id -> name; id 0 is the floor."""
        self.start: Pose2D | None = (
            Pose2D(spec.start.x, spec.start.y, math.radians(spec.start.theta_deg)) if spec.start else None
        )

        self.contact_owners: tuple[str, ...] = tuple(
            [f"walls[{i}]" for i in range(len(spec.walls))]
            + [f"obstacles[{i}]" for i in range(len(spec.obstacles))]
        )
        """Owner id (column 5 of a :meth:`contacts_at` row) -> world item name."""
        edges = _Edges.of(spec)
        self.segments: FloatArray = np.vstack(edges.segments) if edges.segments else np.zeros((0, 4))
        """(K, 4) every wall and obstacle edge, ``x0, y0, x1, y1``."""
        self.segment_owner: tuple[str, ...] = tuple(edges.owners)
        thin_edges = np.vstack(edges.thin) if edges.thin else np.zeros((0, 4))
        self._thin_v = np.ascontiguousarray(thin_edges.reshape(-1, 2), dtype=float)  # edge k: rows 2k, 2k+1
        self._thin_owner = np.array(edges.thin_owner, dtype=np.int64)
        solids = edges.solids
        self._solid_v, self._solid_off = pack_polygons(solids)
        self._solid_owner = np.array(edges.solid_owner, dtype=np.int64)
        centers = [v.mean(axis=0) for v in solids]
        self._solid_c = np.array(centers, dtype=float).reshape(-1, 2)
        self._solid_r = np.array([np.max(np.hypot(*(v - c).T)) for v, c in zip(solids, centers, strict=True)])
        self._patch_vertices = [p.vertices() for p in spec.patches]
        self._patch_v, self._patch_off = pack_polygons(self._patch_vertices)
        self._patch_sid = np.array(
            [self.surface_names.index(p.surface) for p in spec.patches], dtype=np.int64
        )
        self.packed: tuple[FloatArray, IntArray] = self._pack()
        """The contact geometry and the patches packed for the simulator's compiled step (floats,
        ints; layout: :func:`omnibot.sim.kernels.world_offsets`)."""

    def _pack(self) -> tuple[FloatArray, IntArray]:
        """The solids, thin edges and patches as one float and one int array."""
        floats = [self._solid_v, self._solid_c, self._solid_r, self._thin_v, self._patch_v]
        return (
            np.concatenate([a.ravel() for a in floats]),
            np.concatenate(
                [
                    [len(self._solid_v), len(self._solid_owner), len(self._thin_owner), len(self._patch_v)],
                    [len(self._patch_sid)],
                    self._solid_off,
                    self._solid_owner,
                    self._thin_owner,
                    self._patch_off,
                    self._patch_sid,
                ]
            ).astype(np.int64),
        )

    def __repr__(self) -> str:
        return f"World({self.name!r}, {len(self.segments)} edges, surfaces {list(self.surface_names)})"

    def with_floor(self, surface: str) -> World:
        """The same world with another default floor surface."""
        return parse_world({**self.spec.model_dump(exclude_none=True), "floor": surface}, "(floor override)")

    @property
    def bounds(self) -> tuple[float, float, float, float] | None:
        """``(x_min, y_min, x_max, y_max)`` of walls, obstacles and patches, or None for an empty world."""
        pts = [self.segments[:, :2], self.segments[:, 2:], *self._patch_vertices]
        allp = np.vstack(pts)
        if len(allp) == 0:
            return None
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))

    # ------------------------------------------------------------------ rays and cones

    def raycast(self, origins: ArrayLike, angles: ArrayLike, max_range: float = math.inf) -> FloatArray:
        """Distance from each origin along its angle to the first edge (inf if none within max_range).

        ``origins`` is (2,) or (R, 2), ``angles`` a scalar or (R,) (either is broadcast to the
        other); the result has shape (R,).
        """
        ang = np.atleast_1d(np.asarray(angles, dtype=float))
        o = np.asarray(origins, dtype=float).reshape(-1, 2)
        count = max(len(ang), len(o))
        ang, o = np.broadcast_to(ang, (count,)), np.broadcast_to(o, (count, 2))
        if len(self.segments) == 0:
            return np.full(len(ang), math.inf)
        d = np.column_stack((np.cos(ang), np.sin(ang)))
        a = self.segments[:, :2]
        e = self.segments[:, 2:] - a
        denom = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]
        ao = a[None, :, :] - o[:, None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (ao[..., 0] * e[None, :, 1] - ao[..., 1] * e[None, :, 0]) / denom
            s = (ao[..., 0] * d[:, None, 1] - ao[..., 1] * d[:, None, 0]) / denom
        hit = (np.abs(denom) > 1e-12) & (t >= 0) & (s >= 0) & (s <= 1)
        dist = np.where(hit, t, math.inf).min(axis=1)
        return np.where(dist <= max_range, dist, math.inf)

    def cone_range(
        self, x: float, y: float, heading: float, cone: float, max_range: float = math.inf
    ) -> float:
        """Distance from (x, y) to the nearest edge point within ``heading +- cone/2`` (inf if none).

        ``cone`` (rad) must be below pi. Exact: each edge is clipped to the cone, then its point
        nearest the apex is taken (:func:`~omnibot.sim.geometry.cone_range` on the world's edges).
        """
        return cone_range(self.segments, x, y, heading, cone, max_range)

    # ------------------------------------------------------------------ surfaces

    def surface_ids(self, points: ArrayLike) -> NDArray[np.int64]:
        """Surface id (index into :attr:`surface_names`) under each point; shape ``points.shape[:-1]``."""
        return self.surface_probe(points)[0]

    def surface_probe(self, points: ArrayLike) -> tuple[NDArray[np.int64], float]:
        """Surface ids under the points (as :meth:`surface_ids`) and their clearance, m.

        The clearance is the distance from the nearest point to the nearest patch edge (inf without
        patches): as long as every point moves less than that, none of them changes surface.
        """
        p = np.asarray(points, dtype=float)
        flat = np.ascontiguousarray(p.reshape(-1, 2))
        ids = np.zeros(len(flat), dtype=np.int64)
        if not len(self._patch_sid):
            return ids.reshape(p.shape[:-1]), math.inf
        clearance = jit.active.surface_probe(flat, self._patch_v, self._patch_off, self._patch_sid, ids)
        return ids.reshape(p.shape[:-1]), float(clearance)

    def surface_at(self, x: float, y: float) -> str:
        """Name of the surface at one point."""
        return self.surface_names[int(self.surface_ids([x, y]))]

    # ------------------------------------------------------------------ collisions

    def contacts(self, outline: ArrayLike) -> list[Contact]:
        """Where a convex outline (world frame, (V, 2)) overlaps walls or obstacles.

        Solid convex obstacles are tested whole (separating axes), walls and non-convex obstacles
        edge by edge; contacts of one owner whose normals are within 30 degrees are merged (the
        deepest is kept) so that a flat face pressed on a 64-gon circle pushes once, not thrice.
        """
        out = self.contact_buffer()
        count, _ = self.contacts_at(outline, 0.0, 0.0, 0.0, out)
        return self.contact_list(out[:count])

    def contact_buffer(self) -> FloatArray:
        """A buffer big enough for every contact :meth:`contacts_at` can report."""
        return np.zeros((len(self._solid_owner) + len(self._thin_owner) + 1, 6))

    def contacts_at(
        self, outline: ArrayLike, x: float, y: float, theta: float, out: FloatArray
    ) -> tuple[int, float]:
        """Contacts of a convex outline given in its own frame, placed at pose (x, y, theta).

        Writes one row per contact into ``out`` (from :meth:`contact_buffer`): point x, y, normal
        x, y, depth, owner id (index into :attr:`contact_owners`), and returns ``(count,
        clearance)``: while the outline's origin stays closer than ``clearance`` (m) to (x, y),
        whatever its rotation, it touches nothing (0 when it touches, or sits inside a solid).
        """
        body = np.ascontiguousarray(outline, dtype=float)
        count, clearance = jit.active.outline_contacts(
            body,
            float(x),
            float(y),
            float(theta),
            self._solid_v,
            self._solid_off,
            self._solid_c,
            self._solid_r,
            self._solid_owner,
            self._thin_v,
            self._thin_owner,
            out,
        )
        return int(count), float(clearance)

    def contact_list(self, rows: FloatArray | list[list[float]]) -> list[Contact]:
        """:class:`Contact` objects from :meth:`contacts_at` rows."""
        owners = self.contact_owners
        return [
            Contact((float(r[0]), float(r[1])), (float(r[2]), float(r[3])), float(r[4]), owners[int(r[5])])
            for r in rows
        ]
