"""Text protocol over a faulty line (``faults+sim://``, fixed seeds): lost and corrupted bytes.

Each command is a ``TELEM,0,<mask>`` with its own mask, and the controller's ``execute`` is wrapped
to record what ran, so a test can tell: calls that succeeded, calls that failed, and whether any
command said OK did not run, ran twice, or ran with parameters other than those sent. The client
sets MODE bits 4 and 5 (checked, sequenced text): a command whose reply is lost is sent again, and
the controller answers the copy from the reply it kept.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from dataclasses import dataclass, field

import pytest

from omnibot.client import EventRecorder, ResetEvent, RobotClient
from omnibot.client.tagging import UNTAGGED_VERDICT
from omnibot.client.wire import TextWire
from omnibot.errors import ControllerError, LinkTimeout, OmnibotError
from omnibot.firmware.controller import Controller
from omnibot.protocol import codes, text
from omnibot.protocol.messages import Move, Ok, Telem
from omnibot.transport import FaultLink, Link, open_link

from .fakes import ScriptedLink, controller


@dataclass
class Tally:
    ok: list[int] = field(default_factory=list)  # masks of the calls that returned OK
    failed: list[int] = field(default_factory=list)  # masks of the calls that raised
    ran: list[tuple[int, list[int]]] = field(default_factory=list)  # what the controller executed


def faulty(drop: float = 0.0, corrupt: float = 0.0, direction: str = "both", seed: int = 1) -> Link:
    inner = open_link("sim://omni4?seed=1")
    return FaultLink(inner, drop=drop, corrupt=corrupt, seed=seed, direction=direction)  # type: ignore[arg-type]


def run(client: RobotClient, n: int = 250) -> Tally:
    """Send ``n`` TELEM commands (masks 0..n-1 mod 256), recording what the controller executes."""
    tally = Tally()
    link = client.link
    assert isinstance(link, FaultLink)
    ctrl = link.inner.device.controller  # type: ignore[attr-defined]
    execute = ctrl.execute

    def spy(kw: int, p: list[int]) -> None:
        tally.ran.append((kw, list(p)))
        execute(kw, p)

    ctrl.execute = spy
    for i in range(n):
        mask = i % 256
        try:
            client.execute(Telem(0, mask))
        except (LinkTimeout, ControllerError, OmnibotError):
            tally.failed.append(mask)
        else:
            tally.ok.append(mask)
    return tally


def sent_ran(tally: Tally) -> list[int]:
    """Masks of the TELEM commands that ran with the period sent (0)."""
    return [p[1] for kw, p in tally.ran if kw == codes.TELEM and p[0] == 0]


def longest_failure_run(tally: Tally, n: int) -> int:
    """The most calls in a row that failed (a lost reply that poisoned the line: all the rest)."""
    failed = {i for i in range(n) if i % 256 in tally.failed}
    run = longest = 0
    for i in range(n):
        run = run + 1 if i in failed else 0
        longest = max(longest, run)
    return longest


def check_honest(tally: Tally, n: int) -> None:
    """No OK for a command that did not run, nothing ran that was not sent."""
    ran = sent_ran(tally)
    # besides TELEM: the probe's HELLO, STATUS, and the client's own MODE bits 4 and 5 (checked,
    # sequenced text) or, from a controller without bit 5, bit 4 alone
    setup = ([codes.MODE_CHECKED_TEXT | codes.MODE_SEQUENCED_TEXT], [codes.MODE_CHECKED_TEXT])
    assert all(
        kw in (codes.TELEM, codes.HELLO, codes.STATUS) or (kw == codes.MODE and p in setup)
        for kw, p in tally.ran
    )
    assert all(p[0] == 0 and 0 <= p[1] < 256 for kw, p in tally.ran if kw == codes.TELEM)
    for mask in tally.ok:  # every OK'd command ran (as often as it was said OK)
        assert ran.count(mask) >= tally.ok.count(mask), f"TELEM,0,{mask} said OK but did not run"
    assert len(tally.ok) + len(tally.failed) == n
    assert len(ran) == len(set(ran)) and set(ran) <= set(range(n)), "a corrupted command ran"


def without_sequence_numbers(ctrl: Controller) -> None:
    """Make ``ctrl`` a controller without MODE bit 5 (firmware from before it): ERROR 39."""
    check = ctrl.limits.check

    def refuse_bit_5(kw: int, p: list[int]) -> int:
        return codes.E_UNSUPPORTED if kw == codes.MODE and p[0] & codes.MODE_SEQUENCED_TEXT else check(kw, p)

    ctrl.limits.check = refuse_bit_5  # type: ignore[method-assign]


@pytest.fixture
def clients() -> Iterator[list[RobotClient]]:
    made: list[RobotClient] = []
    yield made
    for c in made:
        c.close()


def _client(made: list[RobotClient], link: Link, tags: bool | None = None) -> RobotClient:
    client = RobotClient(link, "omni4", timeout=0.2, tags=tags)
    made.append(client)
    return client


def test_lost_replies_are_sent_again_and_run_once(clients: list[RobotClient]) -> None:
    link = faulty(drop=0.01, direction="rx", seed=3)
    client = _client(clients, link)
    tally = run(client)
    assert client.tags is True and client.sequenced
    check_honest(tally, 250)  # each ran once: the copies sent again were answered, not run
    assert link.stats.rx_dropped > 20, "the seed should lose some replies"  # type: ignore[attr-defined]
    assert tally.failed == [] and sorted(sent_ran(tally)) == sorted(tally.ok)


def test_corrupted_commands_never_run_and_are_never_said_ok(clients: list[RobotClient]) -> None:
    link = faulty(corrupt=0.01, direction="both", seed=5)
    client = _client(clients, link)
    tally = run(client)
    check_honest(tally, 250)
    assert link.stats.tx_corrupted + link.stats.rx_corrupted > 40  # type: ignore[attr-defined]
    # a damaged command or reply is sent again until one copy gets through: no call fails
    assert tally.failed == []


def test_drop_and_corrupt_both_ways(clients: list[RobotClient]) -> None:
    client = _client(clients, faulty(drop=0.005, corrupt=0.005, seed=11))
    tally = run(client)
    check_honest(tally, 250)
    assert tally.failed == []


def test_checked_text_without_sequence_numbers_fails_only_the_call_whose_reply_is_lost(
    clients: list[RobotClient],
) -> None:
    """A controller without MODE bit 5 (an older firmware): tagged and checked, never sent twice, so a lost
    reply fails its own call (it may or may not have run) and the calls after it work."""
    link = faulty(drop=0.01, direction="rx", seed=3)
    without_sequence_numbers(link.inner.device.controller)  # type: ignore[attr-defined]
    client = _client(clients, link)
    tally = run(client)
    assert client.tags is True and not client.sequenced and client.added_checked_text
    check_honest(tally, 250)
    assert tally.failed, "the seed should lose some replies"
    assert len(tally.failed) <= 30  # about the share of replies (13 bytes) that lose a byte: 12 %
    ran = sent_ran(tally)
    assert all(mask in ran for mask in tally.failed)  # they ran; only their replies were lost
    assert longest_failure_run(tally, 250) <= 3  # not poisoned: the calls after a lost reply work


def test_untagged_client_resynchronises_after_a_lost_reply(clients: list[RobotClient]) -> None:
    client = _client(clients, faulty(drop=0.01, direction="rx", seed=3), tags=False)
    tally = run(client)
    check_honest(tally, 250)
    assert tally.failed and len(tally.failed) <= 40
    assert longest_failure_run(tally, 250) <= 3  # the next call (after a STATUS exchange) works again


def test_without_tags_corruption_runs_wrong_commands(clients: list[RobotClient]) -> None:
    """What the tags and checks prevent: untagged, the same line runs commands nobody sent."""
    client = _client(clients, faulty(corrupt=0.01, direction="both", seed=5), tags=False)
    tally = run(client)
    with pytest.raises(AssertionError, match="said OK but did not run"):
        check_honest(tally, 250)
    ran = sent_ran(tally)
    assert any(ran.count(mask) > 1 for mask in ran)  # a command corrupted into another one ran


def _old_controller(line: bytes) -> bytes:
    """A controller from before tags: a '#' or '*' in a keyword is an unknown command."""
    if b"#" in line.split(b",")[0] or b"*" in line.split(b",")[0]:
        return b"ERROR,23,unknown command\r\n"
    return controller(line)


def test_old_controller_gets_untagged_commands() -> None:
    link = ScriptedLink(_old_controller)
    client = RobotClient(link)
    client.status()
    assert client.tags is False
    lines = bytes(link.written).split(b"\n")
    probes = [line for line in lines if line.startswith(b"HELLO#")]
    # each tagged question answered untagged, and a plain HELLO answered as plainly: the line is clean
    assert len(probes) == UNTAGGED_VERDICT and lines.count(b"HELLO") == UNTAGGED_VERDICT
    assert bytes(link.written).endswith(b"\nSTATUS\n")


def test_tagged_commands_on_the_wire(clients: list[RobotClient]) -> None:
    client = _client(clients, open_link("spy+sim://omni4?seed=1&file=/dev/null"))
    client.status()
    assert client.tags is True
    pendings = client.submit_text("MOVE,INF,60,0,0;FOO")
    assert pendings[0].result().keyword == "OK"
    with pytest.raises(ControllerError, match="unknown command"):
        pendings[1].result()


def test_reset_of_a_tagged_controller_is_seen_and_tags_asked_again() -> None:
    with RobotClient.open("sim://omni4?seed=1") as client:
        resets = EventRecorder()
        client.on_reset(resets)
        client.status()
        assert client.tags is True
        device = client.link.device  # type: ignore[attr-defined]
        device.controller = Controller(device.hal, device.controller.config)  # reboots: greets
        client.sleep(0.05)
        assert len(resets.of(ResetEvent)) == 1 and client.tags is None
        assert client.status().idle
        assert client.tags is True


@pytest.mark.parametrize("owed", [1, 2])
def test_untagged_lines_owed_to_an_earlier_client_do_not_fool_the_tag_question(owed: int) -> None:
    """An ERROR line left on the line (a previous client's command) answers the first tagged HELLO;
    the HELLO reply tagged for it then came while no HELLO waited and was taken for a reset, which
    failed the next command and asked again, for ever. A tagged HELLO reply is never a reset."""
    link = open_link("sim://omni4?seed=1")
    link.read(timeout=0.05)  # the power-up greeting
    link.write(b"FOO\n" * owed)  # a previous client's, its ERROR still to come
    with RobotClient(link) as client:
        resets = EventRecorder()
        client.on_reset(resets)
        assert client.status().idle
        assert client.tags is True and client.hello().name == "omni4"
        assert resets.events == []


def test_late_tagged_reply_lands_on_its_own_command() -> None:
    """Checked text without sequence numbers (a controller without MODE bit 5): a reply that comes
    after its call gave up lands on its own command, not on the next one."""
    held: list[bytes] = []

    def slow(line: bytes) -> bytes:  # answers MOVE only when the next command comes
        tag = int(line.rstrip(b"\n").split(b"#")[1].split(b"*")[0])
        if line.startswith(b"HELLO#"):
            return text.with_suffix(b"HELLO,2,fake,4", tag) + b"\r\n"
        if line.startswith(b"MODE,48"):
            return text.with_suffix(b"ERROR,39,not supported", tag) + b"\r\n"
        reply = b"OK" if not line.startswith(b"STATUS") else b"STATUS,1,0,16,0;POWER,0,0,0,0;MOVE,0,0,0,0"
        out = b"".join(held)
        held.clear()
        answer = text.with_suffix(reply, tag) + b"\r\n"
        if line.startswith(b"MOVE"):
            held.append(answer)
            return out
        return out + answer

    link = ScriptedLink(slow)
    client = RobotClient(link, timeout=0.5)
    move = client.submit(Move(10, 40, 0, 0))
    with pytest.raises(LinkTimeout) as info:
        move.result()
    assert "may or may not have run" in str(info.value.__notes__)
    assert client.tags is True and client.status().idle  # the late OK does not answer STATUS
    assert move.reply == Ok()  # it landed on MOVE
    assert move.result() == Ok()


def test_a_step_before_a_command_that_times_out_says_the_command_was_not_sent() -> None:
    # the tag probe: nothing answers at all
    silent = RobotClient(ScriptedLink(), timeout=0.2)
    with pytest.raises(LinkTimeout, match=r"no reply to HELLO.*\(STATUS was not sent\)"):
        silent.status()
    assert b"STATUS" not in bytes(silent.link.written)  # type: ignore[attr-defined]
    # the resync of an untagged client: a command timed out, then the controller fell silent
    answers = {"on": True}
    link = ScriptedLink(lambda line: controller(line) if answers["on"] and b"TELEM" not in line else b"")
    client = RobotClient(link, tags=False, timeout=0.2)
    with pytest.raises(LinkTimeout):
        client.execute(Telem(0, 1))
    answers["on"] = False
    with pytest.raises(LinkTimeout, match=r"\(TELEM,0,2 was not sent\)"):
        client.execute(Telem(0, 2))
    assert b"TELEM,0,2" not in bytes(link.written)


@pytest.mark.parametrize("into", [b";", b"\r", b"\n"])
def test_a_byte_turned_into_a_terminator_runs_nothing(clients: list[RobotClient], into: bytes) -> None:
    """A digit damaged into a terminator cuts the checked line short (``TELEM,0,2`` and ``9#n*....``):
    the client has asked for checked text only (MODE bit 4), so neither piece runs, however often
    the client sends the line again (here every copy is cut the same way)."""
    client = _client(clients, faulty())
    client.execute(Telem(0, 1))  # the probe, then MODE bit 4
    assert client.tags and client.added_checked_text
    link = client.link
    ctrl = link.inner.device.controller  # type: ignore[attr-defined]
    ran: list[tuple[int, list[int]]] = []
    execute = ctrl.execute

    def spy(kw: int, p: list[int]) -> None:
        ran.append((kw, list(p)))
        execute(kw, p)

    ctrl.execute = spy
    write = link.write
    link.write = lambda data: write(data.replace(b"TELEM,0,249", b"TELEM,0,2" + into + b"9", 1))  # type: ignore[method-assign]
    with pytest.raises(
        LinkTimeout, match=f"after {codes.HOST_RETRIES + codes.TEXT_HOST_EXTRA_RETRIES} retries"
    ):  # no piece is answered with its tag
        client.execute(Telem(0, 249))
    assert ran == []
    link.write = write  # type: ignore[method-assign]
    client.execute(Telem(0, 0))  # the next call works, after a HELLO that starts the sequence again
    assert ran == [(codes.HELLO, []), (codes.TELEM, [0, 0])]


def test_sequenced_texts_sender_has_more_fast_retransmissions() -> None:
    """Sequenced text's host sender (client/wire.py): binary's schedule with
    codes.TEXT_HOST_EXTRA_RETRIES more retransmissions 50 ms apart before the patient ones (its
    lines are longer, so a try fails more often on a lossy line)."""
    wire = TextWire(tags=True)
    wire.sequence(True)
    tx = wire.sender
    assert tx is not None
    first, _ = tx.allocate()
    tx.track(first, b"a", 0)
    sent = [now for now in range(0, 8000) if tx.poll(now)]
    fast = codes.RETRIES + codes.TEXT_HOST_EXTRA_RETRIES
    assert sent[:fast] == list(range(50, 50 * (fast + 1), 50))
    assert [b - a for a, b in itertools.pairwise(sent)][fast - 1 :] == [100, 200, 400, 400, 400, 400, 400]
    assert tx.take_failed() == [first] and tx.budget_ms() == 3200 + 50 * codes.TEXT_HOST_EXTRA_RETRIES
