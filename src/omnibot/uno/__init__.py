"""The Arduino UNO controller: building ``firmware-avr/`` and running it in simavr (``firmware-avr/unosim``)."""

__all__: list[str] = []
