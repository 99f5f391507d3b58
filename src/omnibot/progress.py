"""What a long command shows on a terminal: a progress bar and one-line notices, both on stderr.

Both appear only when stderr is a terminal, so piped or logged output stays the command's own result
(tqdm's ``disable=None``). The bars never start tqdm's monitor thread.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, Protocol


class Progress(Protocol):
    """What a long run reports its progress to (a tqdm bar fits)."""

    def update(self, n: float | None = 1) -> bool | None:
        """Advance the bar by ``n`` steps."""

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """Show ``s`` after the bar."""


def on_terminal() -> bool:
    """Whether stderr is a terminal (a person is watching)."""
    isatty = getattr(sys.stderr, "isatty", None)
    return bool(isatty and isatty())


def notice(message: str) -> None:
    """``omnibot: message`` on stderr, on a terminal only."""
    if on_terminal():
        print(f"omnibot: {message}", file=sys.stderr, flush=True)


@contextmanager
def progress_bar(desc: str, total: float | None, unit: str = "it", **options: Any) -> Iterator[Any]:
    """A tqdm bar on stderr (a no-op bar when stderr is not a terminal); ``total`` None or 0: unknown."""
    from tqdm import tqdm

    class Bar(tqdm):  # type: ignore[type-arg]
        monitor_interval = 0  # no monitor thread left behind

    with Bar(
        total=total or None, desc=desc, unit=unit, disable=None, file=sys.stderr, leave=True, **options
    ) as bar:
        yield bar
