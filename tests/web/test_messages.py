"""Browser messages: what is accepted, and the reasons given for what is not."""

from __future__ import annotations

import json

import pytest

from omnibot.web.messages import MAX_DEPTH, MAX_FRAME, Drive, EStop, Joy, Ping, Teach, nesting, parse_message


def test_valid_messages() -> None:
    assert parse_message('{"type": "drive", "vx": 0.5, "w": -1}') == Drive(type="drive", vx=0.5, w=-1.0)
    assert parse_message('{"type": "drive", "enable": false}') == Drive(type="drive", enable=False)
    joy = parse_message('{"type": "joy", "axes": [0.1, -1], "buttons": [0, 1, 0.5]}')
    assert isinstance(joy, Joy) and joy.axes == [0.1, -1.0]
    assert parse_message('{"type": "estop"}') == EStop(type="estop")
    assert parse_message('{"type": "teach", "action": "follow"}') == Teach(type="teach", action="follow")
    assert parse_message('{"type": "ping", "t": 12.5}') == Ping(type="ping", t=12.5)


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ('{"type": "drive", "vx": 5}', "drive.vx: Input should be less than or equal to 1 (got 5)"),
        ('{"type": "drive", "vx": NaN}', "not JSON: NaN is not a number a message may hold"),
        ('{"type": "drive", "vx": -Infinity}', "not JSON: -Infinity is not a number"),
        ('{"type": "drive", "vx": 1e999}', "not JSON: 1e999 is out of range"),
        ('{"type": "ping", "t": 1e309}', "not JSON: 1e309 is out of range"),
        ('{"type": "drive", "vx": "1"}', "drive.vx: Input should be a valid number (got '1')"),
        ('{"type": "drive", "vx": true}', "drive.vx: Input should be a valid number"),
        ('{"type": "drive", "w": null}', "drive.w: Input should be a valid number"),
        ('{"type": "drive", "enable": 1}', "drive.enable: Input should be a valid boolean (got 1)"),
        ('{"type": "drive", "enable": "true"}', "drive.enable: Input should be a valid boolean"),
        ('{"type": "joy", "axes": ["0.5"], "buttons": [true]}', "joy.axes.0: Input should be a valid number"),
        ('{"type": "joy", "axes": [[0.5]], "buttons": []}', "joy.axes.0: Input should be a valid number"),
        ('{"type": "ping", "t": "12"}', "ping.t: Input should be a valid number"),
        ("[" * 1500 + "]" * 1500, "message nested too deeply (at most 4 levels"),
        ('{"type": "drive", "source": {"a": {"b": [[1]]}}}', "message nested too deeply"),
        ('{"type": "drive", "vx": 1' + "0" * 400 + "}", "drive.vx: Input should be"),
        ('{"type": "drive", "vx": "fast"}', "drive.vx: Input should be a valid number"),
        ('{"type": "drive", "speed": 1}', "drive.speed: unknown key"),
        ('{"type": "drive", "enable": "yes please"}', "drive.enable: Input should be a valid boolean"),
        ('{"type": "fly"}', "unknown message type 'fly'; expected one of: drive, joy, estop"),
        ('{"vx": 1}', "a message needs a 'type'"),
        (
            '{"type": "joy", "axes": [2], "buttons": []}',
            "joy.axes.0: Input should be less than or equal to 1",
        ),
        (
            json.dumps({"type": "joy", "axes": [], "buttons": [0] * 40}),
            "joy.buttons: List should have at most 32 items",
        ),
        (
            '{"type": "teach", "action": "dance"}',
            "teach.action: Input should be 'record', 'stop' or 'follow'",
        ),
        ("[1, 2]", "a message is a JSON object, got list"),
        ("not json", "not JSON: Expecting value"),
    ],
)
def test_rejected_with_a_reason(text: str, reason: str) -> None:
    result = parse_message(text)
    assert isinstance(result, str)
    assert reason in result


def test_oversized_frames_are_not_parsed() -> None:
    text = json.dumps({"type": "ping", "t": 1, "pad": "x" * MAX_FRAME})
    result = parse_message(text)
    assert isinstance(result, str) and result.startswith("message too long")


def test_nesting_counts_brackets_outside_strings_only() -> None:
    assert nesting('{"type": "joy", "axes": [0], "buttons": []}') == 2
    assert nesting('{"type": "ping", "t": 1, "x": "[[[[[[\\"[[[["}') == 1
    assert nesting("[" * 10_000) == 10_000  # unbalanced: still counted without recursion
    assert nesting("1") == 0
    assert parse_message('{"type": "ping", "t": 0.5}') == Ping(type="ping", t=0.5)
    deep = '{"type": "joy", "axes": ' + "[" * (MAX_DEPTH - 1) + "]" * (MAX_DEPTH - 1) + ', "buttons": []}'
    assert nesting(deep) == MAX_DEPTH and "nested" not in str(parse_message(deep))


def test_integers_are_numbers() -> None:
    assert parse_message('{"type": "drive", "vx": 1, "vy": -1, "w": 0}') == Drive(
        type="drive", vx=1.0, vy=-1.0, w=0.0
    )
