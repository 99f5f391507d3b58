"""``omnibot``'s subcommands declared by name and summary alone, each filled in (its options declared,
the module that declares them imported) only when it is chosen (:class:`Commands`), so that no
command imports another's modules (``tests/cli/test_startup.py`` checks ``--help``).

:func:`command_in` declares a command whose options (``add_arguments``) and handler (``run``) live in
one module; :func:`lazy` one whose adder does more (``log``'s and ``calibrate``'s subcommands).
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Callable, Sequence
from typing import TypeAlias

from omnibot.cliargs import add_debug_option

Adder: TypeAlias = "Callable[[argparse._SubParsersAction[argparse.ArgumentParser]], None]"


def command_in(
    module: str, name: str, *, add: str = "add_arguments", run: str = "run", summary: str, description: str
) -> Adder:
    """The adder of the subcommand ``name`` (``summary``: its line in ``omnibot --help``) whose options
    (``module.add(p)``) and handler (``module.run(args)``) live in ``module``: imported only when the
    command is chosen (:class:`Commands`) and when it runs, so the heavy imports stay in the handler."""

    def handler(args: argparse.Namespace) -> int:
        status: int = getattr(importlib.import_module(module), run)(args)
        return status

    def adder(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
        p = sub.add_parser(name, help=summary, description=description)
        getattr(importlib.import_module(module), add)(p)
        p.set_defaults(handler=handler)

    return lazy(name, summary, adder)


def lazy(name: str, summary: str, adder: Adder) -> Adder:
    """``adder`` declared to :class:`Commands` by its name and summary alone: it runs (importing the
    module that declares the command's options) only when the command is chosen."""

    def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
        if isinstance(sub, Commands):
            sub.add_lazy(name, summary, adder)
        else:
            adder(sub)

    return register


class Commands(argparse._SubParsersAction):  # type: ignore[type-arg]
    """``omnibot``'s subcommands. A command added with :meth:`add_lazy` is a placeholder carrying its
    name and summary (all ``omnibot --help`` shows) until it is chosen: only then is its adder run, and
    the module that declares its options imported. So ``omnibot --help`` and ``omnibot robot list``
    import none of what the other commands need (numpy, numba, pydantic, the client, ...)."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self._adders: dict[str, Adder] = {}

    def add_lazy(self, name: str, summary: str, adder: Adder) -> None:
        """Declare command ``name`` by its ``summary``; ``adder`` runs when it is chosen."""
        self.add_parser(name, help=summary)
        self._adders[name] = adder

    def fill(self, name: str) -> None:
        """Run the adder of command ``name`` if it is still a placeholder (its line in the help keeps
        its place)."""
        adder = self._adders.pop(name, None)
        if adder is None:
            return
        del self._name_parser_map[name]
        place = next(k for k, a in enumerate(self._choices_actions) if a.dest == name)
        placeholder = self._choices_actions.pop(place)
        adder(self)
        filled = self._choices_actions.pop()
        if filled.help != placeholder.help:
            raise AssertionError(f"omnibot {name}: summary {placeholder.help!r} != {filled.help!r}")
        self._choices_actions.insert(place, filled)
        add_debug_to(self._name_parser_map[name])

    def fill_all(self) -> None:
        """Run every adder still waiting (the full parser: ``build_parser(full=True)``)."""
        for name in list(self._adders):
            self.fill(name)

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: str | Sequence[object] | None,
        option_string: str | None = None,
    ) -> None:
        """The command chosen (the first value) is filled in, then parsed as argparse does."""
        if isinstance(values, Sequence) and values and isinstance(values[0], str):
            self.fill(values[0])
        super().__call__(parser, namespace, values, option_string)


def add_debug_to(p: argparse.ArgumentParser) -> None:
    """``--debug`` on a (sub)command and its own subcommands, so that it can go anywhere on the line."""
    if "--debug" not in p._option_string_actions:
        add_debug_option(p)
    for action in p._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                add_debug_to(child)
