"""Binary mode (MODE bit 2): frames over the same UART with sequence numbers, ACKs and retries.

Uses the protocol package's MicroPython-safe layers as they are: :mod:`omnibot.protocol.frame`
(length, COBS, CRC-32, varints) and :mod:`omnibot.protocol.arq` (window, retry, duplicate replies).
Replies carry the answered command's seq and are kept for duplicates; events get their own seq and
are retransmitted until the host ACKs them (backlogged while the window is full); TEL has seq 0.
Both windows are ``window`` (codes.WINDOW, 32, by default): the HELLO reply announces it, and the
host takes events with a window of codes.WINDOW, so it may be WINDOW_MIN..WINDOW. 32 kept replies
of at most 255 bytes (an OK: 11) fit a board's heap.
"""

from omnibot.protocol import arq, codes, frame

BACKLOG_MAX = 16  # events waiting for the send window; more are dropped


class BinaryLink:
    """The controller's binary session state."""

    def __init__(self, write: "Callable[[bytes], None]", window: int = codes.WINDOW) -> None:
        self._write = write
        self.window = window  # taken and announced from the next session on (WINDOW_MIN..WINDOW)
        self.decoder = frame.FrameDecoder()
        self.tx = arq.Sender(window=window)
        self.rx = arq.Receiver(window=window)
        self._backlog: list[tuple[int, list[int], bytes]] = []

    def reset(self) -> None:
        """A new session: forget frames, sequence state and waiting events."""
        self.decoder.reset()
        self.tx = arq.Sender(window=self.window)
        self.rx = arq.Receiver(window=self.window)
        self._backlog = []

    def reply(self, type_id: int, seq: int, ints: "list[int]", text: bytes = b"") -> None:
        """Send a reply frame with the command's ``seq``, remembered so a repeated command gets it again."""
        data = frame.encode_message(type_id, seq, ints, text)
        self.rx.remember(seq, data)
        self._write(data)

    def event(self, type_id: int, ints: "list[int]", now_ms: int, text: bytes = b"") -> None:
        """Send an event frame reliably; while the send window is full it waits in a bounded backlog
        (dropped beyond BACKLOG_MAX)."""
        if self._backlog or not self.tx.ready():
            if len(self._backlog) < BACKLOG_MAX:
                self._backlog.append((type_id, ints, text))
            return
        self._send_event(type_id, ints, text, now_ms)

    def telemetry(self, ints: "list[int]") -> None:
        """Send a telemetry frame (seq 0, never acknowledged or repeated)."""
        self._write(frame.encode_message(codes.TEL, 0, ints))

    def poll(self, now_ms: int) -> None:
        """Retransmit what is due and send waiting events as the window frees."""
        for data in self.tx.poll(now_ms):
            self._write(data)
        self.tx.take_failed()
        while self._backlog and self.tx.ready():
            type_id, ints, text = self._backlog.pop(0)
            self._send_event(type_id, ints, text, now_ms)

    def _send_event(self, type_id: int, ints: "list[int]", text: bytes, now_ms: int) -> None:
        seq, sync = self.tx.allocate()
        data = frame.encode_message(type_id, seq, ints, text, sync)
        self.tx.track(seq, data, now_ms)
        self._write(data)


TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable
