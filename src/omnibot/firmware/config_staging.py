"""Host side (CPython): the board's file set, ``robot_config.py``'s text and a staged board directory.

:data:`BOARD_MODULES` lists every firmware module a board runs (``config*.py``, ``avr*.py`` and
``unixhal.py`` are the host's); :func:`stage_board` lays them out with ``main.py`` and the robot's
``robot_config.py`` as ``mpremote`` copies them to a board (``python -m omnibot.firmware.config``).
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path
from typing import Any

from omnibot.errors import ConfigError

PACKAGE_DIR = Path(__file__).resolve().parent
SRC_DIR = PACKAGE_DIR.parent.parent
BOARD_MODULES = (
    "battery",
    "binlink",
    "calibration",
    "controller",
    "controller_commands",
    "controller_input",
    "controller_replies",
    "controller_state",
    "hal",
    "landing",
    "limits",
    "mixins",
    "motion",
    "motion_brake",
    "motion_commands",
    "motion_drive",
    "motion_landing",
    "motion_state",
    "mpu6050",
    "parser",
    "power",
    "progress",
    "queue",
    "safety",
    "sonar",
    "speedctl",
    "telemetry",
    "watchdog",
)
PROTOCOL_MODULES = ("codes", "crc", "frame", "arq", "linecheck")


def _non_finite(value: Any, where: str) -> str | None:
    """Where in ``value`` (nested lists and dicts) a float is not finite, or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return f"{where} = {value!r}"
    if isinstance(value, list | tuple):
        items: Any = enumerate(value)
    elif isinstance(value, dict):
        items = value.items()
    else:
        return None
    for key, item in items:
        found = _non_finite(item, f"{where}[{key!r}]")
        if found:
            return found
    return None


def config_module_source(config: dict[str, Any]) -> str:
    """The text of ``robot_config.py``: ``CONFIG = {...}`` with plain literals, one key a line.
    A number that is not finite is refused (ConfigError naming it): ``inf`` and ``nan`` are not
    literals, and the board would stop at a NameError."""
    for key, value in config.items():
        found = _non_finite(value, str(key))
        if found:
            raise ConfigError(f"the firmware config cannot hold {found}: every number must be finite")
    lines = [f'"""Firmware config of robot {config["name"]!r}, written by omnibot.firmware.config."""', ""]
    lines.append("CONFIG = {")
    for key, value in config.items():
        lines.append(f"    {key!r}: {value!r},")
    lines.append("}")
    return "\n".join(lines) + "\n"


def write_config_module(config: dict[str, Any], path: str | Path) -> Path:
    """Write ``robot_config.py``; returns its path."""
    path = Path(path)
    path.write_text(config_module_source(config), encoding="utf-8")
    return path


def board_files() -> list[tuple[Path, str]]:
    """(source file, path on the board) of every module the board needs, main.py at the root."""
    files = [
        (SRC_DIR / "omnibot" / "__init__.py", "omnibot/__init__.py"),
        (SRC_DIR / "omnibot" / "protocol" / "__init__.py", "omnibot/protocol/__init__.py"),
        (PACKAGE_DIR / "__init__.py", "omnibot/firmware/__init__.py"),
    ]
    files += [
        (SRC_DIR / "omnibot" / "protocol" / f"{m}.py", f"omnibot/protocol/{m}.py") for m in PROTOCOL_MODULES
    ]
    files += [(PACKAGE_DIR / f"{m}.py", f"omnibot/firmware/{m}.py") for m in BOARD_MODULES]
    files.append((PACKAGE_DIR / "main.py", "main.py"))
    return files


def stage_board(dest: str | Path, config: dict[str, Any]) -> list[Path]:
    """Copy the board's files and ``robot_config.py`` under ``dest``, laid out as on the board."""
    dest = Path(dest)
    out = []
    for src, rel in board_files():
        target = dest / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, target)
        out.append(target)
    out.append(write_config_module(config, dest / "robot_config.py"))
    return out
