"""The range scanner: the RPLIDAR's serial protocol (codec), an emulated RPLIDAR fed by the simulator,
and the host side that reads either one into :class:`~omnibot.scan.Scan` (see docs/lidar.md).

Other packages take the scanner's source (``open_scanner``: an RPLIDAR on a device path, the
simulator's on ``sim://``; ``RplidarScanner``, the driver) and the emulated RPLIDAR (``RplidarDevice``
and its models) from this face::

    from omnibot.lidar import ScanSource, open_scanner

Each loads on first use, with only the module that defines it (the emulated device no reader).
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.lidar.reader import RplidarScanner, ScanningSim, ScanSource, SimScanSource, open_scanner
    from omnibot.lidar.rplidar_device import A1, A2, RplidarDevice, RplidarModel, model_named

_EXPORTS = {
    "reader": ("RplidarScanner", "ScanSource", "ScanningSim", "SimScanSource", "open_scanner"),
    "rplidar_device": ("A1", "A2", "RplidarDevice", "RplidarModel", "model_named"),
}

__all__ = [
    "A1",
    "A2",
    "RplidarDevice",
    "RplidarModel",
    "RplidarScanner",
    "ScanSource",
    "ScanningSim",
    "SimScanSource",
    "model_named",
    "open_scanner",
    "reader",
    "rplidar_device",
]

if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
