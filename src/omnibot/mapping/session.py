"""A mapping run on the runtime: scans and the runtime's odometry into the SLAM, trajectories kept.

:class:`MappingSink` is a runtime sink (:mod:`omnibot.runtime.sinks`). Every cycle it keeps the
runtime's estimate (the fused wheel and gyro odometry) as the odometry trajectory, takes the scans
completed since the last cycle from a :class:`~omnibot.lidar.reader.ScanSource` (None: the
runtime's scanner, the cycle's ``scans``, which the log, ROS 2 and the page read too), gives each to the
:class:`~omnibot.mapping.slam.Slam` with the odometry pose at the scan's first ray and the
odometry's twist from its first ray to its last (interpolated between the cycles around them; a
scan newer than the last estimate waits for the next cycle), and
keeps the SLAM's pose as the estimate trajectory. Scans and estimates must share a clock: simulated
time on ``sim://`` (the link's clock and the simulator's scans), the host's monotonic clock on a
real port (the client's clock and :class:`~omnibot.lidar.reader.RplidarScanner`'s stamps).

On a link in lockstep the SLAM runs in the runtime's thread (simulated time waits for it, and the
run is deterministic); on a real link ``threaded=True`` hands the scans to a worker thread, so a
slow loop closure never delays a VEL.

:func:`write_outputs` writes what a mapping run leaves in its directory: ``map.yaml`` + ``map.pgm``
(map_server's format), ``estimate.tum`` and ``odometry.tum``, and with the simulator's truth
``truth.tum``, ``report.json`` (APE/RPE of both trajectories, the map's precision and recall against
the world's own geometry) and ``map.png``.
"""

from __future__ import annotations

import bisect
import contextlib
import itertools
import json
import math
import queue
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from omnibot.mapping.deskew import scan_points
from omnibot.mapping.se2 import between, compose, transform, wrap
from omnibot.mapping.slam import Slam
from omnibot.motion import Pose2D, Twist
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]

if TYPE_CHECKING:
    from omnibot.lidar import ScanSource
    from omnibot.mapping.grid import OccupancyGrid
    from omnibot.mapping.localise import Localiser
    from omnibot.runtime import Cycle
    from omnibot.sim import World

HISTORY = 4096
"""Odometry samples kept for interpolation (40 s at 100 Hz; scans are never that late)."""
PENDING_MAX = 64
"""Scans kept while the odometry has not caught up with them (the oldest are dropped)."""
P_HIT = 0.6
"""What one hit within the hit range says of its cell (two hits make it occupied at map_server's 0.65)."""
REFLECT = 0.1
"""A cell hit by at least this share of the scans that reached it (and by two) is occupied, whatever
the rays grazing past it say (the mapper's ``reflect``): a thin wall on a cell boundary, which a
doorway's rays run along, stays marked (house, omni4, a 59 m route: recall 65 -> 77 %, precision
98.8 -> 99.1 %; 0.03-0.3 measured, BENCHMARKS.md)."""


@dataclass
class Track:
    """A trajectory being recorded: times (s) and poses."""

    stamps: list[float] = field(default_factory=list)
    poses: list[Pose2D] = field(default_factory=list)

    def add(self, stamp: float, pose: Pose2D) -> None:
        """Append a pose (times never decrease)."""
        self.stamps.append(stamp)
        self.poses.append(pose)

    def __len__(self) -> int:
        return len(self.stamps)


def interpolate(stamps: list[float], poses: list[Pose2D], t: float) -> Pose2D | None:
    """The pose at ``t`` between the samples around it (linear, heading the short way round); None
    when ``t`` is outside the samples."""
    if not stamps or t < stamps[0] or t > stamps[-1]:
        return None
    i = bisect.bisect_left(stamps, t)
    if stamps[i] == t or i == 0:
        return poses[i]
    t0, t1 = stamps[i - 1], stamps[i]
    a, b = poses[i - 1], poses[i]
    k = (t - t0) / (t1 - t0)
    return Pose2D(a.x + k * (b.x - a.x), a.y + k * (b.y - a.y), wrap(a.theta + k * wrap(b.theta - a.theta)))


