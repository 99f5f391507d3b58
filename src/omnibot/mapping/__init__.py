"""The SLAM bench: maps, scan matching, localisation, planning, and scores against the truth.

Modules (each owns one thing; the plain scan type is :mod:`omnibot.scan`):

* :mod:`omnibot.mapping.grid` - :class:`~omnibot.mapping.grid.OccupancyGrid`, the map every other
  module reads (ROS nav_msgs/OccupancyGrid conventions).
* :mod:`omnibot.mapping.mapper` - :class:`~omnibot.mapping.mapper.OccupancyMapper`: (scan, pose)
  pairs -> log-odds grid (compiled ray walk), growing to fit; cheap rebuilds after a loop closure.
* :mod:`omnibot.mapping.mapfile` - ROS map_server files: ``save_map`` / ``load_map`` (YAML + PGM,
  PNG...; trinary, scale and raw modes).
* :mod:`omnibot.mapping.score` - ``score_map``: a map's precision and recall against the world's
  own geometry.
* :mod:`omnibot.mapping.trajectory` - TUM trajectory files and ``score_trajectory`` (APE / RPE
  with evo).
* :mod:`omnibot.mapping.localise` - :class:`~omnibot.mapping.localise.Localiser`: a likelihood-field
  particle filter refined by scan-to-map matching, in a saved map.
* :mod:`omnibot.mapping.se2` - planar pose algebra on :class:`~omnibot.motion.Pose2D` (compose,
  inverse, between, points moved by a pose, covariances turned between frames).
* :mod:`omnibot.mapping.deskew` - motion-distortion correction: a spinning scanner's returns brought
  to one instant of the base's motion.
* :mod:`omnibot.mapping.matcher` - :class:`~omnibot.mapping.matcher.ScanMatcher`, 2D scan
  registration (correlative search then point-to-line ICP) with a covariance that shows degeneracy.
  Its parts: :mod:`~omnibot.mapping.target` (a target's points, normals and likelihood grid),
  :mod:`~omnibot.mapping.correlative` (the correlative search, compiled),
  :mod:`~omnibot.mapping.icp` (point-to-line ICP, ``MatchResult``) and
  :mod:`~omnibot.mapping.degeneracy` (the constrained directions, the covariance).
* :mod:`omnibot.mapping.slam` - :class:`~omnibot.mapping.slam.Slam`, online 2D SLAM: keyframes
  matched to a local submap, a gtsam pose graph with verified, robust loop closures.
  Its parts: :mod:`~omnibot.mapping.keyframes` (the keyframes, their submaps),
  :mod:`~omnibot.mapping.anchor` (a degenerate match completed on the anchor submap),
  :mod:`~omnibot.mapping.loops` (loop closures) and :mod:`~omnibot.mapping.posegraph` (the gtsam
  pose graph and its optimiser).
* :mod:`omnibot.mapping.session` - the runtime's sinks: :class:`~omnibot.mapping.session.MappingSink`
  (scans and odometry into the SLAM) and :class:`~omnibot.mapping.session.LocalisingSink` (into
  a localiser). Its parts: :mod:`~omnibot.mapping.feed` (``ScanFeed``: scans meet the odometry of
  their time; ``Track``), :mod:`~omnibot.mapping.snapshot` (``MapSnapshot``, ``RangeNoise``: the
  run's map) and :mod:`~omnibot.mapping.report` (``write_outputs``, ``write_report``,
  ``score_lines``: the run's files and scores).
* :mod:`omnibot.mapping.planner` - ``plan_path``: a collision-free path for a disc robot on a
  grid, on the parts below.
* :mod:`omnibot.mapping.costmap` - :class:`~omnibot.mapping.costmap.CostMap` and ``inflate``: the
  walls inflated by the robot's radius and margin, a cost beyond.
* :mod:`omnibot.mapping.distance` - the exact Euclidean distance transform (compiled).
* :mod:`omnibot.mapping.cellwalk` - the cells a straight run crosses, walked exactly (compiled).
* :mod:`omnibot.mapping.astar` - the grid planner: A* on the cells (compiled), any-angle shortcuts.
* :mod:`omnibot.mapping.sampling` - OMPL's sampling planners (RRT*, PRM*, BIT*) on a cost map.
* :mod:`omnibot.mapping.ends` - a path's ends: ``check_start``, ``check_goal`` and their errors.

The user's guide is docs/mapping.md. Other packages take the names below from this face::

    from omnibot.mapping import Localiser, OccupancyGrid, load_map, plan_path

Each loads on first use, with only the module that defines it: a grid or a map file loads no numba,
only the SLAM session loads gtsam.
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.mapping.costmap import MARGIN, CostMap, inflate
    from omnibot.mapping.ends import check_goal, check_start
    from omnibot.mapping.feed import ScanFeed, Track, interpolate, undistorted
    from omnibot.mapping.grid import OCCUPIED, OccupancyGrid
    from omnibot.mapping.localise import Localiser
    from omnibot.mapping.mapfile import load_map, save_map
    from omnibot.mapping.planner import PlannedPath, Planner, plan_path
    from omnibot.mapping.report import MappingResult, path_length, score_lines, write_outputs, write_report
    from omnibot.mapping.se2 import compose, inverse, transform
    from omnibot.mapping.session import LocalisingSink, MappingSink
    from omnibot.mapping.snapshot import MapSnapshot, RangeNoise

_EXPORTS = {
    "costmap": ("MARGIN", "CostMap", "inflate"),
    "ends": ("check_goal", "check_start"),
    "grid": ("OCCUPIED", "OccupancyGrid"),
    "localise": ("Localiser",),
    "mapfile": ("load_map", "save_map"),
    "planner": ("PlannedPath", "Planner", "plan_path"),
    "se2": ("compose", "inverse", "transform"),
    "feed": ("ScanFeed", "Track", "interpolate", "undistorted"),
    "report": ("MappingResult", "path_length", "score_lines", "write_outputs", "write_report"),
    "session": ("LocalisingSink", "MappingSink"),
    "snapshot": ("MapSnapshot", "RangeNoise"),
}

__all__ = [
    "MARGIN",
    "OCCUPIED",
    "CostMap",
    "Localiser",
    "LocalisingSink",
    "MapSnapshot",
    "MappingResult",
    "MappingSink",
    "OccupancyGrid",
    "PlannedPath",
    "Planner",
    "RangeNoise",
    "ScanFeed",
    "Track",
    "check_goal",
    "check_start",
    "compose",
    "costmap",
    "ends",
    "feed",
    "grid",
    "inflate",
    "interpolate",
    "inverse",
    "load_map",
    "localise",
    "mapfile",
    "path_length",
    "plan_path",
    "planner",
    "report",
    "save_map",
    "score_lines",
    "se2",
    "session",
    "snapshot",
    "transform",
    "undistorted",
    "write_outputs",
    "write_report",
]

# a name loads its own module only: OccupancyGrid needs no gtsam, load_map no numba
if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
