"""Protocol switching and discovery (client/switch.py), on clean and on noisy sim:// lines."""

from __future__ import annotations

from collections.abc import Sequence
from typing import NoReturn

import pytest

from omnibot.client import ErrorEvent, EventRecorder, RobotClient
from omnibot.client.greet import wait_for_controller
from omnibot.client.switch import ProtocolSwitch
from omnibot.client.tagging import UNTAGGED_VERDICT
from omnibot.client.wire import BinaryWire
from omnibot.errors import LinkError, LinkTimeout, ProtocolError
from omnibot.firmware.controller import Controller
from omnibot.protocol import codes
from omnibot.protocol.messages import ErrorReply, Ok, Reply, Vel
from omnibot.sim import SimDevice
from omnibot.transport import FaultLink, Link, LockstepLink
from tests.client.fakes import Silent
from tests.sim.linkio import read_until

NOISY = "drop=0.01&corrupt=0.01"  # 1 % of the bytes lost and 1 % corrupted, each way


def firmware(client: RobotClient) -> Controller:
    """The controller behind a (possibly fault-wrapped) sim:// client: the truth to check against."""
    link: Link = client.link
    while isinstance(link, FaultLink):
        link = link.inner
    assert isinstance(link, LockstepLink) and isinstance(link.device, SimDevice)
    return link.device.controller


@pytest.mark.parametrize("seed", range(12))
def test_switching_works_on_a_noisy_line(seed: int) -> None:
    """At 1 % faults each way the switch used to fail 10 times in 12 (issue 12)."""
    with RobotClient.open(f"faults+sim://omni4?faults.seed={seed}&{NOISY}") as client:
        ctrl = firmware(client)
        ctrl.executor.set_mode(codes.MODE_SIMULATION)  # another bit, which the switch must keep
        hello = client.use_binary()
        assert hello.version == max(codes.VERSIONS) and client.binary
        assert ctrl.binary and ctrl.mode == codes.MODE_SIMULATION | codes.MODE_BINARY
        assert client.status().binary
        client.use_text()
        assert not client.binary and not ctrl.binary and ctrl.mode == codes.MODE_SIMULATION


def test_a_corrupted_mode_line_is_put_right_in_binary() -> None:
    """MODE,4 with one bit flipped can read MODE,5 (simulation + binary): the switch confirms
    the bits with a binary STATUS and sets them again."""
    with RobotClient.open("sim://omni4?seed=1") as client:
        ctrl = firmware(client)
        wire = client.link
        real_write = wire._write
        first = [True]

        def corrupt_mode(data: bytes) -> None:
            if first[0] and data.startswith(b"MODE,4"):
                first[0] = False
                data = b"MODE,5" + data[6:]
            real_write(data)

        wire._write = corrupt_mode  # type: ignore[method-assign]
        client.use_binary()
        assert not first[0]
        assert ctrl.mode == codes.MODE_BINARY and client.mode_bits == codes.MODE_BINARY


