"""The VEL watchdog: a countdown that a refresh re-arms and that expires once."""


class Watchdog:
    """Counts down in microseconds; :meth:`expired` is True once when it runs out."""

    def __init__(self) -> None:
        self.armed = False
        self.left_us = 0

    def arm(self, ms: int) -> None:
        self.armed = True
        self.left_us = ms * 1000

    def disarm(self) -> None:
        self.armed = False

    def expired(self, dt_us: int) -> bool:
        if not self.armed:
            return False
        self.left_us -= dt_us
        if self.left_us > 0:
            return False
        self.armed = False
        return True