class ScanFeed:
    """The runtime's side of a scan consumer (see the module docstring): keeps the odometry of every
    cycle, matches each scan to the odometry of its time and hands it to :meth:`_update` (in the
    runtime's thread, or a worker's with ``threaded``); ``close()`` when the run ends."""

    def __init__(self, scans: ScanSource | None, *, threaded: bool = False) -> None:
        self.scans = scans
        self.odometry = Track()
        self.received = 0
        """Scans taken from the source."""
        self.dropped = 0
        """Scans dropped: older than the odometry kept, or while too many waited."""
        self.failure: BaseException | None = None
        """Why the worker stopped (a threaded feed), else None."""
        self._history_t: list[float] = []
        self._history_p: list[Pose2D] = []
        self._pending: list[Scan] = []
        self._lock = threading.Lock()
        self._queue: queue.Queue[tuple[Scan, Pose2D] | None] | None = None
        self._worker: threading.Thread | None = None
        if threaded:
            self._queue = queue.Queue()
            self._worker = threading.Thread(
                target=self._work, name=f"omnibot-{type(self).__name__}", daemon=True
            )
            self._worker.start()

    def __call__(self, cycle: Cycle) -> None:
        """Keep the cycle's odometry; hand every scan it covers on."""
        est = cycle.estimate
        if est is not None and (not self._history_t or cycle.t > self._history_t[-1]):
            pose = Pose2D(est.x, est.y, est.theta)
            self._history_t.append(cycle.t)
            self._history_p.append(pose)
            self.odometry.add(cycle.t, pose)
            if len(self._history_t) > HISTORY:
                del self._history_t[: len(self._history_t) - HISTORY]
                del self._history_p[: len(self._history_p) - HISTORY]
        fresh = self.scans.poll() if self.scans is not None else list(cycle.scans)
        self.received += len(fresh)
        self._pending.extend(fresh)
        waiting: list[Scan] = []
        for scan in self._pending:
            span = scan.time_increment * max(len(scan) - 1, 0)
            odom = interpolate(self._history_t, self._history_p, scan.stamp)
            end = interpolate(self._history_t, self._history_p, scan.stamp + span) if span > 0 else odom
            if odom is not None and end is not None:
                self._keep(scan, odom, end, span)
                self._take(scan, odom)
            elif self._history_t and scan.stamp < self._history_t[0]:
                self.dropped += 1  # before the odometry began (or long gone)
            else:
                waiting.append(scan)
        if len(waiting) > PENDING_MAX:
            self.dropped += len(waiting) - PENDING_MAX
            waiting = waiting[-PENDING_MAX:]
        self._pending = waiting

    @property
    def last_odometry(self) -> Pose2D | None:
        """The latest cycle's odometry pose (None before the first estimate)."""
        return self._history_p[-1] if self._history_p else None

    def map_to_odom_now(self) -> Pose2D | None:
        """The odometry frame's pose in the map now (None while there is no map to place it in)."""
        raise NotImplementedError

    def pose_now(self) -> Pose2D | None:
        """The robot's map-frame pose now: :meth:`map_to_odom_now` composed with the latest
        odometry (None before the first odometry, or while there is no map)."""
        odom = self.last_odometry
        correction = None if odom is None else self.map_to_odom_now()
        return None if odom is None or correction is None else compose(correction, odom)

    def _keep(self, scan: Scan, start: Pose2D, end: Pose2D, span: float) -> None:
        """A scan with the odometry at its first and last rays (``span`` s apart), in the runtime's
        thread before :meth:`_update` (nothing here)."""

    def _update(self, scan: Scan, odom: Pose2D) -> None:
        raise NotImplementedError

    def _take(self, scan: Scan, odom: Pose2D) -> None:
        if self._queue is not None:
            self._queue.put((scan, odom))
        else:
            self._update(scan, odom)

    def _work(self) -> None:
        assert self._queue is not None
        while (item := self._queue.get()) is not None:
            if self.failure is not None:
                continue  # drain: it failed once, it is not asked again
            try:
                self._update(*item)
            except Exception as exc:  # kept, and told by the command: never raised in the loop
                self.failure = exc

    def close(self) -> None:
        """Finish the work (a threaded feed waits for its queue) and close the scan source."""
        if self._worker is not None and self._queue is not None:
            self._queue.put(None)
            self._worker.join()
            self._worker = None
        if self.scans is not None:
            with contextlib.suppress(Exception):
                self.scans.close()


