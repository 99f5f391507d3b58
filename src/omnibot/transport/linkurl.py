"""One layer of a parsed link URL (:class:`LinkUrl`: ``scheme://target?options``) and its options
read as strings, integers, numbers and flags, each with an error naming the option and the URL (the
grammar: :mod:`omnibot.transport.url`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from omnibot.errors import ConfigError


@dataclass(frozen=True)
class LinkUrl:
    """One layer of a parsed link URL: ``scheme://target?options``, options already assigned."""

    scheme: str
    target: str
    options: Mapping[str, str] = field(default_factory=dict)
    source: str = ""
    """The whole URL this layer came from, for error messages."""
    url: str = ""
    """What the link opened for this layer should report as its ``url`` (pass it on as ``url=``):
    the whole URL for the outermost layer, this layer's :attr:`text` for a wrapped base, "" for an
    inner wrapper (which then names itself)."""

    @property
    def text(self) -> str:
        """This layer alone as a URL."""
        query = "&".join(f"{k}={v}" if v else k for k, v in self.options.items())
        return f"{self.scheme}://{self.target}" + (f"?{query}" if query else "")

    def _bad(self, name: str, what: str, value: str) -> ConfigError:
        return ConfigError(f"expected {what}, got {value!r} in URL {self.source!r}", key=name)

    def get_str(self, name: str, default: str) -> str:
        """Option ``name`` as given, or ``default``."""
        return self.options.get(name, default)

    def get_int(self, name: str, default: int, *, minimum: int | None = None) -> int:
        """Option ``name`` as an integer (``default`` when absent); ConfigError if not one or below
        ``minimum``."""
        value = self.options.get(name)
        if value is None:
            return default
        try:
            number = int(value)
        except ValueError:
            raise self._bad(name, "an integer", value) from None
        if minimum is not None and number < minimum:
            raise self._bad(name, f"an integer >= {minimum}", value)
        return number

    def get_float(
        self, name: str, default: float, *, minimum: float = 0.0, maximum: float | None = None
    ) -> float:
        """Option ``name`` as a number in [``minimum``, ``maximum``] (``default`` when absent); ConfigError
        otherwise."""
        value = self.options.get(name)
        if value is None:
            return default
        try:
            number = float(value)
        except ValueError:
            raise self._bad(name, "a number", value) from None
        if not (number >= minimum and (maximum is None or number <= maximum)):
            limits = f"in [{minimum}, {maximum}]" if maximum is not None else f">= {minimum}"
            raise self._bad(name, f"a number {limits}", value)
        return number

    def get_bool(self, name: str, default: bool = False) -> bool:
        """Option ``name`` as a flag: bare or 1/true/yes/on is True, 0/false/no/off False; ConfigError
        otherwise."""
        value = self.options.get(name)
        if value is None:
            return default
        lowered = value.lower()
        if lowered in ("", "1", "true", "yes", "on"):
            return True
        if lowered in ("0", "false", "no", "off"):
            return False
        raise self._bad(name, "a flag (1/0, true/false, or no value)", value)
