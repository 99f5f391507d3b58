"""How ``omnibot send`` and ``omnibot console`` print an event."""

from __future__ import annotations

from omnibot.apps.formats import format_event
from omnibot.client import ErrorEvent, Hello, RangeEvent, ResetEvent, Telemetry, Unexpected, WarnEvent
from omnibot.protocol.messages import Malformed
from omnibot.protocol.messages import Telemetry as TelMessage


def test_format_event() -> None:
    assert format_event(RangeEvent(time=0, sonar=1, distance=0.42)) == "<- RANGE sonar 1: 42 cm"
    assert format_event(RangeEvent(time=0, sonar=2, distance=None)) == "<- RANGE sonar 2: no echo"
    warn = WarnEvent(time=0, code=13, text="emergency stop by sonar")
    assert format_event(warn) == "<- WARN 13 emergency stop by sonar"
    assert "no command waiting" in format_event(ErrorEvent(time=0, code=36, text="internal fault"))
    assert (
        format_event(ResetEvent(time=0, hello=Hello(1, "omni4", 4)))
        == "<- HELLO,1,omni4,4 (controller reset)"
    )
    odd = Unexpected(time=0, message=Malformed(b"\xff", "not ASCII"), reason="not ASCII")
    assert format_event(odd) == "<- ?? not ASCII: b'\\xff'"
    tel = Telemetry.from_message(TelMessage(1504, (0, 220), (0, 912), (), 50, 100, 7190, (0, 1), (42,)), 0.0)
    assert format_event(tel) == (
        "<- TEL 1.504 s pwr 0,220 enc 0,912 gyro 0.5 deg/s hdg 1.0 deg bat 7.19 V moving q1 sonar 42cm"
    )
