"""The SLAM bench: maps, scan matching, localisation, planning, and scores against the truth.

Modules (each owns one thing; the plain scan type is :mod:`omnibot.scan`):

* :mod:`omnibot.mapping.grid` - :class:`~omnibot.mapping.grid.OccupancyGrid`, the map every other
  module reads (ROS nav_msgs/OccupancyGrid conventions).
"""