def span_twist(start: Pose2D, end: Pose2D, span: float) -> Twist:
    """The body twist that goes from ``start`` to ``end`` in ``span`` s (zero for no span)."""
    if span <= 0:
        return Twist()
    d = between(start, end)
    return Twist(d.x / span, d.y / span, d.theta / span)


def undistorted(scan: Scan, start: Pose2D, end: Pose2D, span: float) -> FloatArray:
    """The scan's returns in the base frame at its first ray, moved by the odometry's motion from
    ``start`` to ``end`` over the revolution's ``span`` s (a spinning scanner's distortion undone)."""
    return scan_points(scan, span_twist(start, end, span))


class MappingSink(ScanFeed):
    """Feeds the SLAM from a runtime (see the module docstring); ``close()`` when the run ends."""

    def __init__(self, scans: ScanSource | None, slam: Slam | None = None, *, threaded: bool = False) -> None:
        self.slam = slam if slam is not None else Slam()
        self.estimate = Track()
        self._clouds: list[tuple[float, NDArray[np.float32], tuple[float, float]]] = []
        self._latest: FloatArray | None = None
        self._twists: dict[float, Twist] = {}  # each scan's own, by stamp, until its update
        super().__init__(scans, threaded=threaded)

    def map_to_odom_now(self) -> Pose2D | None:
        """The SLAM's ``map -> odom`` (None until its first keyframe: there is no map before)."""
        if not self.slam.keyframes():
            return None
        with self._lock:
            return self.slam.map_to_odom

    def points_now(self) -> FloatArray | None:
        """The latest scan's returns in the map frame (None before the first): the SLAM's current
        ``map -> odom`` applied to them (goto's obstacle watch while exploring)."""
        with self._lock:
            latest, correction = self._latest, self.slam.map_to_odom
        return None if latest is None else transform(correction, latest)

    def _keep(self, scan: Scan, start: Pose2D, end: Pose2D, span: float) -> None:
        """Keep the scan's returns (distortion undone) for the map, and its twist for the SLAM."""
        twist = span_twist(start, end, span)
        points = scan_points(scan, twist)
        self._clouds.append((scan.stamp, points.astype(np.float32), (scan.mount.x, scan.mount.y)))
        with self._lock:
            self._latest = transform(start, points)  # the odometry frame
            self._twists[scan.stamp] = twist

    def _update(self, scan: Scan, odom: Pose2D) -> None:
        with self._lock:
            twist = self._twists.pop(scan.stamp, None)
        pose = self.slam.update(odom, scan, scan.stamp, twist)
        with self._lock:
            self.estimate.add(scan.stamp, pose)

    # ------------------------------------------------------------------ results

    @property
    def pose(self) -> Pose2D | None:
        """The SLAM's latest map-frame pose of the robot (None before the first scan)."""
        with self._lock:
            return self.estimate.poses[-1] if self.estimate.poses else None

    def trajectory(self) -> Track:
        """The estimate trajectory with every correction of the pose graph so far (re-read from the
        SLAM: the poses recorded as they came are the ones known then)."""
        track = Track()
        for stamp, pose in self.slam.trajectory():
            track.add(stamp, pose)
        return track

    def grid(self, resolution: float = 0.05, noise: RangeNoise | None = None) -> OccupancyGrid:
        """The map: every scan's returns (motion distortion undone) at the SLAM's corrected pose of
        its first ray. A return marks its cell only within the scanner's ``noise.hit_range`` (where its
        range noise is small against a cell); farther ones clear the cells before them, short of their
        3-sigma uncertainty, and mark nothing (a far wall's noise would thicken it into the room and
        behind it). Rays without a return clear nothing: a dropout is no evidence of free space."""
        return self.snapshot()(resolution, noise)

    def snapshot(self) -> MapSnapshot:
        """What :meth:`grid` maps, as it is now (the scans so far at the SLAM's poses now): cheap to
        take in the runtime's thread, mapped later in another (the ROS 2 ``map`` publisher's)."""
        return MapSnapshot(list(self._clouds), dict(self.slam.trajectory()))


