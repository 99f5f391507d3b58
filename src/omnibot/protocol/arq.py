"""Sequence numbers, acknowledgement and retry for binary frames (MicroPython-safe, no timers).

Both directions use the same rules (docs/protocol.md, "Sequence numbers, acknowledgement, retry"):

* A sequenced frame carries seq 1..255 (wrapping to 1). The sender (:class:`Sender`) sends a frame
  only if its seq is less than ``window`` after the oldest unacknowledged one (the window its
  receiver takes: a controller announces it in its HELLO reply). One timer runs for the oldest
  unacknowledged frame, restarted whenever it is acknowledged (the line makes progress): when it
  runs out (``timeout_ms``), the sender sends the oldest frame again and every one after it (the
  receiver dropped those as out of order: go-back-N). After ``retries`` such retransmissions of
  the same oldest frame it gives up on it and on every later frame still pending, and marks its
  next frame SYNC. A full window waiting on the line (32 frames: 44 ms of a 115200-baud line, more
  with pauses) therefore never times out while replies keep coming.
* Commands are acknowledged by their reply (same seq), events by an ACK frame (same seq).
* The receiver (:class:`Receiver`) takes frames strictly in order: the expected seq is NEW
  (execute/deliver, then reply/ACK); one of the last ``window`` seqs is a DUPLICATE (re-send the
  cached reply / re-ACK, never execute twice); anything else, seq 0 included, is OUT_OF_ORDER and
  dropped without an answer, so the sender's retransmissions restore the order. On a line that
  keeps the frames' order a frame arrives at most W_s behind and W_s - 1 ahead of the expected seq
  (W_s: its sender's window); with W_s <= ``window`` <= codes.WINDOW_LIMIT the two ranges never
  meet in the 255 seqs, so a duplicate is never taken for a new frame nor a new one for a duplicate.
* A SYNC frame that is not a duplicate is NEW whatever seq the receiver expected: the sender
  abandoned every earlier frame. The sender sends nothing after a SYNC frame until it is
  acknowledged, so it starts the window again from a seq the receiver has taken. STOP and HELLO
  are always sent SYNC; HELLO also resets the receiver (:meth:`Receiver.reset`) before it is
  classified, which starts a session.

Time is a number of milliseconds passed in by the caller (``now``); nothing here reads a clock.
"""

from omnibot.protocol import codes

NEW = 0
DUPLICATE = 1
OUT_OF_ORDER = 2


def seq_next(seq: int, top: int = codes.SEQ_MAX) -> int:
    """The sequence number after ``seq`` (1..top, ``top`` wraps to 1: binary 255, text tags 9999)."""
    return seq % top + 1


def seq_back(expected: int, seq: int, top: int = codes.SEQ_MAX) -> int:
    """How many frames before ``expected`` the frame ``seq`` is (0 = it is the expected one)."""
    return (expected - seq) % top


class _Out:
    """A frame awaiting acknowledgement."""

    def __init__(self, seq: int, frame: bytes, sync: bool) -> None:
        self.seq = seq
        self.frame = frame
        self.resent = 0  # retransmissions while it was the oldest
        self.sync = sync


