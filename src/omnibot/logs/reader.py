"""Reading an omnibot log back: every message in file order, decoded with the same type store.

A file cut short (a run killed with SIGKILL, a full disk) is read up to its last whole chunk:
:attr:`LogFile.cut_short` then says where reading stopped, and the messages before it are all
there. ``omnibot log`` reads through this module; the tests read with rosbags and Foxglove's own
libraries as well.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mcap.exceptions import McapError
from mcap.records import Channel, Message, Metadata, Schema
from mcap.stream_reader import StreamReader

from omnibot.errors import ConfigError
from omnibot.logs import schemas


@dataclass(frozen=True)
class LogMessage:
    """One message: its topic, ROS type name, log time (ns since the epoch) and CDR bytes."""

    topic: str
    typename: str
    ns: int
    data: bytes

    @property
    def t(self) -> float:
        """Log time in seconds since the epoch."""
        return self.ns / 1e9

    def decode(self) -> Any:
        """The message decoded from its CDR bytes."""
        return schemas.deserialize(self.data, self.typename)


@dataclass
class LogFile:
    """An MCAP file written by :class:`~omnibot.logs.recorder.Recorder` (or any ros2-profile MCAP)."""

    path: Path
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    profile: str = ""
    cut_short: str | None = None
    """Why reading stopped before the file's end (None: the file is whole)."""

    @classmethod
    def open(cls, path: str | Path) -> LogFile:
        """The MCAP file at ``path``; ConfigError when it is missing, unreadable or no MCAP file."""
        p = Path(path)
        if not p.is_file():
            raise ConfigError(f"no log file {p}", key="FILE")
        log = cls(p)
        try:
            with p.open("rb") as f:
                head = f.read(8)
        except OSError as exc:
            raise ConfigError(f"cannot read {p}: {exc.strerror or exc}", key="FILE") from None
        if head != b"\x89MCAP0\r\n":
            raise ConfigError(f"{p} is not an MCAP file", key="FILE")
        return log

    def records(self) -> Iterator[Any]:
        """Every record of the file in file order (``mcap.records``: Header, Schema, Channel, Message,
        Metadata, ...), up to where it was cut short (then :attr:`cut_short` says why)."""
        self.cut_short = None
        with self.path.open("rb") as f:
            records = StreamReader(f, skip_magic=False).records
            while True:
                try:
                    record = next(records)
                except StopIteration:
                    break
                except (McapError, ValueError, EOFError, OSError, KeyError) as exc:
                    self.cut_short = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
                    break
                except Exception as exc:  # the mcap reader's struct/zstd errors on a torn chunk
                    self.cut_short = f"{type(exc).__name__}: {exc}"
                    break
                yield record
        if self.cut_short is None and not self._has_footer():
            self.cut_short = "no summary (the recording did not end normally)"

    def messages(self, topics: set[str] | None = None) -> Iterator[LogMessage]:
        """Every message (of ``topics``, if given) in file order; metadata is collected on the way."""
        schema_names: dict[int, str] = {}
        channels: dict[int, Channel] = {}
        for record in self.records():
            if isinstance(record, Schema):
                schema_names[record.id] = record.name
            elif isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Metadata):
                self.metadata[record.name] = dict(record.metadata)
            elif isinstance(record, Message):
                channel = channels.get(record.channel_id)
                if channel is None or (topics is not None and channel.topic not in topics):
                    continue
                yield LogMessage(
                    channel.topic,
                    schema_names.get(channel.schema_id, ""),
                    record.log_time,
                    bytes(record.data),
                )
            elif type(record).__name__ == "Header":
                self.profile = getattr(record, "profile", "")

    def is_whole(self) -> bool:
        """The file ends with its footer (a recording that ended normally, summary and all)."""
        return self._has_footer()

    def _has_footer(self) -> bool:
        with self.path.open("rb") as f:
            f.seek(0, 2)
            if f.tell() < 16:
                return False
            f.seek(-8, 2)
            return f.read(8) == b"\x89MCAP0\r\n"

    def read_all(self) -> list[LogMessage]:
        """Every message in file order, as a list."""
        return list(self.messages())