@dataclass(frozen=True)
class MapSnapshot:
    """The scans' returns (stamp, points in the base frame, mount x/y) and the SLAM's pose of each
    stamp at one instant; called, it makes the map (see :meth:`MappingSink.grid`)."""

    clouds: list[tuple[float, NDArray[np.float32], tuple[float, float]]]
    poses: dict[float, Pose2D]

    def __call__(self, resolution: float = 0.05, noise: RangeNoise | None = None) -> OccupancyGrid:
        """The map of the snapshot's scans (``resolution`` m cells; ``noise`` as in :meth:`MappingSink.grid`)."""
        from omnibot.mapping.mapper import OccupancyMapper

        noise = noise or RangeNoise()
        mapper = OccupancyMapper(resolution, max_clear=0.0, p_occ=P_HIT, reflect=REFLECT)
        for stamp, points, mount in self.clouds:
            pose = self.poses.get(stamp)
            if pose is None:
                continue
            rays = points - np.asarray(mount, dtype=np.float32)
            r = np.hypot(rays[:, 0], rays[:, 1])
            near = r <= noise.hit_range
            far_r = r[~near]
            shorter = np.maximum(far_r - 3.0 * noise.sigma(far_r), 0.0) / np.maximum(far_r, 1e-9)
            cleared = np.asarray(mount) + rays[~near] * shorter[:, None]
            origin = transform(pose, [mount])[0]
            short = np.maximum(resolution, 3.0 * noise.sigma(r[near]))
            mapper.add_points(
                (float(origin[0]), float(origin[1])),
                transform(pose, points[near]),
                transform(pose, cleared),
                short=short,
            )
        return mapper.to_grid()

    def returns(self, grid: OccupancyGrid) -> NDArray[np.int32]:
        """How many of the snapshot's returns (at every range, those beyond the hit range too) fall
        in each cell of ``grid`` (a map of the same snapshot): where the scanner saw something, even
        where the map does not mark it (a wall seen only from afar, or edge-on)."""
        placed = [transform(self.poses[t], points) for t, points, _ in self.clouds if t in self.poses]
        rows, cols = grid.shape
        if not placed:
            return np.zeros((rows, cols), dtype=np.int32)
        cells = grid.world_to_cell(np.concatenate(placed))
        cells = cells[grid.inside(cells)]
        flat = np.bincount(cells[:, 0] * cols + cells[:, 1], minlength=rows * cols)
        return flat.reshape(rows, cols).astype(np.int32)


class LocalisingSink(ScanFeed):
    """Localises the robot in a saved map from a runtime: each scan and the odometry of its time go
    to a :class:`~omnibot.mapping.localise.Localiser`; :meth:`pose_now` is the map-frame pose now (the
    localiser's ``map -> odom`` composed with the latest odometry) and :meth:`points` the latest
    scan's returns in the map frame (for goto's obstacle watch)."""

    def __init__(self, scans: ScanSource | None, localiser: Localiser, *, threaded: bool = False) -> None:
        self.localiser = localiser
        self.updates = 0
        self._map_to_odom = Pose2D(0.0, 0.0, 0.0)
        self._points: FloatArray | None = None
        self._odom_points: dict[float, FloatArray] = {}  # by stamp, until the scan's update
        super().__init__(scans, threaded=threaded)

    def _keep(self, scan: Scan, start: Pose2D, end: Pose2D, span: float) -> None:
        points = transform(start, undistorted(scan, start, end, span))  # the odometry frame
        with self._lock:
            self._odom_points[scan.stamp] = points

    def _update(self, scan: Scan, odom: Pose2D) -> None:
        self.localiser.update(odom, scan)
        with self._lock:
            self._map_to_odom = self.localiser.map_to_odom
            self.updates += 1
            points = self._odom_points.pop(scan.stamp, None)
            if points is not None:
                self._points = transform(self._map_to_odom, points)

    def map_to_odom_now(self) -> Pose2D:
        """The odometry frame's pose in the map, as the last scan placed it (the start's guess before)."""
        with self._lock:
            return self._map_to_odom

    def points(self) -> FloatArray | None:
        """The latest scan's returns in the map frame (None before the first)."""
        with self._lock:
            return self._points


