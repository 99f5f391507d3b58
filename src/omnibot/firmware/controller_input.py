"""The controller's input: the UART's bytes as text lines or binary frames, one command at a time.

Text: the line splitter's commands, each parsed after its ``#tag*check`` suffix is split off
(``protocol/linecheck.py``); with MODE bit 4 only checked lines run, with MODE bit 5 checked tags are
taken in sequence (``protocol/arq.py``'s Receiver: a duplicate answered from its kept reply). Binary
(MODE bit 2): COBS frames, acknowledged and sequenced by the link. A MODE that switches between the
two hands the rest of the bytes to the other.
"""

from omnibot.firmware import parser
from omnibot.firmware.controller_state import ControllerState
from omnibot.protocol import arq, codes, linecheck

TYPE_CHECKING = False
if TYPE_CHECKING:
    from omnibot.protocol.frame import Frame

SYNC = (codes.STOP, codes.HELLO, codes.MODE)  # sequenced text: taken whatever tag was expected


class Input(ControllerState):
    """The controller's reading of commands from text lines and binary frames."""

    def _text_input(self, data: bytes) -> None:
        lines = self._lines
        ends = self._ends
        self._split.feed(data, lines, ends)
        for k in range(len(lines)):
            self.handle(lines[k])
            if self.binary:  # MODE switched to binary: the rest of the bytes are frames
                rest = data[ends[k] :]
                del lines[:]
                del ends[:]
                self._split.reset()
                if rest:
                    self._binary_input(rest)
                return
        del lines[:]
        del ends[:]

    def _binary_input(self, data: bytes) -> None:
        frames = self._frames
        i = 0
        n = len(data)
        while i < n:
            end = data.find(b"\x00", i)
            stop = n if end < 0 else end + 1
            self.link.decoder.feed(data[i:stop], frames)
            i = stop
            for fr in frames:
                self._frame(fr)
            del frames[:]
            if not self.binary:  # a binary MODE cleared bit 2: the rest is text
                if i < n:
                    self._text_input(data[i:])
                return

    def _frame(self, fr: "Frame") -> None:
        t = fr.type_id
        if t < 0:
            return  # bad CRC, COBS or length: dropped, the host retries
        link = self.link
        if t == codes.ACK:
            link.tx.ack(fr.seq)
            return
        if t == codes.HELLO and fr.sync:
            link.rx.reset()
        kind = link.rx.classify(fr.seq, fr.sync)
        if kind == arq.DUPLICATE:
            reply = link.rx.reply_for(fr.seq)
            if reply is not None:
                self.hal.uart_write(reply)
            return
        if kind == arq.OUT_OF_ORDER:
            return
        self._seq = fr.seq
        if t not in codes.PARAM_COUNTS:
            self._error(codes.E_UNKNOWN)
            return
        try:
            ints, _ = fr.fields()
        except ValueError:
            self._error(codes.E_NOT_INTEGER)
            return
        if len(ints) > codes.params_max(t):
            self._error(codes.E_PARAM_COUNT)
            return
        for v in ints:
            if v < codes.INT_MIN or v > codes.INT_MAX:
                self._error(codes.E_RANGE16)
                return
        self.execute(t, ints)

    def handle(self, cmd: "bytes | None") -> None:
        """Handle one text command (None: it was too long); exactly one reply, which echoes the
        command's ``#tag`` and carries a ``*`` check if the command did (a bad check: ERROR 26,
        untagged, nothing run)."""
        self._tag = None
        self._check = False
        if cmd is None:
            self._error(codes.E_TOO_LONG)
            return
        end, tag_start, tag_end, checked = linecheck.split(cmd)
        if checked == linecheck.BAD_CHECK:
            self._error(codes.E_CHECKSUM)
            return
        p = self._params
        kw = parser.parse(cmd[:end] if end < len(cmd) else cmd, p)
        if kw == 0:
            return
        if self.checked_only and checked != linecheck.CHECKED:
            # MODE bit 4: only what the check covers runs; a line cut short by a damaged byte (a
            # digit turned into ";" or CR) or a suffix damaged out of recognition has none
            self._error(codes.E_CHECK_REQUIRED)
            return
        seq = 0
        if tag_start >= 0:
            self._tag = cmd[tag_start:tag_end]
            if checked == linecheck.CHECKED:
                for i in range(tag_start, tag_end):
                    seq = seq * 10 + cmd[i] - 48
        self._check = checked == linecheck.CHECKED
        sequenced = self.sequenced and self._check and self._tag is not None
        if sequenced and not self._in_sequence(kw, seq):
            self._tag = None
            self._check = False
            return
        self._kept = b"" if sequenced or (self._check and kw == codes.MODE) else None
        if kw < 0:
            self._error(-kw)
        else:
            self.execute(kw, p)
        if self._kept is not None and self._check and self._tag is not None:
            if not sequenced and self.sequenced:  # the MODE that set bit 5 starts the sequence
                self.text_rx.reset()
                self.text_rx.classify(seq, True)
            if self.sequenced:
                self.text_rx.remember(seq, self._kept)
        self._kept = None
        self._tag = None
        self._check = False

    def _in_sequence(self, kw: int, seq: int) -> bool:
        """Sequenced text (MODE bit 5): whether the checked command tagged ``seq`` is new and runs.
        A duplicate (one of the last TEXT_SEQ_WINDOW tags) gets its kept reply again and does not
        run; one out of order (after a lost line) is dropped unanswered: the host's retransmission
        restores the order (arq.Receiver, as binary frames). STOP, HELLO and MODE are new whatever
        tag was expected, and HELLO starts the sequence afresh (a new session)."""
        rx = self.text_rx
        if kw == codes.HELLO:
            rx.reset()
        kind = rx.classify(seq, kw in SYNC)
        if kind == arq.NEW:
            return True
        if kind == arq.DUPLICATE:
            reply = rx.reply_for(seq)
            if reply is not None:
                self.hal.uart_write(reply)
        return False
