"""Acknowledgement and retry: Sender and Receiver alone, then both over a lossy link."""

from __future__ import annotations

import itertools

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from omnibot.protocol import arq, binary, codes, text
from omnibot.protocol import messages as m


def test_first_frame_is_sync_and_seqs_wrap() -> None:
    tx = arq.Sender(window=300, first_seq=254)
    got = [tx.allocate() for _ in range(4)]
    assert got == [(254, True), (255, False), (1, False), (2, False)]
    assert arq.seq_next(255) == 1 and arq.seq_back(1, 255) == 1 and arq.seq_back(7, 7) == 0


def session(**kwargs: int) -> arq.Sender:
    """A Sender whose first frame (seq 1, SYNC) has been acknowledged: the next seq is 2."""
    tx = arq.Sender(**kwargs)
    assert tx.allocate() == (1, True)
    tx.track(1, b"hello", 0)
    assert not tx.ready()  # nothing follows a SYNC frame before its acknowledgement
    assert tx.ack(1) and tx.ready()
    return tx


def test_window_limits_unacknowledged_frames() -> None:
    tx = session(window=2)
    for now in (0, 1):
        seq, _ = tx.allocate()
        tx.track(seq, b"f%d" % seq, now)
    assert not tx.ready()
    with pytest.raises(ValueError):
        tx.allocate()
    assert tx.ack(2) and not tx.ack(2) and not tx.ack(99)
    assert tx.ready() and tx.pending() == [3]


def test_window_spans_from_the_oldest_unacknowledged_frame() -> None:
    tx = session(window=3)
    for now in range(3):
        seq, _ = tx.allocate()
        tx.track(seq, b"x", now)
    tx.ack(3)
    tx.ack(4)
    assert tx.pending() == [2] and not tx.ready()  # seq 5 would be 3 after the pending seq 2
    tx.ack(2)
    assert tx.ready()


def test_timeout_retransmits_then_gives_up() -> None:
    tx = session(window=4, timeout_ms=50, retries=2)
    for now in (0, 10):
        seq, _ = tx.allocate()
        tx.track(seq, b"f%d" % seq, now)
    assert tx.poll(49) == []
    assert tx.poll(50) == [b"f2", b"f3"]  # the oldest and every frame after it (go-back-N)
    assert tx.poll(60) == [] and tx.poll(99) == []
    assert tx.poll(100) == [b"f2", b"f3"]
    assert tx.take_failed() == []
    assert tx.poll(150) == []  # f2 out of retries: it and every later frame are given up
    assert tx.take_failed() == [2, 3] and tx.take_failed() == []
    assert tx.pending() == [] and tx.allocate() == (4, True)  # the next frame resynchronises


def test_idle_while_nothing_waits_and_no_give_up_is_untaken() -> None:
    tx = session(window=4, timeout_ms=50, retries=0)
    assert tx.idle()
    seq, _ = tx.allocate()
    tx.track(seq, b"f", 0)
    assert not tx.idle()
    assert tx.poll(50) == [] and tx.pending() == [] and not tx.idle()  # given up: still to be taken
    assert tx.take_failed() == [seq] and tx.idle()


def test_progress_restarts_the_timer() -> None:
    """While the oldest frame keeps being acknowledged, a full window waiting on the line is not
    sent again (32 frames take 44 ms of a 115200-baud line); an acknowledgement of a later frame
    alone is no progress (the oldest's reply was lost)."""
    tx = session(window=8, timeout_ms=50, retries=1)
    for seq in range(2, 6):
        assert tx.allocate() == (seq, False)
        tx.track(seq, b"f%d" % seq, 0)
    assert tx.ack(2) and tx.poll(45) == []  # acknowledged at 40..45: due again at 95
    assert tx.poll(94) == [] and tx.ack(3) and tx.poll(94) == []  # due at 144
    assert tx.poll(143) == [] and tx.poll(144) == [b"f4", b"f5"]
    assert tx.ack(5) and tx.poll(193) == []  # 5 before 4: not the oldest, no restart
    assert tx.poll(194) == [] and tx.take_failed() == [4]  # f4's second time out: given up
    assert tx.pending() == []


def test_retransmissions_count_for_the_oldest_frame_only() -> None:
    """A frame sent again only because an older one was lost has not failed itself: it gets the
    full budget once it is the oldest."""
    tx = session(window=8, timeout_ms=50, retries=2)
    for seq in (2, 3):
        tx.allocate()
        tx.track(seq, b"f%d" % seq, 0)
    assert tx.poll(50) == [b"f2", b"f3"] and tx.poll(100) == [b"f2", b"f3"]
    assert tx.ack(2) and tx.poll(105) == []  # f3 the oldest now, sent twice but never timed out
    assert tx.poll(155) == [b"f3"] and tx.poll(205) == [b"f3"] and tx.take_failed() == []
    assert tx.poll(255) == [] and tx.take_failed() == [3]