@dataclass(frozen=True)
class RangeNoise:
    """A scanner's range noise, 1 sigma = ``std + fraction * range`` (the robot description's
    ``scanner.noise_std`` and ``noise_fraction``), and the range within which a return marks its cell:
    where sigma is at most ``hit_sigma`` (2 cm: 2.5 sigma inside a 5 cm tolerance), or ``range`` if given."""

    std: float = 0.0
    fraction: float = 0.01
    hit_sigma: float = 0.02
    range: float | None = None

    @classmethod
    def of(cls, robot: Any, range: float | None = None) -> RangeNoise:
        """The noise of ``robot``'s scanner section (the defaults without one)."""
        spec = getattr(robot, "scanner", None)
        if spec is None:
            return cls(range=range)
        return cls(float(spec.noise_std), float(spec.noise_fraction), range=range)

    def sigma(self, r: NDArray[np.floating[Any]]) -> NDArray[np.float64]:
        """Range noise at ranges ``r``, 1 sigma, m."""
        return np.asarray(self.std + self.fraction * np.asarray(r, dtype=np.float64), dtype=np.float64)

    @property
    def hit_range(self) -> float:
        """Returns up to this range mark their cells, m."""
        if self.range is not None:
            return self.range
        if self.fraction <= 0:
            return math.inf if self.std <= self.hit_sigma else 0.0
        return max(0.0, (self.hit_sigma - self.std) / self.fraction)


# ---------------------------------------------------------------------------------------------------
# outputs


@dataclass(frozen=True)
class MappingResult:
    """What :func:`write_outputs` wrote and measured."""

    files: list[Path]
    report: dict[str, Any]
    grid: OccupancyGrid | None = None
    """The map written."""


def write_outputs(
    out: Path,
    sink: MappingSink,
    *,
    truth: Track | None = None,
    world: World | None = None,
    resolution: float = 0.05,
    noise: RangeNoise | None = None,
    plot: bool = True,
) -> MappingResult:
    """Write the map, the trajectories and (with ``truth`` and ``world``) the scored report to ``out``."""
    if not sink.slam.keyframes():
        raise ValueError("no scan reached the SLAM: nothing to map")
    noise = noise or RangeNoise()
    grid = sink.grid(resolution, noise)
    estimate = sink.trajectory()
    report: dict[str, Any] = {
        "scans": sink.received,
        "scans_dropped": sink.dropped,
        "keyframes": len(sink.slam.keyframes()),
        "loop_closures": sink.slam.closures,
        "keyframes_degenerate": sum(1 for m in sink.slam.matches if m.unconstrained),
        "keyframes_anchored": sink.slam.anchored,
        "distance_m": path_length(estimate.poses),
        "map": {"hit_range_m": noise.hit_range},
    }
    tracks = {"estimate": estimate, "odometry": sink.odometry}
    if truth is not None:
        tracks["truth"] = truth
    return write_report(out, grid, tracks, report, world=world, plot=plot)


