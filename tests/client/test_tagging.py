"""Text's tags and checks as a client starts (client/tagging.py): what ``tags`` says before a byte
is sent. The tag question and MODE bits 4 and 5 on a controller are tests/client/test_switch.py's,
test_text_faults.py's and test_greet.py's."""

from __future__ import annotations

import pytest

from omnibot.client import RobotClient
from tests.client.fakes import ScriptedLink, controller


@pytest.mark.parametrize(
    ("tags", "auto", "checks_wanted"),
    [
        (None, True, False),  # asked before the first text command, then the bits if it takes tags
        (True, False, True),  # tagged from the first command, MODE bits 4 and 5 still to be asked for
        (False, False, False),  # never tagged, never the bits
    ],
)
def test_before_the_first_command_nothing_is_set_on_the_controller(
    tags: bool | None, auto: bool, checks_wanted: bool
) -> None:
    link = ScriptedLink(controller)
    client = RobotClient(link, tags=tags)
    switch = client._switch
    assert client.tags is tags and switch.auto_tags is auto and switch.checks_wanted is checks_wanted
    assert client.added_text_bits == 0 and not client.added_checked_text and not client.sequenced
    assert not link.written


def test_untagged_commands_never_ask_for_the_bits() -> None:
    link = ScriptedLink(controller)
    client = RobotClient(link, tags=False)
    client.stop()
    assert bytes(link.written) == b"STOP\n"
    assert client.added_text_bits == 0 and client.tags is False
