"""Files a command will write, checked before any robot moves (:func:`check_writable`): a library
that writes a file its caller named (a log, a plot, a report) and the command-line options share it.
"""

from __future__ import annotations

import errno
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


def check_directory(path: str | Path, flag: str) -> Path:
    """Refuse, before any robot moves, an output directory that could not be made: a file where it
    or one of its parents should be, or a nearest existing parent that is not writable. Nothing is
    made here (:func:`made_directory` does, when the first file goes into it), so a run refused or
    interrupted before writing leaves no empty directory behind."""
    target = Path(path)
    existing = next(p for p in (target, *target.parents) if p.exists() or p == Path(p.anchor))
    if not existing.is_dir():  # as mkdir says it: the directory itself a file, or one of its parents
        error = errno.EEXIST if existing == target else errno.ENOTDIR
        raise ConfigError(f"cannot make directory {target}: {os.strerror(error)}", key=flag)
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ConfigError(f"cannot make directory {target}: {os.strerror(errno.EACCES)}", key=flag)
    return target


def made_directory(path: Path, flag: str) -> Path:
    """``path`` made (with its parents) for the files about to go into it; one line if it cannot be."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"cannot make directory {path}: {exc.strerror or exc}", key=flag) from None
    return path