def write_report(
    out: Path,
    grid: OccupancyGrid,
    tracks: dict[str, Track],
    report: dict[str, Any],
    *,
    world: World | None = None,
    plot: bool = True,
) -> MappingResult:
    """What a scored run leaves in ``out``: ``grid`` as map.yaml + map.pgm, each of ``tracks``
    (``estimate``, ``odometry``, ``truth``) as NAME.tum, ``report`` (what the run adds) completed with
    the map's size, the trajectories' APE/RPE against ``truth`` and the map's precision and recall
    against ``world`` in report.json, and map.png."""
    from omnibot.mapping.mapfile import save_map
    from omnibot.mapping.trajectory import Trajectory, write_tum

    save_map(grid, out / "map.yaml")
    files = [out / "map.yaml", out / "map.pgm"]
    trajectories: dict[str, Trajectory] = {}
    for name, track in tracks.items():
        if len(track) == 0:
            continue
        trajectories[name] = Trajectory.from_poses(track.stamps, track.poses)
        path = out / f"{name}.tum"
        write_tum(path, trajectories[name])
        files.append(path)
    report["map"] = {
        "resolution": grid.resolution,
        **report.get("map", {}),
        "origin": [grid.origin.x, grid.origin.y, grid.origin.theta],
        "size_cells": list(grid.shape),
    }
    if "truth" in trajectories:
        report["trajectory"] = _scores(trajectories)
    if world is not None:
        from omnibot.mapping.score import score_map

        score = score_map(grid, world)
        report["map"]["precision"] = _number(score.precision)
        report["map"]["recall"] = _number(score.recall)
        report["map"]["tolerance_m"] = score.tolerance
    path = out / "report.json"
    path.write_text(json.dumps(report, indent=2) + "\n")
    files.append(path)
    if plot:
        files.append(_plot(out / "map.png", grid, tracks))
    return MappingResult(files, report, grid)


def score_lines(report: dict[str, Any]) -> list[str]:
    """A report's scores in words, one line each: the trajectories' APE, the map's precision and
    recall (what the report has of them)."""
    lines = []
    for name in ("estimate", "odometry"):
        scores = report.get("trajectory", {}).get(name)
        if scores is not None:
            lines.append(
                f"{name}: APE RMSE {_cm(scores['ape_rmse_m'])}, max {_cm(scores['ape_max_m'])} "
                "(from the simulator's truth)"
            )
    m = report["map"]
    if "precision" in m:
        lines.append(
            f"map: precision {_pct(m['precision'])}, recall {_pct(m['recall'])} within "
            f"{m['tolerance_m'] * 100:.0f} cm of the world's walls and furniture"
        )
    return lines


def _cm(v: float | None) -> str:
    return "n/a" if v is None else f"{v * 100:.1f} cm"


def _pct(v: float | None) -> str:
    return "n/a" if v is None else f"{v * 100:.1f} %"


def path_length(poses: list[Pose2D]) -> float:
    """m along ``poses``."""
    return sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in itertools.pairwise(poses))


def _scores(trajectories: dict[str, Any]) -> dict[str, Any]:
    from omnibot.mapping.trajectory import score_trajectory

    truth = trajectories["truth"]
    scores: dict[str, Any] = {}
    for name in ("estimate", "odometry"):
        if name in trajectories:
            errors = score_trajectory(trajectories[name], truth)
            scores[name] = {
                "ape_rmse_m": _number(errors.ape_rmse),
                "ape_max_m": _number(errors.ape_max),
                "rpe_rmse_m": _number(errors.rpe_rmse),
                "rpe_delta_m": errors.rpe_delta,
                "poses": errors.pairs,
            }
    return scores


def _number(v: float) -> float | None:
    """A float for JSON: None where it is not a number (JSON has no NaN)."""
    return v if math.isfinite(v) else None


def _plot(path: Path, grid: OccupancyGrid, tracks: dict[str, Track]) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 8 * grid.height / max(grid.width, 1e-9)))
    shade = np.where(grid.data < 0, 0.8, 1.0 - grid.data / 100.0)
    x0, y0 = grid.origin.x, grid.origin.y
    ax.imshow(
        shade, cmap="gray", vmin=0, vmax=1, origin="lower", extent=(x0, x0 + grid.width, y0, y0 + grid.height)
    )
    for name, color in (("truth", "tab:green"), ("odometry", "tab:red"), ("estimate", "tab:blue")):
        track = tracks.get(name)
        if track is not None and len(track):
            ax.plot([p.x for p in track.poses], [p.y for p in track.poses], color=color, lw=1, label=name)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="upper right")
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path
