"""The MCAP file a recording writes: chunks, channels and their schemas, rosbag2's metadata, and
what a failed write does (:class:`LogWriter`; :class:`~omnibot.logs.recorder.Recorder` builds on it).

Bounded memory: messages go to the current chunk, which is compressed and written when it reaches
``chunk_size`` bytes or is ``flush_period`` s (wall clock) old; only the chunk indexes (one per chunk)
stay in memory. The file is written unbuffered, so a SIGKILL loses only the open chunk.

A write that fails (a full disk, ``ulimit -f``, a read-only or failing device: any ``OSError``) stops
the file, never the run: the writer says so once (a warning on stderr and to every
:attr:`LogWriter.on_failure` callback: a runtime's notice), keeps what it wrote before (``omnibot log
recover`` rewrites it whole), writes nothing more to it and raises nothing into the client's
listeners or the runtime's loop; :attr:`LogWriter.failure` tells the command its log is incomplete.
"""

from __future__ import annotations

import contextlib
import logging
import sys
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import IO, Any, Protocol, Self, cast

import yaml
from mcap.writer import CompressionType, Writer

from omnibot import __version__
from omnibot.config_errors import load_yaml
from omnibot.errors import ConfigError
from omnibot.logs import schemas
from omnibot.logs.topics import CALIBRATION, MAP, ROBOT_DESCRIPTION
from omnibot.signals import held

log = logging.getLogger("omnibot.logs")

CHUNK_SIZE = 256 * 1024
"""Uncompressed bytes after which a chunk is compressed and written."""
FLUSH_PERIOD = 1.0
"""Wall-clock seconds after which an open chunk is written anyway (what a SIGKILL can lose)."""

_QOS_VOLATILE = (
    "- history: keep_last\n  depth: 10\n  reliability: reliable\n  durability: volatile\n"
    "  deadline: {sec: 0, nsec: 0}\n  lifespan: {sec: 0, nsec: 0}\n  liveliness: automatic\n"
    "  liveliness_lease_duration: {sec: 0, nsec: 0}\n  avoid_ros_namespace_conventions: false\n"
)
_QOS_LATCHED = _QOS_VOLATILE.replace("depth: 10", "depth: 1").replace("volatile", "transient_local")
_LATCHED = {ROBOT_DESCRIPTION, CALIBRATION, MAP}


def offered_qos(topic: str) -> str:
    """The ``offered_qos_profiles`` (rosbag2's YAML) of ``topic``: transient local for the URDF and
    the calibration (sent once), volatile for the rest."""
    return _QOS_LATCHED if topic in _LATCHED else _QOS_VOLATILE


def rosbag2_metadata(
    file_name: str, channels: Mapping[str, str], counts: Mapping[str, int], start_ns: int, end_ns: int
) -> str:
    """rosbag2's ``serialized_metadata`` (its ``metadata.yaml``) of one MCAP file ``file_name`` with
    ``channels`` (topic -> type), ``counts`` messages per topic, from ``start_ns`` to ``end_ns``."""
    duration = max(0, end_ns - start_ns)
    total = sum(counts.get(topic, 0) for topic in channels)
    topics = [
        {
            "topic_metadata": {
                "name": topic,
                "type": typename,
                "serialization_format": "cdr",
                "offered_qos_profiles": load_yaml(offered_qos(topic)),
                "type_description_hash": schemas.type_hash(typename),
            },
            "message_count": counts.get(topic, 0),
        }
        for topic, typename in channels.items()
    ]
    info = {
        "rosbag2_bagfile_information": {
            "version": 9,
            "storage_identifier": "mcap",
            "relative_file_paths": [file_name],
            "duration": {"nanoseconds": duration},
            "starting_time": {"nanoseconds_since_epoch": start_ns},
            "message_count": total,
            "topics_with_message_count": topics,
            "compression_format": "",
            "compression_mode": "",
            "files": [
                {
                    "path": file_name,
                    "starting_time": {"nanoseconds_since_epoch": start_ns},
                    "duration": {"nanoseconds": duration},
                    "message_count": total,
                }
            ],
            "custom_data": {"omnibot_version": __version__},
            "ros_distro": "jazzy",
        }
    }
    return yaml.safe_dump(info, sort_keys=False)


class Mirror(Protocol):
    """Something that gets every message the recorder writes (the Foxglove live server)."""

    def __call__(self, topic: str, typename: str, data: bytes, ns: int) -> None:
        """Take one message: its ``topic``, ``typename``, CDR ``data`` and time ``ns``."""

    def close(self) -> None:
        """Release what the mirror holds (a server, channels)."""