def test_nothing_follows_an_unacknowledged_sync_frame() -> None:
    """After a give-up only the SYNC frame goes out until it is acknowledged: a line that loses
    everything costs one seq per give-up (0.55 s), so the seqs lapping round to the receiver's
    duplicates takes minutes, not a few windows' worth of give-ups (docs/protocol.md)."""
    tx = session(window=32, timeout_ms=50, retries=0)
    for now in range(5):
        seq, _ = tx.allocate()
        tx.track(seq, b"x", now)
    tx.poll(60)  # no retries: all five given up
    assert tx.take_failed() == [2, 3, 4, 5, 6]
    used = []
    for lap in range(3):  # each SYNC frame lost too: one seq a give-up
        seq, sync = tx.allocate()
        tx.track(seq, b"sync", 100 * lap)
        assert sync and not tx.ready()
        with pytest.raises(ValueError):
            tx.allocate()
        tx.poll(100 * lap + 60)
        used += tx.take_failed()
    assert used == [7, 8, 9]
    seq, sync = tx.allocate()
    tx.track(seq, b"sync", 1000)
    assert (seq, sync) == (10, True) and tx.ack(10) and tx.ready()
    assert tx.allocate() == (11, False)


def test_ack_stops_retransmission() -> None:
    tx = arq.Sender(timeout_ms=50, retries=3)
    seq, _ = tx.allocate()
    tx.track(seq, b"f", 0)
    assert tx.poll(50) == [b"f"]
    tx.ack(seq)
    assert tx.poll(1000) == [] and tx.take_failed() == []


def test_the_hosts_retransmissions_turn_patient_after_the_fast_ones() -> None:
    """The host's sender: codes.RETRIES - 1 retransmissions 50 ms apart (a lossy line's lost byte
    costs 50 ms, as the controller's), then waits of 100, 200 and 400 ms up to its HOST_RETRIES
    (3.2 s in all: a stalled line costs no call); the next frame starts fast again."""
    tx = arq.Sender(retries=codes.HOST_RETRIES, max_timeout_ms=codes.HOST_RETRY_TIMEOUT_MAX_MS)
    first, _ = tx.allocate()
    tx.track(first, b"a", 0)
    sent = [now for now in range(0, 5000) if tx.poll(now)]
    assert sent[:10] == list(range(50, 550, 50))
    assert [b - a for a, b in itertools.pairwise(sent)][9:] == [100, 200, 400, 400, 400, 400, 400]
    assert tx.take_failed() == [first] and tx.budget_ms() == 3200 == sent[-1] + 400
    second, _ = tx.allocate()
    tx.track(second, b"b", 5000)
    assert [now for now in range(5000, 5200) if tx.poll(now)] == [5050, 5100, 5150]
    assert arq.Sender().budget_ms() == 550  # the controller's: 10 retransmissions 50 ms apart


def test_sync_abandons_pending_frames() -> None:
    tx = session()
    for now in range(3):
        seq, _ = tx.allocate()
        tx.track(seq, b"x", now)
    assert tx.allocate(sync=True) == (5, True)
    assert tx.take_failed() == [2, 3, 4] and tx.pending() == []


def test_receiver_in_order_duplicate_and_out_of_order() -> None:
    rx = arq.Receiver(window=2)
    assert rx.classify(10) == arq.NEW  # first frame: any seq
    assert rx.classify(11) == arq.NEW
    assert rx.classify(11) == arq.DUPLICATE
    assert rx.classify(10) == arq.DUPLICATE
    assert rx.classify(9) == arq.OUT_OF_ORDER  # older than the window
    assert rx.classify(13) == arq.OUT_OF_ORDER  # 12 is missing
    assert rx.classify(12) == arq.NEW
    assert rx.classify(13) == arq.NEW
    assert rx.classify(0) == arq.OUT_OF_ORDER and rx.expected == 14  # no seq: never run
    assert rx.classify(0, sync=True) == arq.OUT_OF_ORDER and rx.expected == 14
    assert rx.classify(40, sync=True) == arq.NEW and rx.expected == 41
    assert rx.classify(40, sync=True) == arq.DUPLICATE  # a retransmitted SYNC frame
    rx.reset()
    assert rx.classify(40) == arq.NEW


