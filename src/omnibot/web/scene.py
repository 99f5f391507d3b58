"""What the page draws that does not move: the room map, the robot's outline, wheels and sonars, a path.

:func:`build_scene` turns a robot description, an optional world and an optional planned path into
one JSON-ready dict (SI units, radians), sent to each page when it connects. :func:`load_path` reads
a planned path from a CSV file (``x,y`` rows, or the ``x`` and ``y`` columns of a file with a header).

A path is drawn where driving it would take the robot: ``omnibot follow`` drives a path from where
the robot stands (the path's start pose on the robot's pose), so :meth:`PlannedPath.placed` puts the
path's first point on the robot and turns it by the robot's heading less the path's start heading.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from omnibot.control.paths import files as path_files
from omnibot.errors import ConfigError
from omnibot.robot import RobotDescription
from omnibot.sim import World

Point = tuple[float, float]
Pose = tuple[float, float, float]


@dataclass(frozen=True)
class PlannedPath:
    """A path to draw, in its file's frame: its points and its heading at the start (rad; the
    ``theta`` column's first value, 0 for ``x,y`` rows)."""

    points: tuple[Point, ...]
    heading: float = 0.0

    def placed(self, pose: Pose | None) -> list[Point]:
        """The points where driving the path from ``pose`` takes them (None: as in the file)."""
        if pose is None:
            return list(self.points)
        x0, y0 = self.points[0]
        turn = pose[2] - self.heading
        c, s = math.cos(turn), math.sin(turn)
        return [
            (pose[0] + c * (x - x0) - s * (y - y0), pose[1] + s * (x - x0) + c * (y - y0))
            for x, y in self.points
        ]


def _points(vertices: Any) -> list[list[float]]:
    return [[round(float(x), 4), round(float(y), 4)] for x, y in vertices]


def robot_scene(robot: RobotDescription) -> dict[str, Any]:
    """The robot's footprint outline, wheels and sonars, in the body frame."""
    wheels = []
    for w in robot.wheels:
        x, y = w.position
        wheels.append(
            {"name": w.name, "x": x, "y": y, "angle": w.drive_angle, "radius": w.radius, "width": w.width}
        )
    sonars = [
        {"name": s.name, "x": s.x, "y": s.y, "angle": s.angle, "cone": s.cone, "max_range": s.max_range}
        for s in robot.sonars
    ]
    return {
        "name": robot.name,
        "footprint": _points(robot.footprint.outline()),
        "wheels": wheels,
        "sonars": sonars,
        "encoders": len(robot.encoders.motors),
    }


def world_scene(world: World | None) -> dict[str, Any] | None:
    """Walls and obstacle edges, obstacle outlines and floor patches, and the bounds to show."""
    if world is None:
        return None
    spec = world.spec
    return {
        "name": world.name,
        "floor": world.floor,
        "segments": [[round(float(v), 4) for v in seg] for seg in world.segments],
        "obstacles": [_points(o.vertices()) for o in spec.obstacles],
        "patches": [{"surface": p.surface, "points": _points(p.vertices())} for p in spec.patches],
        "bounds": world.bounds,
    }


def build_scene(
    robot: RobotDescription, world: World | None = None, path: Sequence[Point] | None = None
) -> dict[str, Any]:
    """The ``scene`` frame: robot, world (None: no map) and planned path (None: none) in the frame
    of the pose the page shows (see :meth:`PlannedPath.placed`)."""
    return {
        "type": "scene",
        "robot": robot_scene(robot),
        "world": world_scene(world),
        "path": [[x, y] for x, y in path] if path else None,
    }


def load_path(file: str | Path) -> PlannedPath:
    """A planned path from a CSV file: with a header, its ``x`` and ``y`` columns (and the first
    ``theta``, so the navigation path files, ``t,x,y,theta[,v]``, are read as they are); without one,
    ``x,y`` in the first two columns. Metres; blank lines and lines starting with ``#`` are skipped."""
    p = Path(file)
    try:
        text = p.read_text(encoding="utf-8-sig")  # a spreadsheet's "CSV UTF-8" starts with a BOM
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) else "not a text (UTF-8) file"
        raise ConfigError(f"cannot read path {p}: {reason}", key="--path") from None
    points: list[Point] = []
    ix, iy = 0, 1
    ith: int | None = None
    heading = 0.0
    first = True
    for n, row in enumerate(csv.reader(text.splitlines()), 1):
        if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
            continue
        if first:
            first = False
            names = [c.strip().lower() for c in row]
            if "x" in names and "y" in names:
                ix, iy = names.index("x"), names.index("y")
                ith = names.index("theta") if "theta" in names else None
                continue
        try:
            x, y = float(row[ix]), float(row[iy])
        except (ValueError, IndexError):
            raise ConfigError(
                f"{p} line {n}: expected x,y in metres, got {','.join(row)!r}", key="--path"
            ) from None
        bound = path_files.LIMITS["x"][0]
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ConfigError(f"{p} line {n}: x and y must be finite", key="--path")
        if max(abs(x), abs(y)) > bound:
            raise ConfigError(f"{p} line {n}: x and y must be within {bound:g} m", key="--path")
        if ith is not None and not points:
            try:
                heading = float(row[ith])
            except (ValueError, IndexError):
                raise ConfigError(f"{p} line {n}: expected theta in radians", key="--path") from None
            if not math.isfinite(heading):
                raise ConfigError(f"{p} line {n}: theta must be finite", key="--path")
        points.append((x, y))
    if len(points) < 2:
        raise ConfigError(f"{p}: a path needs at least 2 points, got {len(points)}", key="--path")
    return PlannedPath(tuple(points), heading)
