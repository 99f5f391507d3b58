"""The Arduino UNO controller: building ``firmware-avr/`` and running it in simavr (``firmware-avr/unosim``).

Its names, each loaded on first use with only the module that defines it::

    from omnibot.uno import UnoEmulator, UnoError, missing_tools   # the firmware in simavr
    from omnibot.uno import UnoLink, counts_at_rest                # the simulator wired to its pins
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.uno.emulator import UnoEmulator, UnoError, missing_tools
    from omnibot.uno.hil import UnoLink, counts_at_rest

_EXPORTS = {
    "emulator": ("UnoEmulator", "UnoError", "missing_tools"),
    "hil": ("UnoLink", "counts_at_rest"),
}

__all__ = ["UnoEmulator", "UnoError", "UnoLink", "counts_at_rest", "emulator", "hil", "missing_tools"]

if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
