"""The page's requests on their way to the link thread (web/inbox.py): bounded, and an emergency
stop or a page gone never dropped, coming after the requests waiting."""

from __future__ import annotations

from omnibot.web.inbox import INBOX_MAX, Inbox, PageGone, Request
from omnibot.web.messages import Drive, EStop, Resume


def test_a_full_inbox_drops_driving_and_flags_the_stop_and_the_page_gone_to_come_last() -> None:
    inbox = Inbox()
    drives = [Drive(type="drive", vx=k / (2 * INBOX_MAX)) for k in range(INBOX_MAX)]
    assert all(inbox.offer(d) for d in drives)
    assert not inbox.offer(Drive(type="drive", vx=1.0)) and not inbox.offer(Resume(type="resume"))
    assert inbox.offer(EStop(type="estop")) and inbox.offer(PageGone())  # flagged, not queued
    assert inbox.qsize() == INBOX_MAX
    taken = list(inbox.take())
    assert taken[:INBOX_MAX] == drives  # in the order they came
    assert taken[INBOX_MAX:] == [PageGone(), EStop(type="estop")]  # the stop last: nothing undoes it
    assert inbox.empty() and list(inbox.take()) == []  # the flags are cleared once taken


def test_with_room_a_stop_is_queued_in_its_place() -> None:
    inbox = Inbox()
    requests: list[Request] = [
        Drive(type="drive", vx=0.5),
        EStop(type="estop"),
        Resume(type="resume"),
        PageGone(),
    ]
    assert all(inbox.offer(r) for r in requests)
    assert list(inbox.take()) == requests
