"""The VEL watchdog: a countdown that a refresh re-arms and that expires once."""


class Watchdog:
    """Counts down in microseconds; :meth:`expired` is True once when it runs out."""

    def __init__(self) -> None:
        self.armed = False
        self.left_us = 0

    def arm(self, ms: int) -> None:
        """Start counting down ``ms`` milliseconds."""
        self.armed = True
        self.left_us = ms * 1000

    def disarm(self) -> None:
        """Stop counting down."""
        self.armed = False

    def expired(self, dt_us: int) -> bool:
        """Count ``dt_us`` off; True once, when the countdown runs out."""
        if not self.armed:
            return False
        self.left_us -= dt_us
        if self.left_us > 0:
            return False
        self.armed = False
        return True
