"""Start-up: ``omnibot --help`` and ``omnibot robot list`` import none of the heavy modules.

Checked deterministically (the modules a fresh interpreter has loaded), not timed: the times are in
BENCHMARKS.md (``python -m benchmarks.startup``). A command whose options live in a heavy module is
declared by name and summary only until it is chosen (``omnibot.apps.subcommands.Commands``).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import subprocess
import sys

import pytest

from omnibot.cli import build_parser

from .conftest import environment

HEAVY = (
    "numpy",
    "numba",
    "llvmlite",
    "scipy",
    "pydantic",
    "yaml",
    "matplotlib",
    "fastapi",
    "starlette",
    "uvicorn",
    "websockets",
    "pygame",
    "serial",
    "mcap",
    "rosbags",
    "zstandard",
    "foxglove",
    "cyclonedds",
    "tqdm",
    "omnibot.client",
    "omnibot.sim",
    "omnibot.robot",
    "omnibot.runtime",
)
"""Packages ``omnibot --help`` must not import (third-party ones, and our own storeys that pull them)."""

PROBE = """
import contextlib, io, json, sys
from omnibot.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    try:
        status = main(sys.argv[1:])
    except SystemExit as end:
        status = end.code
print(json.dumps({"status": status, "modules": sorted(sys.modules)}))
"""


def loaded_by(*argv: str) -> set[str]:
    """The modules a fresh interpreter has loaded after ``omnibot ARGV`` (run through ``main``)."""
    done = subprocess.run(
        [sys.executable, "-c", PROBE, *argv],
        check=False,
        capture_output=True,
        text=True,
        env=environment(),
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout.splitlines()[-1])
    assert result["status"] == 0
    return set(result["modules"])


def heavy_in(modules: set[str], heavy: tuple[str, ...] = HEAVY) -> list[str]:
    return sorted(h for h in heavy if any(m == h or m.startswith(h + ".") for m in modules))


def test_help_imports_no_heavy_module() -> None:
    assert heavy_in(loaded_by("--help")) == []


def test_robot_list_imports_only_what_descriptions_need() -> None:
    """The presets are pydantic models read from YAML: those two, nothing of the simulator or client."""
    allowed = ("pydantic", "yaml", "omnibot.robot")
    assert heavy_in(loaded_by("robot", "list"), tuple(h for h in HEAVY if h not in allowed)) == []


def help_of(parser_args: list[str], *, full: bool) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
        build_parser(full=full).parse_args(parser_args)
    return out.getvalue()


@pytest.mark.parametrize("argv", [["--help"], ["follow", "--help"], ["log", "replay", "--help"]])
def test_lazy_commands_help_as_declared_ones(argv: list[str]) -> None:
    """The placeholders' summaries are the commands' own (``fill`` checks it too), and a command chosen
    is declared whole: the same help as a parser with every command declared at once."""
    assert help_of(argv, full=False) == help_of(argv, full=True)


def test_debug_goes_anywhere_on_a_lazy_command() -> None:
    args = build_parser().parse_args(["log", "info", "x.mcap", "--debug"])
    assert args.debug and args.command == "log"
    args = build_parser().parse_args(["--debug", "follow", "p.csv"])
    assert args.debug and args.command == "follow"


def test_every_command_declares_debug() -> None:
    parser = build_parser(full=True)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, p in sub.choices.items():
        assert "--debug" in p._option_string_actions, name