class Sender:
    """Outgoing sequenced frames awaiting acknowledgement.

    Use: ``seq, sync = tx.allocate()``; encode the frame with them; ``tx.track(seq, frame, now)``;
    write it. On a reply/ACK call ``tx.ack(seq)``. Call ``tx.poll(now)`` often and write the frames
    it returns. ``tx.take_failed()`` lists seqs that will never be acknowledged.
    """

    def __init__(
        self,
        window: int = codes.WINDOW,
        timeout_ms: int = codes.RETRY_TIMEOUT_MS,
        retries: int = codes.RETRIES,
        first_seq: int = 1,
        max_timeout_ms: int = 0,
        top: int = codes.SEQ_MAX,
        fast: int = codes.RETRIES,
    ) -> None:
        self.window = window
        self.top = top  # the largest seq (binary 255; sequenced text's tags 9999)
        self.timeout_ms = timeout_ms
        self.retries = retries
        # above timeout_ms: the retransmissions after the first ``fast`` wait twice the last
        self.max_timeout_ms = max_timeout_ms
        self.fast = fast
        self._next = first_seq
        self._sync = True
        self._sync_seq = 0  # the seq just allocated with SYNC (0: the last one had none)
        self._pending: list[_Out] = []
        self._deadline = 0  # when the oldest pending frame is due again
        self._progress = False  # the oldest was acknowledged since the last poll: restart the timer
        self._failed: list[int] = []

    def ready(self) -> bool:
        """True if another frame may be sent now: its seq is less than ``window`` after the oldest
        unacknowledged one (so a receiver always tells a retransmission from a new frame), and
        that one is no SYNC frame: nothing follows a SYNC frame before it is acknowledged, so a
        line that loses everything costs one seq per give-up, not a window of them."""
        if not self._pending:
            return True
        oldest = self._pending[0]
        return not oldest.sync and seq_back(self._next, oldest.seq, self.top) < self.window

    def idle(self) -> bool:
        """Nothing waits for its acknowledgement and no give-up is still to be taken: :meth:`poll`
        and :meth:`take_failed` have nothing to do, whenever they are called."""
        return not self._pending and not self._failed

    @property
    def needs_sync(self) -> bool:
        """True if the next frame will be SYNC: the first one, or the first after a give-up."""
        return self._sync

    def pending(self) -> "list[int]":
        """Seqs sent and not yet acknowledged, oldest first."""
        return [p.seq for p in self._pending]

    def allocate(self, sync: bool = False) -> "tuple[int, bool]":
        """Seq and SYNC flag for the next frame.

        ``sync=True`` (STOP, HELLO) abandons every pending frame first. A SYNC flag is also given
        to the first frame and to the first frame after a give-up. Raises ValueError if the
        window is full.
        """
        if sync:
            self._abandon(0)
        elif not self.ready():
            raise ValueError("send window full")
        seq = self._next
        self._next = seq_next(seq, self.top)
        flag = sync or self._sync
        self._sync = False
        self._sync_seq = seq if flag else 0
        return seq, flag

    def track(self, seq: int, frame: bytes, now: int) -> None:
        """Remember a frame just written, for retransmission until it is acknowledged."""
        if not self._pending:
            self._deadline = now + self.timeout_ms
            self._progress = False
        self._pending.append(_Out(seq, frame, seq == self._sync_seq))

    def ack(self, seq: int) -> bool:
        """The peer acknowledged ``seq``; False if it was not pending (late or duplicate ack)."""
        for i in range(len(self._pending)):
            if self._pending[i].seq == seq:
                self._pending.pop(i)
                self._progress = self._progress or i == 0
                return True
        return False

    def poll(self, now: int) -> "list[bytes]":
        """Frames to retransmit at time ``now``: none while the oldest keeps being acknowledged
        within ``timeout_ms``, else every pending frame, oldest first; gives up after ``retries``
        retransmissions of the same oldest frame."""
        if not self._pending:
            return []
        if self._progress:
            self._progress = False
            self._deadline = now + self.timeout_ms
            return []
        if now < self._deadline:
            return []
        head = self._pending[0]
        if head.resent >= self.retries:
            self._abandon(0)
            return []
        head.resent += 1
        self._deadline = now + self._wait(head.resent)
        return [entry.frame for entry in self._pending]

    def _wait(self, resent: int) -> int:
        """ms to wait for progress after the ``resent``-th retransmission of the oldest frame:
        ``timeout_ms`` for the first ``fast`` (a lossy line's lost byte costs one such wait), then,
        with ``max_timeout_ms`` above it, twice the wait before, up to that (a line, controller or
        host stalled for seconds costs no call)."""
        late = resent - self.fast
        if late < 0 or self.max_timeout_ms <= self.timeout_ms:
            return self.timeout_ms
        wait = self.timeout_ms << (late + 1)
        return wait if wait < self.max_timeout_ms else self.max_timeout_ms

    def budget_ms(self) -> int:
        """ms from sending a frame that is the oldest until it is given up without progress."""
        total = self.timeout_ms
        for resent in range(1, self.retries + 1):
            total += self._wait(resent)
        return total

    def take_failed(self) -> "list[int]":
        """Seqs given up on or abandoned since the last call (they get no reply), oldest first."""
        failed = self._failed
        self._failed = []
        return failed

    def _abandon(self, start: int) -> None:
        if start < len(self._pending):
            for entry in self._pending[start:]:
                self._failed.append(entry.seq)
            self._pending = self._pending[:start]
            self._sync = True


class Receiver:
    """Incoming sequenced frames: in-order acceptance, duplicate detection, cached replies."""

    def __init__(self, window: int = codes.WINDOW, top: int = codes.SEQ_MAX) -> None:
        self.window = window
        self.top = top  # the largest seq (binary 255; sequenced text's tags 9999)
        self.expected = 0  # 0: nothing received yet, the first frame is accepted whatever its seq
        self._replies: dict[int, bytes] = {}

    def reset(self) -> None:
        """Start a new session (on HELLO): accept the next frame whatever its seq."""
        self.expected = 0
        self._replies = {}

    def classify(self, seq: int, sync: bool = False) -> int:
        """NEW, DUPLICATE or OUT_OF_ORDER for an incoming frame; NEW advances the expected seq.

        Seq 0 is no sequence number (TEL, which is never classified): a command or event carrying
        it is OUT_OF_ORDER, so a replayed frame can never run twice."""
        if seq == 0:
            return OUT_OF_ORDER
        if self.expected:
            back = seq_back(self.expected, seq, self.top)
            if 0 < back <= self.window:
                return DUPLICATE
            if back and not sync:
                return OUT_OF_ORDER
        self.expected = seq_next(seq, self.top)
        for old in list(self._replies):
            if not 0 < seq_back(self.expected, old, self.top) <= self.window:
                del self._replies[old]
        return NEW

    def remember(self, seq: int, reply: bytes) -> None:
        """Keep the reply frame sent for ``seq``, to answer a duplicate of it."""
        self._replies[seq] = reply

    def reply_for(self, seq: int) -> "bytes | None":
        """The reply sent for a duplicate ``seq``, if it is still kept."""
        return self._replies.get(seq)
