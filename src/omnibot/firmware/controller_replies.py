"""The controller's replies and events: text lines ending in CR LF, or binary frames after MODE bit 2.

A text reply echoes the command's ``#tag`` and carries a ``*`` check when the command did
(``protocol/linecheck.py``); with MODE bit 5 the reply is kept for a duplicate of its command.
"""

from omnibot.firmware.controller_state import ControllerState
from omnibot.protocol import codes, linecheck


class Replies(ControllerState):
    """The controller's output: OK, ERROR, STATUS, HELLO replies and WARN, IDLE, RANGE events."""

    def emit(self, line: str) -> None:
        """Send one text line (CR LF added)."""
        self.hal.uart_write((line + "\r\n").encode())

    def _reply(self, line: str) -> None:
        """Send a text reply, with the command's tag and a check if it had them."""
        if self._tag is None and not self._check:
            self.emit(line)
            return
        data = line.encode()
        data += linecheck.suffix(data, self._tag, self._check) + b"\r\n"
        if self._kept is not None:
            self._kept = data
        self.hal.uart_write(data)

    def _ok(self) -> None:
        if self.binary:
            self.link.reply(codes.OK, self._seq, [])
        else:
            self._reply("OK")

    def _error(self, code: int) -> None:
        if self.binary:
            self.link.reply(codes.ERROR, self._seq, [code])
        else:
            self._reply(f"ERROR,{code},{codes.TEXTS[code]}")

    def _warn(self, code: int) -> None:
        if self.binary:
            self.link.event(codes.WARN, [code], self.now_ms)
        else:
            self.emit(f"WARN,{code},{codes.TEXTS[code]}")

    def _idle(self) -> None:
        if self.binary:
            self.link.event(codes.IDLE, [], self.now_ms)
        else:
            self.emit("IDLE")

    def _range(self, sonar: int, cm: int) -> None:
        if self.binary:
            self.link.event(codes.RANGE, [sonar, cm], self.now_ms)
        else:
            self.emit(f"RANGE,{sonar},{cm}")

    def _hello_text(self, version: int = codes.PROTOCOL_VERSION) -> str:
        return f"HELLO,{version},{self.name},{self.motors}"

    def _status(self) -> None:
        ex = self.executor
        m = ex.remembered
        state = self.state
        queued = len(self.queue)
        cap = self.queue.capacity
        mode = self.mode
        if self.binary:
            ints = [state, queued, cap, mode]
            ints.extend(ex.powers)
            ints.extend(m)
            self.link.reply(codes.STATUS_REPLY, self._seq, ints)
            return
        powers = ",".join([str(v) for v in ex.powers])
        self._reply(f"STATUS,{state},{queued},{cap},{mode};POWER,{powers};MOVE,{m[0]},{m[1]},{m[2]},{m[3]}")
