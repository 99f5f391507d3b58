"""Every ERROR code a host can trigger (docs/protocol.md, Codes), and that a rejected command
changes nothing. 36 (internal fault) cannot be triggered from outside; 40 is in test_safety.py."""

from __future__ import annotations

import itertools
from collections.abc import Iterator

import pytest

from omnibot.client import (
    CalibrationRejected,
    CommandRejected,
    NotSupported,
    OutOfRange,
    QueueFull,
    RobotClient,
)
from omnibot.errors import ControllerError
from omnibot.protocol import codes
from omnibot.protocol.messages import Move, Stop

# code -> (exception class, command lines that must get exactly that code)
CASES: dict[int, tuple[type[ControllerError], list[str]]] = {
    codes.E_TOO_LONG: (CommandRejected, ["MOVE," + "1" * 70, "STATUS" + " " * 59]),
    codes.E_UNKNOWN: (
        CommandRejected,
        ["FOO", "MOVEX,1,40,0,0", "ACK", "OK", "\x01\x7f", "STATUS\x00", "STOP\x00\x00", "MOVE\x00,1,40,0,0"],
    ),
    codes.E_PARAM_COUNT: (
        CommandRejected,
        [
            "MOVE,1,40,0",
            "MOVE,1,40,0,0,0",
            "STATUS,1",
            "POWER,100,10,10",
            "DELTA,1,2,3,4,5,6",
            "HELLO,1,2,3,4,5,6",
            "VEL,30,0,0,100,1,2",  # version 4's VEL has 7 parameters, version 3's 5: never 6
            "VEL,30,0,0,100,1,2,3,4",
        ],
    ),
    codes.E_NOT_INTEGER: (
        CommandRejected,
        ["MOVE,x,40,0,0", "MOVE,1.5,40,0,0", "MOVE,,40,0,0", "ROTATE,0x10,90"],
    ),
    codes.E_TIME: (
        OutOfRange,
        ["POWER,0,0,0,0,0", "POWER,30001,0,0,0,0", "VEL,0,0,0,0", "VEL,0,0,0,1001", "TELEM,5,1"],
    ),
    codes.E_SPEED: (
        OutOfRange,
        [
            "MOVE,10,29,0,0",
            "MOVE,10,101,0,0",
            "MOVE,10,0,0,0",
            "ROTATE,90,0",
            "ROTATE,90,900",
            "POWER,100,256,0,0,0",
            "VEL,101,0,0,100",
            "VEL,0,0,900,100",
            "DELTA,0,201,0,0,0",
        ],
    ),
    codes.E_ANGLE: (OutOfRange, ["ROTATE,30001,90", "ROTATE,-30001,90"]),
    codes.E_CURVATURE: (OutOfRange, ["MOVE,10,40,0,100", "MOVE,10,40,0,-100", "DELTA,0,0,0,200,0"]),
    codes.E_COURSE: (OutOfRange, ["MOVE,10,40,360,0", "MOVE,10,40,-360,0", "DELTA,0,0,720,0,0"]),
    codes.E_DISTANCE: (
        OutOfRange,
        ["MOVE,500,40,0,0", "MOVE,-500,40,0,0", "MOVE,29999,40,0,0", "DELTA,1000,0,0,0,0"],
    ),
    codes.E_SONAR_PERIOD: (OutOfRange, ["SONAR,1,59,0,0,0", "SONAR,1,1,0,0,0", "SONAR,1,30001,0,0,0"]),
    codes.E_RANGE16: (CommandRejected, ["MOVE,40000,40,0,0", "MOVE,1,-32769,0,0", "MODE,99999"]),
    codes.E_REPEAT: (OutOfRange, ["DELTA,0,0,0,0,30001", "DELTA,0,0,0,0,-1"]),
    codes.E_SONAR: (
        OutOfRange,
        ["SONAR,2,60,0,0,0", "SONAR,0,60,0,0,0", "SONAR,1,60,0,501,0", "SONAR,1,60,-1,0,0"],
    ),
    codes.E_CALIBRATION: (
        CalibrationRejected,
        ["CAL,0,1,0,2200", "CAL,0,0,0,0", "CAL,18,0,0,0", "CAL,1,0,-5,1000"],
    ),
    codes.E_UNSUPPORTED: (NotSupported, ["MODE,64", "MODE,128", "TELEM,100,256", "HELLO,1", "HELLO,0,1,5"]),
}


