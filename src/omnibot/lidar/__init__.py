"""The range scanner: the RPLIDAR's serial protocol (codec), an emulated RPLIDAR fed by the simulator,
and the host side that reads either one into :class:`~omnibot.scan.Scan` (see docs/lidar.md)."""

__all__ = ["reader", "rplidar_device"]
