"""Errors of the host client, all inside omnibot's one hierarchy (:mod:`omnibot.errors`).

::

    ControllerError (omnibot.errors)   the controller answered ERROR,<code>,<text>; .code, .text
     +-- QueueFull                     21: the command queue is full
     +-- CommandRejected               22, 23, 24, 25, 34: the command's form (length, keyword,
     |                                 parameter count, integers, 16-bit range)
     +-- OutOfRange                    27..33, 35, 37: a parameter outside the protocol/robot limits
     +-- InternalFault                 36
     +-- CalibrationRejected           38: CAL table, index, knot order or value
     +-- NotSupported                  39: a MODE bit, TELEM mask bit or protocol version
     +-- EmergencyStopLatched          40: motion blocked until STOP
    LinkError (omnibot.errors)
     +-- LinkTimeout                   no reply in time (on the link's clock)
     +-- ControllerReset               the controller restarted (unsolicited HELLO): the commands
                                       still waiting for a reply were lost

:func:`controller_error` picks the subclass for a code; unknown codes give a plain ControllerError.
"""

from __future__ import annotations

from omnibot.errors import ControllerError, LinkError
from omnibot.protocol import codes


class QueueFull(ControllerError):
    """ERROR 21: the command queue is full; wait for IDLE or for the queue to drain."""


class CommandRejected(ControllerError):
    """ERROR 22, 23, 24, 25 or 34: the controller could not parse the command."""


class OutOfRange(ControllerError):
    """ERROR 27..33, 35 or 37: a parameter is outside the protocol's or the robot's limits."""


class InternalFault(ControllerError):
    """ERROR 36: the controller reported an internal fault."""


class CalibrationRejected(ControllerError):
    """ERROR 38: a CAL command's table, index, knot order or value is wrong."""


class NotSupported(ControllerError):
    """ERROR 39: a MODE bit, TELEM mask bit or protocol version the controller does not have."""


class EmergencyStopLatched(ControllerError):
    """ERROR 40: the sonar emergency stop is latched; send STOP to release it."""


class BatteryStopLatched(ControllerError):
    """ERROR 44: the battery stop is latched (the pack fell below its stop threshold); STOP releases it
    only once the voltage is back above the stop threshold plus its hysteresis (a charged pack)."""


class ControllerReset(LinkError):
    """The controller restarted (it sent HELLO unasked); commands awaiting a reply were lost."""


_BY_CODE: dict[int, type[ControllerError]] = {
    codes.E_QUEUE_FULL: QueueFull,
    codes.E_INTERNAL: InternalFault,
    codes.E_CALIBRATION: CalibrationRejected,
    codes.E_UNSUPPORTED: NotSupported,
    codes.E_ESTOP: EmergencyStopLatched,
    codes.E_BATTERY: BatteryStopLatched,
}
for _code in (codes.E_TOO_LONG, codes.E_UNKNOWN, codes.E_PARAM_COUNT, codes.E_NOT_INTEGER, codes.E_RANGE16):
    _BY_CODE[_code] = CommandRejected
for _code in (*range(codes.E_TIME, codes.E_SONAR_PERIOD + 1), codes.E_REPEAT, codes.E_SONAR):
    _BY_CODE[_code] = OutOfRange


def controller_error(code: int, text: str = "", command: str | None = None) -> ControllerError:
    """The ControllerError subclass for ``code``; ``command`` (its text) is added as a note."""
    exc = _BY_CODE.get(code, ControllerError)(code, text or codes.TEXTS.get(code, ""))
    if command:
        exc.add_note(f"command: {command}")
    return exc
