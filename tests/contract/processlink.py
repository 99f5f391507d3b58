"""A Link to a child process's stdin/stdout (the MicroPython firmware backend); wall clock."""

from __future__ import annotations

import os
import select
import subprocess
import tempfile
from collections.abc import Mapping, Sequence

from omnibot.errors import LinkError
from omnibot.transport import Link


class ProcessLink(Link):
    """Runs ``argv`` and talks to it over pipes; ``close()`` ends its input and reaps it."""

    def __init__(self, argv: Sequence[str], *, env: Mapping[str, str] | None = None, url: str = "") -> None:
        super().__init__(url or f"process://{argv[0]}")
        self._stderr = tempfile.TemporaryFile()  # noqa: SIM115 - closed in _close
        self.proc = subprocess.Popen(
            list(argv), stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._stderr, env=env, bufsize=0
        )
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self._in = self.proc.stdin.fileno()
        self._out = self.proc.stdout.fileno()

    def _gone(self, what: str) -> LinkError:
        self._stderr.seek(0)
        err = self._stderr.read().decode(errors="replace").strip()
        return LinkError(f"{self.url}: {what} (exit status {self.proc.poll()}) {err}")

    def _write(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            try:
                n = os.write(self._in, view)
            except OSError as exc:
                raise self._gone(f"write failed: {exc}") from exc
            view = view[n:]

    def _read(self, max_bytes: int, timeout: float | None) -> bytes:
        ready, _, _ = select.select([self._out], [], [], timeout)
        if not ready:
            return b""
        data = os.read(self._out, max_bytes)
        if not data:
            raise self._gone("the process closed its output")
        return data

    def _close(self) -> None:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.close()
        try:
            self.proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.proc.stdout.close()
        self._stderr.close()
