"""Motion control on the host: PID, paths (files, teach, geometry, speed profile) and path followers.

Depends on the robot description and plain data only (no client, no simulator): the navigation
glue (:mod:`omnibot.navigation`) feeds followers estimates and sends their commands.
"""

__all__ = ["followers", "paths", "reach"]
