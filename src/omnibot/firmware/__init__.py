"""The motor-controller firmware of seed 000, in the subset of Python that MicroPython runs.

The same modules run on a microcontroller board (``main.py`` + ``robot_config.py``) and inside the
simulator: they reach hardware only through a HAL (:mod:`omnibot.firmware.hal`). See docs/firmware.md.

Board modules import nothing outside this package but ``omnibot.protocol`` (``codes``, ``crc``,
``frame``, ``arq``: MicroPython-safe); ``config.py`` is host-side (CPython) and is not copied to a
board. Entry points: ``controller.Controller(hal, config)`` and its ``poll()``; ``hal.HAL``;
``config.build_config(robot)``.
"""

__all__ = ["calibration", "config", "controller", "hal", "power"]