class _Direct:
    """A file the MCAP writer writes straight to the OS (no user-space buffer a SIGKILL would lose;
    the writer already hands over whole chunks)."""

    def __init__(self, raw: IO[bytes]) -> None:
        self._raw = raw
        self._pos = 0

    def write(self, data: bytes | memoryview) -> int:
        view = memoryview(data)
        while view:
            n = self._raw.write(view)
            view = view[n or 0 :]
        self._pos += len(data)
        return len(data)

    def tell(self) -> int:
        return self._pos

    def flush(self) -> None:
        pass


def _start_file(path: Path, chunk_size: int, compression: str) -> tuple[IO[bytes], Writer]:
    """``path`` opened (its folder made) and an MCAP writer started on it, its header written; a
    :class:`ConfigError` for ``--log`` when it cannot be."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        file = open(path, "wb", buffering=0)  # noqa: SIM115 (the recorder closes it in close())
    except OSError as exc:
        raise ConfigError(f"cannot write {path}: {exc.strerror or exc}", key="--log") from None
    kinds = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}
    writer = Writer(cast("IO[Any]", _Direct(file)), chunk_size=chunk_size, compression=kinds[compression])
    try:
        writer.start(profile="ros2", library=f"omnibot {__version__}")
    except OSError as exc:  # no room for the header: the command cannot start
        file.close()
        raise ConfigError(f"cannot write {path}: {exc.strerror or exc}", key="--log") from None
    return file, writer


class LogWriter:
    """Writes one MCAP file (``path``; None: no file) and hands every message to ``mirrors``
    (``mirror(topic, typename, cdr_bytes, ns)``: the Foxglove live server), each time placed on the
    wall clock (:meth:`ns`)."""

    def __init__(
        self,
        path: str | Path | None,
        *,
        chunk_size: int = CHUNK_SIZE,
        flush_period: float = FLUSH_PERIOD,
        compression: str = "zstd",
        mirrors: Sequence[Mirror] = (),
    ) -> None:
        self.path = Path(path) if path is not None else None
        self.mirrors = list(mirrors)
        self._file: IO[bytes] | None = None
        self._writer: Writer | None = None
        if self.path is not None:
            self._file, self._writer = _start_file(self.path, chunk_size, compression)
        self.compression = compression
        self.flush_period = flush_period
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, tuple[int, str]] = {}
        self.counts: Counter[str] = Counter()
        """Messages written per topic."""
        self.lost = 0
        """Messages that could not be serialized (a bug; logged): 0 in a good run."""
        self._epoch_ns = time.time_ns()
        self._t0: float | None = None
        self._first_ns: int | None = None
        self._last_ns = 0
        self._last_flush = time.monotonic()
        self.closed = False
        self.failure: str | None = None
        """Why the file stopped being written mid-run (a write failed: a full disk...); None while
        it is whole."""
        self.on_failure: list[Callable[[str], None]] = []
        """Called once with the warning when a write fails (any thread; a runtime's notice)."""
        self._fail_lock = threading.Lock()
        self._lock = threading.RLock()
        """Held around every use of the MCAP writer: its records are several writes each, and a
        recorder is not bound to one thread (front ends' callbacks, a close at a signal)."""

    # ------------------------------------------------------------------ time

    def place(self, t: float, epoch_ns: int) -> None:
        """Link time ``t`` is ``epoch_ns`` (ns since the epoch): the placing of every later time
        (another recorder's, to stamp alike; before the first message)."""
        self._t0, self._epoch_ns = t, epoch_ns

    @property
    def placing(self) -> tuple[float, int] | None:
        """(link time, ns since the epoch) of one instant, by which every time is placed (None before
        the first message)."""
        return None if self._t0 is None else (self._t0, self._epoch_ns)

    def ns(self, t: float) -> int:
        """Link-clock seconds -> ns since the epoch (the first time seen is when recording started)."""
        if self._t0 is None:
            self._t0 = t
        ns = self._epoch_ns + round((t - self._t0) * 1e9)
        return max(ns, 0)

    # ------------------------------------------------------------------ writing

    @contextlib.contextmanager
    def _writing(self) -> Iterator[None]:
        """Around every write to the file, one thread at a time and never cut in two by a signal's
        exception (:func:`omnibot.signals.held`: a record half written leaves its chunk unreadable):
        an ``OSError`` stops the file (:meth:`_failed`), nothing is raised."""
        with self._lock, held():
            try:
                yield
            except OSError as exc:
                self._failed(exc)

    def _failed(self, exc: OSError) -> None:
        """A write failed: no more writes to the file, one warning (stderr, :attr:`on_failure`)."""
        with self._fail_lock:
            if self.failure is not None:
                return
            why = exc.strerror or str(exc) or type(exc).__name__
            self.failure = (
                f"--log {self.path}: recording stopped, {why}; the robot goes on, the log keeps what "
                f"was written before (`omnibot log recover {self.path}` rewrites it whole)"
            )
            self._writer = None  # what it still holds (the open chunk) has no room: dropped
        log.debug("the log's write failed", exc_info=exc)
        with contextlib.suppress(OSError, ValueError):  # stderr on the same full disk, or closed
            print(f"omnibot: warning: {self.failure}", file=sys.stderr, flush=True)
        for callback in list(self.on_failure):
            try:
                callback(self.failure)
            except Exception:
                log.exception("a log failure callback failed")

    def _channel(self, writer: Writer, topic: str, typename: str) -> int:
        known = self._channels.get(topic)
        if known is not None:
            return known[0]
        schema = self._schemas.get(typename)
        if schema is None:
            schema = writer.register_schema(
                typename, "ros2msg", schemas.schema_text(typename).encode("utf-8")
            )
            self._schemas[typename] = schema
        channel = writer.register_channel(topic, "cdr", schema, {"offered_qos_profiles": offered_qos(topic)})
        self._channels[topic] = (channel, typename)
        return channel

    def write(self, topic: str, typename: str, message: Any, ns: int) -> None:
        """Serialize ``message`` (a ``typename`` object) onto ``topic`` at ``ns``."""
        if self.closed:
            return
        try:
            data = schemas.serialize(message, typename)
        except Exception:
            self.lost += 1
            log.exception("cannot serialize a %s for %s", typename, topic)
            return
        with self._lock:
            self.counts[topic] += 1
            sequence = self.counts[topic]
        for mirror in list(self.mirrors):
            try:
                mirror(topic, typename, data, ns)
            except Exception:
                # once, not once per message: the mirror is dropped, the file and the run go on
                log.exception("mirror %r failed on %s; it is dropped", mirror, topic)
                self.mirrors = [m for m in self.mirrors if m is not mirror]
        with self._writing():
            writer = self._writer
            if writer is None or self.closed:
                self._last_ns = max(self._last_ns, ns)
                return
            channel = self._channel(writer, topic, typename)
            writer.add_message(channel, log_time=ns, publish_time=ns, data=data, sequence=sequence)
            self._first_ns = ns if self._first_ns is None else min(self._first_ns, ns)
            self._last_ns = max(self._last_ns, ns)
            now = time.monotonic()
            if now - self._last_flush >= self.flush_period:
                self.flush()

    def flush(self) -> None:
        """Write the open chunk now."""
        with self._writing():
            writer = self._writer
            if not self.closed and writer is not None:
                writer.flush()  # type: ignore[no-untyped-call]
                self._last_flush = time.monotonic()

    def add_metadata(self, name: str, values: dict[str, str]) -> None:
        """An MCAP metadata record ``name`` (nothing without a file, or once closed)."""
        with self._writing():
            writer = self._writer
            if writer is not None and not self.closed:
                writer.add_metadata(name, values)

    # ------------------------------------------------------------------ the end

    def close(self) -> None:
        """Write the open chunk, rosbag2's metadata and the summary; close the file."""
        with self._lock:  # a write from another thread waits, then finds the file closed
            if self.closed:  # closed by another thread meanwhile
                return
            try:
                writer = self._writer
                if writer is not None:
                    with self._writing():
                        writer.add_metadata("rosbag2", {"serialized_metadata": self._rosbag2_metadata()})
                        writer.finish()  # type: ignore[no-untyped-call]
            finally:
                self.closed = True
                if self._file is not None:
                    with self._writing():
                        self._file.close()
            for mirror in self.mirrors:
                with contextlib.suppress(Exception):
                    mirror.close()

    def _rosbag2_metadata(self) -> str:
        assert self.path is not None
        channels = {topic: typename for topic, (_, typename) in self._channels.items()}
        start = self._first_ns or self._epoch_ns
        return rosbag2_metadata(self.path.name, channels, self.counts, start, self._last_ns)

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
