"""The controller's state, shared by its parts (:mod:`~omnibot.firmware.controller` and the ``controller_*`` mixins).

:class:`ControllerState` builds what the controller owns (calibration, power model, limits, queue,
executor, sonars and their guard, telemetry, battery monitor, binary link, line splitter) and the
state of the command being answered, and reports the STATUS state and MODE bits from them. Under
``TYPE_CHECKING`` it names, for mypy only, the methods a part calls in another one.
"""

from omnibot.firmware import battery, parser
from omnibot.firmware.binlink import BinaryLink
from omnibot.firmware.calibration import Calibration
from omnibot.firmware.limits import Limits
from omnibot.firmware.motion import Executor
from omnibot.firmware.power import PowerModel
from omnibot.firmware.queue import CommandQueue
from omnibot.firmware.safety import SonarGuard
from omnibot.firmware.sonar import Sonars
from omnibot.firmware.telemetry import Telemetry
from omnibot.protocol import arq, codes

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any

    from omnibot.firmware.hal import HAL
    from omnibot.protocol.frame import Frame


class ControllerState:
    """What the controller owns and the state of the command being answered."""

    if TYPE_CHECKING:

        def _reply(self, line: str) -> None:
            """Replies._reply (controller_replies.py)."""

        def _ok(self) -> None:
            """Replies._ok (controller_replies.py)."""

        def _error(self, code: int) -> None:
            """Replies._error (controller_replies.py)."""

        def _warn(self, code: int) -> None:
            """Replies._warn (controller_replies.py)."""

        def _idle(self) -> None:
            """Replies._idle (controller_replies.py)."""

        def _status(self) -> None:
            """Replies._status (controller_replies.py)."""

        def _hello_text(self, version: int = codes.PROTOCOL_VERSION) -> str:
            """Replies._hello_text (controller_replies.py)."""

        def execute(self, kw: int, p: "list[int]") -> None:
            """Commands.execute (controller_commands.py)."""

        def _relimit(self) -> None:
            """Controller._relimit (controller.py)."""

        def _check_halt(self) -> None:
            """Controller._check_halt (controller.py)."""

    def _init_state(self, hal: "HAL", config: "dict[str, Any]") -> None:
        """Build the controller's parts from the config; no command being answered."""
        self.hal = hal
        self.config = config
        self.name = str(config["name"])
        self.motors = int(config["motors"])
        self.tracking = int(config["tracking"])
        self.has_gyro = bool(config["gyro"])
        self.calibration = Calibration(config)
        self.model = PowerModel(config, self.calibration)
        self.limits = Limits(config)
        self.queue = CommandQueue(int(config["queue_capacity"]))
        self.executor = Executor(config, hal, self.queue, self.model, self._warn, self._idle)
        self.sonars = Sonars(len(config["sonar_period_min_ms"]))
        self.guard = SonarGuard(config, self.sonars)
        self.executor.guard = self.guard
        self.telemetry = Telemetry()
        self.link = BinaryLink(hal.uart_write)
        self.binary = False
        self.checked_only = False  # MODE bit 4: text commands need a matching "*" check
        self.sequenced = False  # MODE bit 5: the tags of checked text commands are sequence numbers
        self.text_rx = arq.Receiver(codes.TEXT_SEQ_WINDOW, codes.TEXT_SEQ_MAX)  # their duplicates
        self._kept: bytes | None = None  # sequenced text: the reply being sent, kept for a duplicate
        self.latched = False  # the sonar's emergency stop (the battery's: self.battery.latched)
        self.battery = battery.BatteryMonitor(config)
        self._battery_ms = 0
        self.now_ms = 0
        self._us = 0
        self._seq = 0
        self._last = hal.ticks_us()
        self._split = parser.LineSplitter(int(config["line_max"]))
        self._lines: list[bytes | None] = []
        self._ends: list[int] = []
        self._frames: list[Frame] = []
        self._params: list[int] = []
        self._tag: bytes | None = None  # text: the tag of the command being answered
        self._check = False  # text: it carried a "*" check, so its reply does

    @property
    def state(self) -> int:
        """The STATE code reported by STATUS: emergency stop latched, moving or idle."""
        if self.battery.latched:
            return codes.STATE_BATTERY
        if self.latched:
            return codes.STATE_ESTOP
        return codes.STATE_MOVING if self.executor.moving else codes.STATE_IDLE

    @property
    def mode(self) -> int:
        """The MODE bits in force."""
        ex = self.executor
        return (
            ex.mode
            | (codes.MODE_BINARY if self.binary else 0)
            | (codes.MODE_REFUSE_UNCOVERED if self.guard.refuse else 0)
            | (codes.MODE_CHECKED_TEXT if self.checked_only else 0)
            | (codes.MODE_SEQUENCED_TEXT if self.sequenced else 0)
        )
