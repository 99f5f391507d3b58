"""A SLAM's results on ROS 2 (``omnibot map --ros2``): ``map`` and the ``map -> odom`` transform.

:class:`MapPublisher` is a runtime sink beside the bridge's :class:`~omnibot.ros2.bridge.Ros2Sink`
(whose node, stamps and frame prefix it uses), reading a
:class:`~omnibot.mapping.session.MappingSink`:

* ``map`` (nav_msgs/OccupancyGrid, reliable, transient local, depth 1: a node that joins late gets
  the latest map, as from slam_toolbox or map_server) whenever the SLAM took scans since the last one,
  at most every :data:`MAP_PERIOD` s of the cycle clock. The map is made in a thread of its own from
  a snapshot taken in the runtime's (:meth:`MappingSink.snapshot
  <omnibot.mapping.session.MappingSink.snapshot>`): mapping every scan again takes longer than a
  cycle;
* ``/tf`` ``map -> odom`` (the SLAM's correction of the odometry) every :data:`TF_PERIOD` s once the
  SLAM has taken a scan, stamped with the cycle's link time, as odom -> base_link is.

Frames are ``map`` and ``odom`` with the robot's tf frame prefix (``r1/map``), as every other frame.
"""

from __future__ import annotations

import logging
import threading
from typing import Any

from omnibot.logs import MAP, TF, map_to_odom, occupancy_grid
from omnibot.ros2.dds import LATCHED
from omnibot.runtime import Cycle

log = logging.getLogger("omnibot.ros2")

MAP_PERIOD = 2.0
"""s: the map is published at most this often (slam_toolbox's map_update_interval is 5 s)."""
TF_PERIOD = 0.05
"""s between two ``map -> odom`` transforms (20 Hz, slam_toolbox's transform_publish_period)."""
MAP_TYPE = "nav_msgs/msg/OccupancyGrid"


class MapPublisher:
    """Publishes ``mapping``'s map and ``map -> odom`` through ``bridge`` (a Ros2Sink already on the
    runtime); ``resolution`` and ``noise`` as the map the command writes. :meth:`close` when the run
    ends (it waits for a map being made)."""

    def __init__(self, bridge: Any, mapping: Any, *, resolution: float = 0.05, noise: Any = None) -> None:
        self.bridge = bridge
        self.mapping = mapping
        self.resolution = resolution
        self.noise = noise
        bridge.add_topic(MAP, MAP_TYPE, LATCHED)
        self.maps = 0
        """Maps published."""
        self._last_map = -float("inf")
        self._last_tf = -float("inf")
        self._mapped = 0  # scans the SLAM had taken when the last map was snapshot
        self._worker: threading.Thread | None = None

    def __call__(self, cycle: Cycle) -> None:
        """``map -> odom`` every TF_PERIOD s; a new map when due (see the module docstring)."""
        taken = len(self.mapping.estimate)
        if not taken:
            return
        if cycle.now - self._last_tf >= TF_PERIOD:
            self._last_tf = cycle.now
            ns = self.bridge.recorder.ns(cycle.t)
            self.bridge.write(TF, map_to_odom(self.mapping.slam.map_to_odom, ns))
        busy = self._worker is not None and self._worker.is_alive()
        if taken != self._mapped and cycle.now - self._last_map >= MAP_PERIOD and not busy:
            self._last_map = cycle.now
            self._mapped = taken
            snapshot = self.mapping.snapshot()
            ns = self.bridge.recorder.ns(cycle.t)
            self._worker = threading.Thread(
                target=self._publish, args=(snapshot, ns), name="omnibot-ros2-map", daemon=True
            )
            self._worker.start()

    def _publish(self, snapshot: Any, ns: int) -> None:
        try:
            grid = snapshot(self.resolution, self.noise)
        except ValueError:  # no scan placed by the SLAM yet (it waits for its first): try again
            self._mapped = 0
            return
        try:
            self.bridge.write(MAP, occupancy_grid(grid, ns))
            self.maps += 1
        except Exception:  # the next map is tried at the next period; the run goes on
            log.exception("publishing the map failed")

    def close(self) -> None:
        """Wait for the map being made, if any."""
        if self._worker is not None:
            self._worker.join()
            self._worker = None
