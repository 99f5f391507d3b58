"""A long recording keeps its memory bounded: the open chunk is written every CHUNK_SIZE bytes (and
every FLUSH_PERIOD s), so what the recorder holds does not grow with the run (only one small chunk
index per chunk does). Two simulated minutes of 100 Hz telemetry + VEL, fed straight to the
recorder (the link and the simulator are not what is measured here)."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

from omnibot.client.events import Telemetry
from omnibot.logs.reader import LogFile
from omnibot.logs.recorder import Recorder
from omnibot.protocol import text
from omnibot.protocol.messages import Ok, Vel
from omnibot.protocol.messages import Telemetry as TelMessage
from omnibot.robot.description import load_robot

RATE = 100


def feed(rec: Recorder, i: int) -> None:
    """One 10 ms cycle: VEL out, OK and a TEL sample back, as the client reports them."""
    t = i / RATE
    vel = Vel(20, 0, 10, 200)
    rec.message(t, "command", vel)
    rec.link_bytes(t, "TX", text.encode(vel))
    tel = TelMessage(
        i * 10, (90, 90, -90, -90), (3 * i, 3 * i, -3 * i, -3 * i), None, 10, i, 7200, (0, 0), (55,)
    )
    rec.link_bytes(t, "RX", b"OK\r\n" + text.encode(tel, b"\r\n"))
    rec.message(t, "reply", Ok())
    rec.event(Telemetry.from_message(tel, t))


def test_memory_stays_bounded_over_a_long_run(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    chunk = 32 * 1024
    rec = Recorder(tmp_path / "long.mcap", chunk_size=chunk)
    rec.start(load_robot("omni4"))
    for i in range(10 * RATE):  # warm up: caches, the first chunks
        feed(rec, i)
    tracemalloc.start()
    try:
        early, _ = tracemalloc.get_traced_memory()
        for i in range(10 * RATE, 60 * RATE):
            feed(rec, i)
        late, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    rec.close()
    with (tmp_path / "long.mcap").open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    chunks = len(summary.chunk_indexes) * 50 // 60  # written while measured
    assert chunks > 20
    # what may grow: the open chunk (up to about two chunk sizes while it is built and compressed)
    # and one chunk index per chunk written (well under 2 KB); nothing per message
    assert late - early < 2 * chunk + 2000 * chunks, (early, late, chunks)
    assert peak - early < 4 * chunk + 2000 * chunks, (early, peak, chunks)
    assert rec.lost == 0
    tels = list(LogFile.open(tmp_path / "long.mcap").messages({"/omnibot/protocol"}))
    assert sum(1 for m in tels if m.decode().keyword == "TEL") == 60 * RATE
