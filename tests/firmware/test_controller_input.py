"""The controller's input (controller_input.py): lines split and merged, tags, checks and sequence numbers."""

from __future__ import annotations

import pytest

from omnibot.protocol import codes, linecheck
from tests.firmware.conftest import Rig, make_rig
from tests.firmware.test_controller import err


def test_line_too_long_then_next_command(rig: Rig) -> None:
    assert rig.send("MOVE," + "1" * 70 + ";STATUS;") == [err(codes.E_TOO_LONG), rig.status()]


def test_one_reply_per_command_in_order_merged_and_split(rig: Rig) -> None:
    text = "HELLO;FOO;;\r\nMOVE,2,40,0,0;STATUS;MOVE,1\n"
    whole = rig.send(text)
    assert whole[0] == "HELLO,2,omni4,4"
    assert whole[1] == err(codes.E_UNKNOWN)
    assert whole[2] == "OK"
    assert whole[3].startswith("STATUS,0,0")
    assert whole[4] == err(codes.E_PARAM_COUNT)
    assert len(whole) == 5
    other = make_rig()
    got: list[str] = []
    for ch in text:
        got += other.send(ch)
    assert got == whole


def _tagged(body: str, tag: str | None, check: bool) -> str:
    data = body.encode()
    return (data + linecheck.suffix(data, None if tag is None else tag.encode(), check)).decode()


@pytest.mark.parametrize(("tag", "check"), [("7", False), ("0042", True), (None, True), ("9999", True)])
def test_reply_echoes_tag_and_check(rig: Rig, tag: str | None, check: bool) -> None:
    for body, reply in (
        ("MOVE,10,40,0,0", "OK"),
        ("FOO,1", err(codes.E_UNKNOWN)),
        ("MOVE,1,x,0,0", err(codes.E_NOT_INTEGER)),
        ("HELLO", f"HELLO,{codes.PROTOCOL_VERSION},omni4,4"),
    ):
        assert rig.cmd(_tagged(body, tag, check)) == [_tagged(reply, tag, check)]
    status = rig.cmd(_tagged("STATUS", tag, check))[0]
    end = linecheck.split(status.encode())[0]
    assert status.startswith("STATUS,0,0,16,0;") and status == _tagged(status[:end], tag, check)


def test_untagged_command_gets_todays_reply(rig: Rig) -> None:
    assert rig.cmd("MOVE,10,40,0,0") == ["OK"]
    assert rig.cmd("STOP") == ["OK", "IDLE"]  # events are never tagged


def test_bad_check_refuses_the_command_untagged(rig: Rig) -> None:
    good = _tagged("MOVE,10,40,0,0", "5", True)
    bad = good.replace("10", "90")
    assert rig.cmd(bad) == [err(codes.E_CHECKSUM)]
    assert rig.status() == "STATUS,1,0,16,0;POWER,0,0,0,0;MOVE,0,0,0,0"  # nothing ran
    assert rig.cmd(good[:-1] + "G") == [err(codes.E_NOT_INTEGER)]  # not a check: left in the body
    assert rig.cmd("STATUS#12345") == [err(codes.E_UNKNOWN)]  # five digits are no tag
    assert rig.cmd(good) == [_tagged("OK", "5", True)]


def test_sequenced_text_runs_each_tag_once_and_in_order(rig: Rig) -> None:
    """MODE bit 5: a checked tag is a sequence number. A duplicate gets the reply kept and runs
    nothing; one out of order gets nothing; STOP, HELLO and MODE are taken whatever was expected."""

    def seq(body: str, tag: int) -> list[str]:
        return rig.cmd(_tagged(body, str(tag), True))

    def remembered() -> int:  # the remembered MOVE's distance once the queue ran: each DELTA adds 4 cm
        rig.run(1000)
        return int(rig.status().split(";MOVE,")[1].split(",")[0])

    delta = "DELTA,4,40,0,0,0"
    twice = ";".join([_tagged(delta, "3", True)] * 2)
    assert rig.cmd(twice) == [_tagged("OK", "3", True)] * 2  # bit 5 clear: a copy runs again
    assert remembered() == 8
    assert seq("STOP", 4)[0] == _tagged("OK", "4", True)
    assert seq("MODE,32", 5) == [_tagged("OK", "5", True)]  # bit 5 alone: starts the sequence at its tag
    assert seq(delta, 6) == [_tagged("OK", "6", True)]
    assert seq(delta, 6) == [_tagged("OK", "6", True)]  # the copy: answered, not run
    assert remembered() == 4 and rig.status().startswith("STATUS,1,0,16,32;")
    assert seq(delta, 8) == []  # 7 never came: out of order, dropped
    assert seq(delta, 7) == [_tagged("OK", "7", True)]
    assert seq("DELTA,0,0,0,0,-1", 8) == [_tagged(err(codes.E_REPEAT), "8", True)]
    assert seq("DELTA,0,0,0,0,-1", 8) == [_tagged(err(codes.E_REPEAT), "8", True)]
    assert rig.cmd(delta) == ["OK"]  # untagged: not sequenced
    assert remembered() == 12
    assert seq("STOP", 40) == [_tagged("OK", "40", True)]  # sync: taken whatever was expected
    assert seq(delta, 41) == [_tagged("OK", "41", True)]
    assert seq("HELLO", 3) == [_tagged("HELLO,2,omni4,4", "3", True)]  # starts afresh
    assert seq(delta, 4) == [_tagged("OK", "4", True)]  # 4 was kept before the HELLO: new now
    assert remembered() == 8
    assert seq("MODE,0", 9999) == []  # 5 before the expected 5 (tags wrap 9999 -> 1): a duplicate
    assert seq("MODE,0", 5) == [_tagged("OK", "5", True)]
    assert seq(delta, 4)[0] == _tagged("OK", "4", True)  # bit 5 clear again (then WARN 11: 120 cm/s)
    assert remembered() == 12