def test_receiver_wraps_at_255() -> None:
    rx = arq.Receiver()
    assert [rx.classify(s) for s in (254, 255, 1, 255)] == [arq.NEW, arq.NEW, arq.NEW, arq.DUPLICATE]


def test_cached_replies_cover_the_window() -> None:
    rx = arq.Receiver(window=2)
    for seq in (1, 2, 3):
        assert rx.classify(seq) == arq.NEW
        rx.remember(seq, b"r%d" % seq)
    assert rx.classify(3) == arq.DUPLICATE and rx.reply_for(3) == b"r3"
    assert rx.reply_for(2) == b"r2"
    assert rx.classify(4) == arq.NEW
    assert rx.reply_for(2) is None and rx.reply_for(3) == b"r3"


def seq_at(expected: int, offset: int) -> int:
    """The seq ``offset`` frames after (before, if negative) ``expected``, wrapping in 1..255."""
    return (expected - 1 + offset) % codes.SEQ_MAX + 1


def offset_of(expected: int, seq: int) -> int:
    """How far ``seq`` is after ``expected`` (negative: before), taking the nearer way round."""
    back = arq.seq_back(expected, seq)
    return -back if back <= codes.SEQ_MAX // 2 else codes.SEQ_MAX - back


def misread(receive_window: int, send_window: int) -> list[tuple[int, int]]:
    """Every (expected seq, offset) whose frame a receiver classifies wrongly, over all the offsets
    an in-order line can bring with the sender's window: -send_window (a duplicate) .. -1 are
    DUPLICATE, 0 NEW, 1 .. send_window - 1 (after a lost frame) OUT_OF_ORDER."""
    wrong = []
    for expected in range(1, codes.SEQ_MAX + 1):
        for offset in range(-send_window, send_window):
            rx = arq.Receiver(window=receive_window)
            rx.expected = expected
            want = arq.DUPLICATE if offset < 0 else arq.NEW if offset == 0 else arq.OUT_OF_ORDER
            if rx.classify(seq_at(expected, offset)) != want:
                wrong.append((expected, offset))
    return wrong


@pytest.mark.parametrize(
    ("receive", "send"),
    [
        (codes.WINDOW_MIN, codes.WINDOW_MIN),  # the UNO's commands and events
        (codes.WINDOW, codes.WINDOW),  # the MicroPython firmware's commands; any controller's events
        (codes.WINDOW_LIMIT, codes.WINDOW),  # the host's commands to a controller of the largest window
        (codes.WINDOW_LIMIT, codes.WINDOW_LIMIT),
    ],
)
def test_sequence_space_tells_duplicates_from_new_frames(receive: int, send: int) -> None:
    assert misread(receive, send) == []


def test_windows_past_the_limit_would_take_new_frames_for_duplicates() -> None:
    assert 2 * codes.WINDOW_LIMIT <= codes.SEQ_MAX < 2 * (codes.WINDOW_LIMIT + 1)
    wrong = misread(codes.WINDOW_LIMIT + 1, codes.WINDOW_LIMIT + 1)
    assert wrong and {offset for _, offset in wrong} == {codes.WINDOW_LIMIT}  # 127 ahead = 128 back


class Controller:
    """A minimal controller: executes each command once and replies OK (the reply is the ack).

    With ``send_window`` it also checks the premise of the sequence-space argument: a frame without
    SYNC arrives at most that many behind, and fewer ahead of, the seq it expects."""

    def __init__(self, window: int = codes.WINDOW, send_window: int = 0) -> None:
        self.rx = arq.Receiver(window)
        self.send_window = send_window
        self.executed: list[m.Message] = []

    def receive(self, wire: bytes) -> bytes | None:
        _, packet = binary.decode(wire)
        assert isinstance(packet, binary.Packet)
        if isinstance(packet.message, m.Hello):
            self.rx.reset()
        if self.send_window and self.rx.expected and not packet.sync:
            assert -self.send_window <= offset_of(self.rx.expected, packet.seq) < self.send_window
        verdict = self.rx.classify(packet.seq, packet.sync)
        if verdict == arq.DUPLICATE:
            return self.rx.reply_for(packet.seq)  # re-ack, do not re-execute
        if verdict == arq.OUT_OF_ORDER:
            return None
        self.executed.append(packet.message)
        reply = binary.encode(m.Ok(), packet.seq)
        self.rx.remember(packet.seq, reply)
        return reply


