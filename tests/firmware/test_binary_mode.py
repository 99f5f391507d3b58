"""Binary mode (MODE bit 2): switching, replies, duplicates, event retries, TEL, switching back."""

from __future__ import annotations

from omnibot.protocol import binary, codes, frame
from omnibot.protocol.binary import Packet
from omnibot.protocol.messages import ErrorReply, HelloReply, Idle, Ok, StatusReply, Telemetry
from tests.firmware.conftest import Rig, make_rig
from tests.firmware.fakehal import advance


def cmd(type_id: int, seq: int, *ints: int, sync: bool = False) -> bytes:
    return frame.encode_message(type_id, seq, list(ints), b"", sync)


def packets(data: bytes) -> list[Packet]:
    dec = binary.BinaryDecoder()
    out = list(dec.feed(data))
    assert all(isinstance(p, Packet) for p in out), out
    return out  # type: ignore[return-value]


def run(rig: Rig, ms: int) -> None:
    advance(rig.ctrl, rig.hal, ms)


def start(rig: Rig) -> None:
    """MODE,4 and the session-starting HELLO frame in one chunk, as a host would send them."""
    rig.hal.send("MODE,4\r\n")
    rig.hal.rx += cmd(codes.HELLO, 1, 2, sync=True)
    rig.ctrl.poll()
    out = rig.hal.take()
    assert out.startswith(b"OK\r\n")
    (p,) = packets(out[4:])
    assert p.message == HelloReply(2, "omni4", 4, codes.WINDOW) and p.seq == 1


def test_switch_and_hello() -> None:
    rig = make_rig()
    start(rig)
    assert rig.ctrl.mode == codes.MODE_BINARY


def test_replies_duplicates_and_order() -> None:
    rig = make_rig()
    start(rig)
    hal = rig.hal
    hal.rx = cmd(codes.MOVE, 2, 100, 40, 0, 0) + cmd(codes.MOVE, 3, 100, 40, 90, 0)
    rig.ctrl.poll()
    out = hal.take()
    assert [(p.message, p.seq) for p in packets(out)] == [(Ok(), 2), (Ok(), 3)]
    assert len(rig.ctrl.queue) == 1
    hal.rx = cmd(codes.MOVE, 3, 100, 40, 90, 0)  # a retransmission: answered again, not run again
    rig.ctrl.poll()
    assert [(p.message, p.seq) for p in packets(hal.take())] == [(Ok(), 3)]
    assert len(rig.ctrl.queue) == 1
    hal.rx = cmd(codes.STATUS, 9)  # out of order: dropped without an answer
    rig.ctrl.poll()
    assert hal.take() == b""
    hal.rx = cmd(codes.STATUS, 4)
    rig.ctrl.poll()
    (p,) = packets(hal.take())
    assert p.message == StatusReply(0, 1, 16, 4, (0, 88, 0, -88), (100, 40, 0, 0)) and p.seq == 4


def test_errors_in_binary() -> None:
    rig = make_rig()
    start(rig)
    hal = rig.hal
    bad = bytearray(cmd(codes.STATUS, 2))
    bad[3] ^= 0x10  # corrupted: dropped, no answer
    hal.rx = bytes(bad)
    rig.ctrl.poll()
    assert hal.take() == b""
    hal.rx = cmd(20, 2) + cmd(codes.MOVE, 3, 1, 40, 0) + cmd(codes.MOVE, 4, 40000, 40, 0, 0)
    hal.rx += cmd(codes.MOVE, 5, 600, 40, 0, 0)
    rig.ctrl.poll()
    got = [(p.message, p.seq) for p in packets(hal.take())]
    # the text is left empty in frames: the code table's text applies (docs/protocol.md)
    assert got == [
        (ErrorReply(codes.E_UNKNOWN, ""), 2),
        (ErrorReply(codes.E_PARAM_COUNT, ""), 3),
        (ErrorReply(codes.E_RANGE16, ""), 4),
        (ErrorReply(codes.E_DISTANCE, ""), 5),
    ]


def test_events_are_retried_until_acked() -> None:
    rig = make_rig(progress_tolerance=0.0)  # the fake wheels never turn: no WARN 17 after the IDLE
    start(rig)
    hal = rig.hal
    hal.rx = cmd(codes.MOVE, 2, 2, 40, 0, 0)
    rig.ctrl.poll()
    hal.take()
    run(rig, 50)
    (idle,) = packets(hal.take())
    assert isinstance(idle.message, Idle) and idle.seq >= 1
    run(rig, 49)
    assert hal.take() == b""
    run(rig, 1)  # 50 ms without an ACK: sent again
    (again,) = packets(hal.take())
    assert again.seq == idle.seq
    hal.rx = frame.encode_message(codes.ACK, idle.seq)
    rig.ctrl.poll()
    run(rig, 300)
    assert hal.take() == b""


def test_telemetry_frames() -> None:
    rig = make_rig()
    start(rig)
    rig.hal.rx = cmd(codes.TELEM, 2, 100, codes.TEL_POWER | codes.TEL_QUEUE)
    rig.ctrl.poll()
    rig.hal.take()
    run(rig, 100)
    (p,) = packets(rig.hal.take())
    assert p.seq == 0
    assert p.message == Telemetry(100, powers=(0, 0, 0, 0), queue=(1, 0))


def test_back_to_text_in_the_same_chunk() -> None:
    rig = make_rig()
    start(rig)
    rig.hal.rx = cmd(codes.MODE, 2, 0) + b"STATUS\n"
    rig.ctrl.poll()
    out = rig.hal.take()
    end = out.rindex(b"\x00") + 1
    (p,) = packets(out[:end])
    assert p.message == Ok() and p.seq == 2
    assert out[end:] == b"STATUS,1,0,16,0;POWER,0,0,0,0;MOVE,0,0,0,0\r\n"


def test_replayed_frames_run_once() -> None:
    """Seq 0 is no sequence number: a command carrying it is dropped, SYNC or not; every other
    command frame runs once however often it arrives (its kept reply answers the copies)."""
    rig = make_rig()
    start(rig)
    hal = rig.hal
    for sync in (False, True):
        zero = cmd(codes.MOVE, 0, 100, 40, 0, 0, sync=sync)
        hal.rx = zero + zero
        rig.ctrl.poll()
        assert hal.take() == b""
        assert not rig.ctrl.executor.moving and len(rig.ctrl.queue) == 0
    moves = [cmd(codes.MOVE, seq, 100, 40, 0, 0) for seq in range(2, 6)]
    for i, move in enumerate(moves):
        hal.rx = move + move + moves[max(i - 1, 0)] + move
        rig.ctrl.poll()
        assert {(p.message, p.seq) for p in packets(hal.take())} == {(Ok(), 2 + max(i - 1, 0)), (Ok(), 2 + i)}
        assert len(rig.ctrl.queue) == i  # the first runs, the others wait: one each
    hal.rx = b"".join(moves) * 2
    rig.ctrl.poll()
    assert [p.seq for p in packets(hal.take())] == [2, 3, 4, 5] * 2
    assert len(rig.ctrl.queue) == 3
