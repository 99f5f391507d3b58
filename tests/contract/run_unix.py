"""Run the firmware as a desktop process on stdin/stdout (MicroPython unix port or CPython).

    micropython tests/contract/run_unix.py ROBOT [--sonar CM]

imports the config module ``ROBOT_config`` (``omnibot.firmware.config.write_config_module`` into a
directory on MICROPYPATH / PYTHONPATH) and polls the controller until stdin closes; see
``omnibot.firmware.unixhal``.
"""

import sys

_here = __file__.rsplit("/", 1)[0] if "/" in __file__ else "."
sys.path.append(_here + "/../../src")

from omnibot.firmware.unixhal import main  # noqa: E402

sys.exit(main(sys.argv[1:]))