def test_duplicate_command_is_re_acknowledged_not_re_executed() -> None:
    ctl = Controller()
    tx = arq.Sender(timeout_ms=50)
    seq, sync = tx.allocate()
    wire = binary.encode(m.Move(2, 40, 0, 0), seq, sync=sync)
    tx.track(seq, wire, 0)
    first = ctl.receive(wire)  # the reply is lost on the way back
    assert first is not None
    [again] = tx.poll(50)
    reply = ctl.receive(again)
    assert reply == first and ctl.executed == [m.Move(2, 40, 0, 0)]
    tx.ack(binary.decode(reply)[1].seq)  # type: ignore[union-attr]
    assert tx.pending() == []


@settings(max_examples=150, deadline=None)
@given(
    st.lists(st.booleans(), min_size=1, max_size=400),  # True: the frame is lost
    st.integers(5, 300),  # up to past the wrap of the seqs
    st.integers(0, 3),
    st.sampled_from([codes.WINDOW_MIN, codes.WINDOW]),
)
def test_lossy_link_executes_each_command_at_most_once_and_in_order(
    losses: list[bool], count: int, retries: int, window: int
) -> None:
    """Commands go out through a link that drops frames (both ways) as ``losses`` says.

    Every command is either acknowledged or reported failed; acknowledged ones ran exactly once;
    whatever ran, ran once and in the order sent; no frame arrived further from the expected seq
    than the sequence-space argument allows.
    """
    loss = itertools.cycle(losses)
    ctl = Controller(window, send_window=window)
    tx = arq.Sender(window=window, timeout_ms=50, retries=retries)
    commands = [m.Move(i, 40, 0, 0) for i in range(count)]
    sent: dict[int, m.Move] = {}
    acked: list[m.Move] = []
    failed: list[m.Move] = []
    wire_out: list[bytes] = []
    now = 0
    queue = list(commands)
    while queue or tx.pending():
        while queue and tx.ready():
            cmd = queue.pop(0)
            seq, sync = tx.allocate()
            frame = binary.encode(cmd, seq, sync=sync)
            sent[seq] = cmd
            tx.track(seq, frame, now)
            wire_out.append(frame)
        wire_out.extend(tx.poll(now))
        for frame in wire_out:
            if next(loss):
                continue
            reply = ctl.receive(frame)
            if reply is not None and not next(loss):
                seq = binary.decode(reply)[1].seq  # type: ignore[union-attr]
                if tx.ack(seq):
                    acked.append(sent[seq])
        wire_out = []
        failed.extend(sent[s] for s in tx.take_failed())
        now += 10
        assert now < 100_000
    assert sorted(acked + failed, key=lambda c: c.distance) == commands
    assert set(acked) <= set(ctl.executed)
    ran = [c.distance for c in ctl.executed if isinstance(c, m.Move)]
    assert len(ran) == len(ctl.executed)
    assert ran == sorted(set(ran))


def test_duplicate_event_is_re_acked_and_delivered_once() -> None:
    ctl_tx = arq.Sender(timeout_ms=50)
    host_rx = arq.Receiver()
    delivered: list[m.Message] = []
    seq, sync = ctl_tx.allocate()
    event = binary.encode(m.Range(1, 35), seq, sync=sync)
    ctl_tx.track(seq, event, 0)
    acks: list[bytes] = []
    for wire in (event, *ctl_tx.poll(50)):  # the first ACK is lost, the event comes again
        packet = binary.decode(wire)[1]
        assert isinstance(packet, binary.Packet)
        if host_rx.classify(packet.seq, packet.sync) == arq.NEW:
            delivered.append(packet.message)
        acks.append(binary.encode(m.Ack(), packet.seq))
    assert delivered == [m.Range(1, 35)] and acks[0] == acks[1]
    ack = binary.decode(acks[1])[1]
    assert isinstance(ack, binary.Packet) and ctl_tx.ack(ack.seq) and ctl_tx.pending() == []


def test_text_tags_wrap_at_their_own_top() -> None:
    """Sequenced text's tags run 1..9999: the same rules in that space (window 8)."""
    top = codes.TEXT_SEQ_MAX
    assert top == text.TAG_MAX  # the sequence space is the tags' own (codes stands alone for the boards)
    assert arq.seq_next(top, top) == 1 and arq.seq_back(1, top, top) == 1
    rx = arq.Receiver(codes.TEXT_SEQ_WINDOW, top)
    assert rx.classify(9998) == arq.NEW and rx.classify(9999) == arq.NEW and rx.classify(1) == arq.NEW
    assert rx.classify(9999) == arq.DUPLICATE and rx.classify(3) == arq.OUT_OF_ORDER
    assert rx.classify(2) == arq.NEW and rx.expected == 3
    tx = arq.Sender(window=codes.TEXT_SEQ_WINDOW, first_seq=top, top=top)
    assert [tx.allocate()[0] for _ in range(3)] == [top, 1, 2]
