"""Files a command will write, checked before any robot moves (:func:`check_writable`): a library
that writes a file its caller named (a log, a plot, a report) and the command-line options share it.
"""

from __future__ import annotations

import os
from pathlib import Path

from omnibot.errors import ConfigError


def check_writable(path: str | Path | None, flag: str) -> None:
    """Refuse, before any robot moves, an output file that could not be written: its directory must
    exist (none is made: a mistyped directory is a mistake to report, not to create) and be writable,
    it must not be a directory, and an existing file must be writable. Nothing is created here, so a
    run that fails later leaves no empty file behind."""
    if path is None:
        return
    target = Path(path)
    if target.is_dir():
        raise ConfigError(f"{target} is a directory; give the file to write", key=flag)
    parent = target.parent
    if not parent.is_dir():
        raise ConfigError(f"cannot write {target}: no directory {parent}", key=flag)
    if not os.access(parent, os.W_OK | os.X_OK) or (target.exists() and not os.access(target, os.W_OK)):
        raise ConfigError(f"cannot write {target}: permission denied", key=flag)