@pytest.mark.parametrize("noise", ["", NOISY])
def test_a_controller_left_in_binary_is_found_and_put_back_to_text(
    noise: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A client killed in binary mode (e.g. by ``record``) leaves the controller there; the next
    client that connects (and sees no greeting) finds it in binary and switches it back."""
    device = SimDevice("omni4", seed=1)
    link: Link = LockstepLink(device)
    if noise:
        link = FaultLink(link, drop=0.01, corrupt=0.01, seed=5)
    first = RobotClient(link, "omni4")
    first.sleep(0.05)  # the greeting
    first.use_binary()
    assert device.controller.binary
    # the first client dies without use_text(); the next one opens the same line
    monkeypatch.setattr("omnibot.transport.url.open_link", lambda url: link)
    second = RobotClient.open("sim://omni4", settle=0.05)
    assert not second.binary and not device.controller.binary
    assert second.last_hello is not None and second.last_hello.name == "omni4"
    assert not second.status().binary
    second.close()


def test_find_protocol_on_a_text_controller_reads_its_error_lines() -> None:
    with RobotClient.open("sim://omni4?seed=1") as client:
        client.find_protocol()
        assert not client.binary
        assert client.status().idle  # no ERROR line for the probe is left to be taken as a reply
        assert client.outstanding == []


@pytest.mark.parametrize(("delay", "direction"), [(0.12, "rx"), (0.2, "rx"), (0.4, "rx"), (0.15, "both")])
def test_a_slow_line_is_found_in_text_and_leaves_no_probe_answer_behind(
    delay: float, direction: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Answers 0.1 s or more late (the pty emulator on a loaded machine, a radio link): a text
    controller answers each probe with two ERROR 23 lines, and those owed to the probes sent before
    the first answer came were read after find_protocol had returned, as the answers to the next
    commands: the tag question took them for "no tags" and the first HELLO got ERROR 23 (``follow``
    over the pty failed so under load), or the client asked again for ever."""
    device = SimDevice("omni4", seed=1)
    inner = LockstepLink(device)
    read_until(inner, b"\r\n")  # the power-up greeting, gone before the host opens the line
    link = FaultLink(inner, delay=delay, direction=direction)  # type: ignore[arg-type]
    monkeypatch.setattr("omnibot.transport.url.open_link", lambda url: link)
    with RobotClient.open("sim://omni4", timeout=2.0) as client:
        assert client.last_hello is None and not client.binary  # no greeting: the probes found text
        errors = EventRecorder()
        client.add_listener(errors, ErrorEvent)
        hello = wait_for_controller(client, window=5.0)
        assert hello.name == "omni4" and client.tags is True
        assert client.status().idle and client.outstanding == []
        client.use_binary()
        client.use_text()
        assert not device.controller.binary and client.status().idle
        assert errors.events == []


def test_a_silent_line_times_out() -> None:
    with RobotClient(LockstepLink(Silent()), "omni4") as client:
        with pytest.raises(LinkTimeout, match="none of"):
            client.find_protocol()
        with pytest.raises(LinkTimeout):
            client.use_binary()


def test_binary_needs_a_version_2_controller() -> None:
    with RobotClient.open("sim://omni4?seed=1") as client:
        assert client.last_hello is not None
        client.last_hello = type(client.last_hello)(1, "old", 4)
        with pytest.raises(ProtocolError, match="version 1"):
            client.use_binary()


@pytest.mark.parametrize("name", ["omni4", "bot"])
def test_a_controller_from_before_the_hello_window_is_named_in_one_line(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A controller flashed before the HELLO reply frame had its window (version, motors, name)
    is refused with what it is, not a timeout: "omni4"'s "o" reads as window -56 (malformed),
    "bot"'s "b" as 49 (allowed, but the text HELLO's name shows it)."""
    with RobotClient.open("sim://omni4") as client:
        ctrl = firmware(client)
        ctrl.name = name
        client.last_hello = client.hello()  # the text HELLO: the name
        reply = ctrl.link.reply

        def old_reply(type_id: int, seq: int, ints: list[int], text: bytes = b"") -> None:
            reply(type_id, seq, ints[:2] if type_id == codes.HELLO_REPLY else ints, text)

        monkeypatch.setattr(ctrl.link, "reply", old_reply)
        with pytest.raises(ProtocolError) as info:
            client.use_binary()
        assert str(info.value) == (
            "the controller's binary HELLO has no window field: its firmware predates this host; "
            "flash the current firmware"
        )


@pytest.mark.parametrize("window", [codes.WINDOW_MIN, codes.WINDOW])
def test_binary_sends_up_to_the_window_the_controller_announces(
    window: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The HELLO reply's window bounds the commands in flight (a controller may take fewer than
    the host's codes.WINDOW, as the UNO does), and fills it: every command runs once."""
    with RobotClient.open("sim://omni4") as client:
        ctrl = firmware(client)
        ctrl.link.window = window
        ran: list[int] = []
        vel = ctrl.executor.vel

        def counted(
            vx: int, vy: int, w: int, t_ms: int, accel: int = 0, body: list[int] | None = None
        ) -> None:
            ran.append(vx)
            vel(vx, vy, w, t_ms, accel, body)

        monkeypatch.setattr(ctrl.executor, "vel", counted)
        hello = client.use_binary()
        assert hello.window == window
        wire = client._wire
        assert isinstance(wire, BinaryWire) and wire.sender.window == window
        flying = []
        calls = []
        for k in range(3 * window):
            calls.append(client.submit(Vel(k % 90, 0, 0, 100)))
            flying.append(len(wire.sender.pending()))
        assert max(flying) == window
        assert all(isinstance(call.result(), Ok) for call in calls)
        assert ran == [k % 90 for k in range(3 * window)]


def _switch(
    host: RobotClient,
    tags: bool | None,
    answers: Sequence[Reply | None] = (),
    asked: list[bool] | None = None,
) -> ProtocolSwitch:
    """A ProtocolSwitch of ``host`` whose link fails the test and whose tag questions get ``answers``
    in turn (each question's ``tagged`` appended to ``asked``)."""
    replies = iter(answers)

    def nothing(*_: object) -> NoReturn:
        raise AssertionError("the switch talked to the controller")

    def ask(wait: float, tagged: bool) -> Reply | None:
        if asked is not None:
            asked.append(tagged)
        return next(replies)

    return ProtocolSwitch(
        host, tags, write=nothing, read=nothing, ask=ask, heard=lambda: True, forget=nothing
    )


def test_the_switch_follows_what_the_client_tells_it() -> None:
    """ProtocolSwitch on its own: the MODE bits answered pick the wire (bit 2 binary, bit 5 sequenced
    text with tags), a reset or a failed link puts it back; none of it talks to the controller."""
    with RobotClient(LockstepLink(Silent()), "omni4") as host:
        switch = _switch(host, True)
        assert switch.tags is True and switch.checks_wanted and not switch.binary and switch.mode is None
        switch.mode_set(codes.MODE_CHECKED_TEXT | codes.MODE_SEQUENCED_TEXT)
        assert (
            switch.sequenced
            and not switch.binary
            and switch.mode == codes.MODE_CHECKED_TEXT | codes.MODE_SEQUENCED_TEXT
        )
        switch.mode_set(codes.MODE_BINARY)
        assert isinstance(switch.wire, BinaryWire) and switch.binary and not switch.sequenced
        switch.link_failed()
        assert switch.binary and switch.mode == codes.MODE_BINARY
        switch.controller_reset(ask_tags=True)
        assert not switch.binary and switch.mode is None and switch.tags is True  # tags given, not asked
        switch.mode_reported(codes.MODE_CLOSED_LOOP)
        assert switch.mode == codes.MODE_CLOSED_LOOP and not switch.sequenced
        asking = _switch(host, None)
        asking.set_tags(True)
        asking.controller_reset(ask_tags=False)  # a reset while the tags are being asked about
        assert asking.tags is True
        asking.controller_reset(ask_tags=True)
        assert asking.tags is None and asking.auto_tags and not asking.checks_wanted


def test_the_switch_decides_on_tags_from_the_answers_alone() -> None:
    """The tag question's verdict: ERROR 23 to the tagged HELLO and the same to a plain one, on
    UNTAGGED_VERDICT rounds in a row, is a controller without tags; ERROR 42 one that runs checked
    text only; a controller that took tags before and now refuses them is an error."""
    refused = ErrorReply(codes.E_UNKNOWN)
    with RobotClient(LockstepLink(Silent()), "omni4") as host:
        asked: list[bool] = []
        untagged = _switch(host, None, [refused] * (2 * UNTAGGED_VERDICT), asked)
        untagged.detect_tags(0.1)
        assert untagged.tags is False and asked == [True, False] * UNTAGGED_VERDICT
        checked = _switch(host, None, [ErrorReply(codes.E_CHECK_REQUIRED)])
        checked.detect_tags(0.1)
        assert checked.tags is True and checked.checks_wanted
        again = _switch(host, None, [refused] * (2 * UNTAGGED_VERDICT))
        again.set_tags(True)
        again.controller_reset(ask_tags=True)
        with pytest.raises(LinkError, match="now refuses them"):
            again.detect_tags(0.1)
