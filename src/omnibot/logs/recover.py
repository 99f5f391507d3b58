"""``omnibot log recover``: a log cut short (a run killed with SIGKILL, a full disk, a power cut)
rewritten whole, so that readers that need the summary open it too (rosbags, ``ros2 bag``, indexed
MCAP readers).

A recording writes its summary (chunk indexes, statistics) and rosbag2's metadata when it ends; a
process killed with SIGKILL never gets there, and its file ends after its last whole chunk (see
:mod:`omnibot.logs.writer`). :func:`recover` reads every record up to there and writes them into
a new file with the recorder's own writer settings: the schemas, the channels with their QoS, every
message with its log and publish time and sequence number, the metadata records (the robot
description, the adopted estimator...), then rosbag2's metadata for the messages recovered and the
summary, as ``mcap recover`` does for any MCAP file. The messages of the chunk that was still open
when the process died are not in the file and cannot be recovered.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, cast

from mcap.records import Channel, Message, Metadata, Schema
from mcap.writer import CompressionType, Writer

from omnibot import __version__
from omnibot.errors import ConfigError
from omnibot.logs.reader import LogFile
from omnibot.logs.writer import CHUNK_SIZE, rosbag2_metadata


@dataclass(frozen=True)
class Recovered:
    """What :func:`recover` wrote: ``messages`` from ``start_ns`` to ``end_ns`` into ``target``;
    ``cut_short``: why the source ended early (None: it was whole, nothing was written)."""

    source: Path
    target: Path
    cut_short: str | None
    messages: int = 0
    start_ns: int = 0
    end_ns: int = 0

    @property
    def duration(self) -> float:
        """Seconds from the first message recovered to the last."""
        return max(0.0, (self.end_ns - self.start_ns) / 1e9)


def default_target(source: Path) -> Path:
    """``run.mcap`` -> ``run-recovered.mcap`` beside it."""
    return source.with_name(f"{source.stem}-recovered{source.suffix or '.mcap'}")


def recover(source: str | Path, target: str | Path | None = None, *, force: bool = False) -> Recovered:
    """Rewrite the log ``source`` whole into ``target`` (default :func:`default_target`); a whole
    ``source`` is left as it is (nothing written) unless ``force``. ConfigError when ``source`` is
    no MCAP file or ``target`` exists or cannot be written."""
    log = LogFile.open(source)
    out = Path(target) if target is not None else default_target(log.path)
    if log.is_whole() and not force:
        return Recovered(log.path, out, None)
    if out.exists() and out.resolve() == log.path.resolve():
        raise ConfigError(f"{out} is the log itself: give another file to write", key="-o")
    if out.exists():
        raise ConfigError(f"{out} exists: remove it or give another file with -o", key="-o")
    counts: Counter[str] = Counter()
    topics: dict[str, str] = {}
    first: int | None = None
    last = 0
    try:
        with out.open("xb") as f:
            writer = Writer(cast("IO[Any]", f), chunk_size=CHUNK_SIZE, compression=CompressionType.ZSTD)
            writer.start(profile=log.profile or "ros2", library=f"omnibot {__version__} (recovered)")
            schemas: dict[int, tuple[int, str]] = {}
            channels: dict[int, tuple[int, str]] = {}
            for record in _data_section(log):
                if isinstance(record, Schema):
                    new = writer.register_schema(record.name, record.encoding, bytes(record.data))
                    schemas[record.id] = (new, record.name)
                elif isinstance(record, Channel) and record.id not in channels:
                    schema_id, typename = schemas.get(record.schema_id, (0, ""))
                    new = writer.register_channel(
                        record.topic, record.message_encoding, schema_id, dict(record.metadata)
                    )
                    channels[record.id] = (new, record.topic)
                    topics.setdefault(record.topic, typename)
                elif isinstance(record, Metadata) and record.name != "rosbag2":
                    writer.add_metadata(record.name, dict(record.metadata))
                elif isinstance(record, Message) and record.channel_id in channels:
                    channel, topic = channels[record.channel_id]
                    writer.add_message(
                        channel,
                        log_time=record.log_time,
                        publish_time=record.publish_time,
                        data=bytes(record.data),
                        sequence=record.sequence,
                    )
                    counts[topic] += 1
                    first = record.log_time if first is None else min(first, record.log_time)
                    last = max(last, record.log_time)
            metadata = rosbag2_metadata(out.name, topics, counts, first or 0, last)
            writer.add_metadata("rosbag2", {"serialized_metadata": metadata})
            writer.finish()  # type: ignore[no-untyped-call]
    except FileExistsError:
        raise ConfigError(f"{out} exists: remove it or give another file with -o", key="-o") from None
    except OSError as exc:
        raise ConfigError(f"cannot write {out}: {exc.strerror or exc}", key="-o") from None
    return Recovered(log.path, out, log.cut_short, sum(counts.values()), first or 0, last)


def _data_section(log: LogFile) -> Iterator[Any]:
    """The records of the data section, read one at a time (the summary of a whole file repeats
    what is in it)."""
    for record in log.records():
        if type(record).__name__ in ("DataEnd", "Footer"):
            return
        yield record
