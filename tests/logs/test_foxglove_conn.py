"""A Foxglove client's connection on its own: its queues' bounds."""

from __future__ import annotations

from omnibot.logs.foxglove_conn import BACKLOG, Connection


def test_a_client_that_does_not_read_is_flagged_once_its_control_queue_is_full() -> None:
    client = Connection(ws=None)  # type: ignore[arg-type]  # the queue alone: nothing is sent
    for _ in range(BACKLOG):
        client.status(2, "bad")
    assert not client.overflow
    client.status(2, "one too many")
    assert client.overflow and len(client.control) == BACKLOG