@pytest.mark.parametrize("code", sorted(CASES))
def test_error_code(client: RobotClient, code: int) -> None:
    kind, lines = CASES[code]
    before = client.status()
    for line in lines:
        (pending,) = client.submit_text(line)
        with pytest.raises(kind) as info:
            pending.result()
        assert info.value.code == code, line
        assert info.value.text == codes.TEXTS[code]
    assert client.status() == before  # a rejected command changes nothing


def test_error_then_next_command_fine(client: RobotClient) -> None:
    pendings = client.submit_text("FOO;MOVE,10,20,0,0;STATUS")
    with pytest.raises(CommandRejected):
        pendings[0].result()
    with pytest.raises(OutOfRange):
        pendings[1].result()
    assert pendings[2].result().keyword == "STATUS"


def test_queue_full(client: RobotClient) -> None:
    capacity = client.status().capacity
    # the first MOVE starts at once (it is not in the queue); then `capacity` fit; one more is refused
    pendings = [client.submit(Move(400, 30, 0, 0)) for _ in range(capacity + 2)]
    for p in pendings[:-1]:
        p.result()
    with pytest.raises(QueueFull) as info:
        pendings[-1].result()
    assert info.value.code == codes.E_QUEUE_FULL
    status = client.status()
    assert (status.state, status.queued) == (codes.STATE_MOVING, capacity)
    client.execute(Stop())
    status = client.status()
    assert (status.state, status.queued) == (codes.STATE_IDLE, 0)


# every command's numeric fields, each with valid neighbours (the motors' count from the client)
EXTREMES = {
    "MOVE": [10, 40, 0, 0],
    "DELTA": [0, 0, 10, 0, 1],
    "ROTATE": [90, 90],
    "VEL": [0, 0, 0, 200],
    "SONAR": [1, 60, 0, 0, 0],
    "TELEM": [100, 1],
    "MODE": [0],
}


INF_FIELDS = {("MOVE", 0), ("ROTATE", 0), ("DELTA", 4)}
"""Fields that take 32767 as INF (an endless MOVE or turn, a DELTA repeated for ever)."""


def _extreme_lines(motors: int) -> Iterator[tuple[str, bool]]:
    """Every command with one or two of its fields at -32768 or 32767 (each combination), the rest
    valid; with whether it may run (be taken as INF): only 32767 in fields that take INF."""
    fields = {**EXTREMES, "POWER": [100] + [0] * motors}
    for keyword, good in fields.items():
        for k in (1, 2):
            for where in itertools.combinations(range(len(good)), k):
                for values in itertools.product((-32768, 32767), repeat=k):
                    params = list(good)
                    for i, value in zip(where, values, strict=True):
                        params[i] = value
                    may_run = all(
                        v == 32767 and (keyword, i) in INF_FIELDS for i, v in zip(where, values, strict=True)
                    )
                    yield f"{keyword},{','.join(map(str, params))}", may_run


def test_the_extreme_16_bit_values_run_nothing_in_any_field(client: RobotClient) -> None:
    """-32768 has no positive twin in 16 bits (``abs`` of it stays negative on a 16-bit int), and two
    of them squared overflow a 32-bit sum (VEL's speed, 2^31): in any one or two fields of any
    command, they and 32767 (INF, where a field takes it) are refused or taken as INF, never wrapped
    into a speed or a power."""
    motors = len(client.status().powers)
    before = client.status()
    for line, may_run in _extreme_lines(motors):
        (pending,) = client.submit_text(line)
        try:
            pending.result()
        except ControllerError:
            continue
        assert may_run, line
        client.stop()  # an INF motion asked: gone again
    client.stop()
    assert client.status().powers == before.powers == tuple([0] * motors)
